// libFuzzer harness: io::read_tetgen; the input is the .node text, a NUL byte, the .ele text.
#include "fuzz_input.hpp"
#include "pliant/io/tetgen.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto [node, ele] =
        pliant::fuzz::split_at_nul({reinterpret_cast<const char*>(data), size});
    pliant::fuzz::write_input("in.node", node);
    pliant::fuzz::write_input("in.ele", ele);
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_tetgen(pliant::fuzz::scratch() / "in"); });
    return 0;
}
