// libFuzzer harness: io::read_metaimage on a single-file .mha (header + LOCAL data).
#include "fuzz_input.hpp"
#include "pliant/io/metaimage.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.mha", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_metaimage(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
