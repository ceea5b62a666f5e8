// libFuzzer harness: io::read_ply (ASCII and binary) and io::read_ply_polygons (polygons, UVs,
// properties) on the same input, then the garment's triangulation for the solver.
#include "fuzz_input.hpp"
#include "pliant/io/ply.hpp"
#include "pliant/io/ply_polygons.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.ply", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] { pliant::io::read_ply(path); });
    pliant::fuzz::expect_result_or_error([&] {
        const pliant::io::PolygonMesh mesh = pliant::io::read_ply_polygons(path);
        pliant::io::triangulate(mesh);
    });
    return 0;
}
