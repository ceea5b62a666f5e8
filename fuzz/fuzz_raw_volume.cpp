// libFuzzer harness: io::read_raw_volume; the input is the JSON sidecar, a NUL byte, then the
// data file it may name as "data_file": "in.raw".
#include "fuzz_input.hpp"
#include "pliant/io/raw_volume.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto [sidecar, payload] =
        pliant::fuzz::split_at_nul({reinterpret_cast<const char*>(data), size});
    pliant::fuzz::write_input("in.raw", payload);
    const auto path = pliant::fuzz::write_input("in.json", sidecar);
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_raw_volume(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
