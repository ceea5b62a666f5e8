// libFuzzer harness: io::read_ccd_queries (Sample-Queries CSV).
#include "fuzz_input.hpp"
#include "pliant/io/ccd_queries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("queries.csv", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_ccd_queries(path, pliant::io::CcdQueryKind::vertex_face); });
    return 0;
}
