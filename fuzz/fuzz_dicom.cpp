// libFuzzer harness: io::read_dicom_series on one file given explicitly (GDCM parses the header
// and decodes the pixel data; pliant checks the geometry and rescales). Findings inside GDCM are
// GDCM's: report them upstream and guard the input in io/dicom.cpp when pliant can.
//
// Known: Debian's GDCM 3.0.21 is built with assertions, and a few flipped bytes in a data set
// (after a valid file meta group) end in `gdcm::FileMetaInformation::ReadCompat: Assertion
// is.good() failed` (SIGABRT inside gdcm::Scanner::Scan) within seconds. Not in scripts/fuzz's
// default list for that reason: run it by name (scripts/fuzz 60 dicom) to look past it.
#include <filesystem>
#include <vector>

#include "fuzz_input.hpp"
#include "pliant/io/dicom.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.dcm", {reinterpret_cast<const char*>(data), size});
    const std::vector<std::filesystem::path> files{path};
    pliant::fuzz::expect_result_or_error([&] {
        pliant::io::read_dicom_series(files,
                                      {.series_uid = "", .max_bytes = pliant::fuzz::MAX_BYTES});
    });
    return 0;
}
