// libFuzzer harness: io::read_nrrd with an attached header (raw or gzip data).
#include "fuzz_input.hpp"
#include "pliant/io/nrrd.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.nrrd", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_nrrd(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
