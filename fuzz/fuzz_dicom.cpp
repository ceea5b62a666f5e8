// libFuzzer harness: io::read_dicom_series on one file given explicitly (pliant walks the data
// elements; GDCM, in a child process, parses the header and decodes the pixel data; pliant checks
// the geometry and rescales). GDCM's own assertions, crashes and runaway allocations end its
// child process and come back as an IoError (io/forked_call.hpp), so they are not findings; what
// is left to find is in pliant's code, in either process. GDCM gets 3 s per file in each of the
// two children (the scan, the decoding), under scripts/fuzz's 10 s per input, so a GDCM hang is
// an IoError too.
#include <filesystem>
#include <vector>

#include "fuzz_input.hpp"
#include "pliant/io/dicom.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.dcm", {reinterpret_cast<const char*>(data), size});
    const std::vector<std::filesystem::path> files{path};
    pliant::fuzz::expect_result_or_error([&] {
        pliant::io::read_dicom_series(
            files, {.series_uid = "", .max_bytes = pliant::fuzz::MAX_BYTES, .gdcm_seconds = 3.0});
    });
    return 0;
}
