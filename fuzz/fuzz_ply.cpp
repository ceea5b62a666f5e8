// libFuzzer harness: io::read_ply (ASCII and binary).
#include "fuzz_input.hpp"
#include "pliant/io/ply.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.ply", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] { pliant::io::read_ply(path); });
    return 0;
}
