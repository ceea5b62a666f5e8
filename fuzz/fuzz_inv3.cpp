// libFuzzer harness: io::read_inv3 (gzip tar with main.plist and matrix.dat).
#include "fuzz_input.hpp"
#include "pliant/io/inv3.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.inv3", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_inv3(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
