// libFuzzer harness: io::read_png (stb_image behind pliant's checks).
#include "fuzz_input.hpp"
#include "pliant/io/png.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.png", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] { (void)pliant::io::read_png(path); });
    return 0;
}
