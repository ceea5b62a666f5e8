// libFuzzer harness: io::read_openvdb on a .vdb file (pliant's checks of the header, metadata,
// grid descriptors and root counts, then OpenVDB's own parser).
#include "fuzz_input.hpp"
#include "pliant/io/openvdb.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.vdb", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error(
        [&] { pliant::io::read_openvdb(path, pliant::fuzz::MAX_BYTES); });
    return 0;
}
