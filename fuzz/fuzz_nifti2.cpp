// libFuzzer harness: io::read_nifti on NIfTI-2 files (540-byte headers, 64-bit dims, double
// placement); its seeds are NIfTI-2, fuzz_nifti's NIfTI-1.
#include "fuzz_input.hpp"
#include "pliant/io/nifti.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.nii", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_nifti(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
