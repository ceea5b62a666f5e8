// libFuzzer harness: io::read_nifti on an uncompressed single-file .nii.
#include "fuzz_input.hpp"
#include "pliant/io/nifti.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.nii", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_nifti(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
