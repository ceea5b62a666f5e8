// libFuzzer harness: io::read_obj.
#include "fuzz_input.hpp"
#include "pliant/io/obj.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.obj", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] { pliant::io::read_obj(path); });
    return 0;
}
