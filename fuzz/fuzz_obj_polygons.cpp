// libFuzzer harness: io::read_obj_polygons, then triangulate and write_obj_polygons of what it
// accepted (the round trip must not throw anything but pliant errors).
#include "fuzz_input.hpp"
#include "pliant/io/obj_polygons.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("in.obj", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] {
        const pliant::io::PolygonMesh mesh = pliant::io::read_obj_polygons(path);
        pliant::io::triangulate(mesh);
        pliant::io::write_obj_polygons(pliant::fuzz::scratch() / "out.obj", mesh, mesh.positions);
    });
    return 0;
}
