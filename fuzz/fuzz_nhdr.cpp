// libFuzzer harness: io::read_nrrd with a detached header; the input is the header, a NUL byte,
// then the data file it may name as `data file: in.raw`.
#include "fuzz_input.hpp"
#include "pliant/io/nrrd.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto [header, payload] =
        pliant::fuzz::split_at_nul({reinterpret_cast<const char*>(data), size});
    pliant::fuzz::write_input("in.raw", payload);
    const auto path = pliant::fuzz::write_input("in.nhdr", header);
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_nrrd(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
