// Triangle meshes: geometry::TriangleMeshD (positions in double, as files are read), the OBJ / PLY
// readers and writers of io, and the generated sheets.
#include <fmt/format.h>

#include <filesystem>

#include "common.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/geometry/validate.hpp"
#include "pliant/io/mesh_io.hpp"

namespace pliant::python {

void bind_mesh(py::module_& m) {
    using geometry::TriangleMeshD;

    py::class_<TriangleMeshD>(m, "TriangleMesh", R"doc(
A triangle mesh that owns its data (geometry::TriangleMeshD).

positions: (N, 3) float64 view of the mesh's own memory (writeable; world units).
triangles: (T, 3) int32 view (writeable), counter-clockwise seen from the normal's side.
The views keep the mesh alive; they stay valid as long as they exist.
)doc")
        .def(py::init([](const DoubleArray& positions, const IndexArray& triangles) {
                 const std::span<const Vec3d> p = vec3d_rows(positions, "TriangleMesh: positions");
                 const std::span<const geometry::Triangle> t =
                     index_rows<3>(triangles, "TriangleMesh: triangles");
                 geometry::validate_triangles(t, p.size(), "TriangleMesh: triangles");
                 TriangleMeshD mesh;
                 mesh.positions.assign(p.begin(), p.end());
                 mesh.triangles.assign(t.begin(), t.end());
                 return mesh;
             }),
             py::arg("positions"), py::arg("triangles"),
             "A mesh from (N, 3) positions and (T, 3) vertex indices (copied). InvalidInput for "
             "other shapes, indices out of [0, N) or a triangle that repeats a vertex.")
        .def_property_readonly(
            "positions",
            [](const py::object& self) {
                return vec3_view(std::span<const Vec3d>(self.cast<TriangleMeshD&>().positions),
                                 self, true);
            },
            "(N, 3) float64 view of the vertex positions (no copy, writeable).")
        .def_property_readonly(
            "triangles",
            [](const py::object& self) {
                return index_view<3>(
                    std::span<const geometry::Triangle>(self.cast<TriangleMeshD&>().triangles),
                    self, true);
            },
            "(T, 3) int32 view of the triangles (no copy, writeable).")
        .def_property_readonly("num_vertices", &TriangleMeshD::num_vertices)
        .def_property_readonly("num_triangles", &TriangleMeshD::num_triangles)
        .def(
            "copy", [](const TriangleMeshD& mesh) { return mesh; }, "A deep copy.")
        .def("__repr__", [](const TriangleMeshD& mesh) {
            return fmt::format("pliant.TriangleMesh({} vertices, {} triangles)",
                               mesh.num_vertices(), mesh.num_triangles());
        });

    m.def("read_mesh", &io::read_mesh, py::arg("path"), py::call_guard<py::gil_scoped_release>(),
          "Reads an OBJ or PLY file (by extension) at full precision. IoError for unreadable or "
          "broken files and other extensions.");
    m.def(
        "write_mesh",
        [](const std::filesystem::path& path, const TriangleMeshD& mesh) {
            io::write_mesh(path, mesh);
        },
        py::arg("path"), py::arg("mesh"), py::call_guard<py::gil_scoped_release>(),
        "Writes an OBJ or PLY (binary little-endian) file by extension, replacing it atomically.");

    m.def(
        "grid_sheet",
        [](int nx, int ny, double width, double height) {
            return geometry::convert_precision<double>(geometry::make_grid_sheet(
                nx, ny, static_cast<float>(width), static_cast<float>(height)));
        },
        py::arg("nx"), py::arg("ny"), py::arg("width") = 1.0, py::arg("height") = 1.0,
        "A flat sheet of nx x ny quads (two triangles each, diagonals alternating), centred at "
        "the origin in the z = 0 plane; width along x, height along y (world units). "
        "(nx+1)(ny+1) vertices, 2 nx ny triangles.");
    m.def("uv_sphere", &geometry::make_uv_sphere, py::arg("center"), py::arg("radius"),
          py::arg("segments") = 32,
          "A closed UV sphere, outward oriented: `segments` slices around +z, segments/2 stacks.");
}

}  // namespace pliant::python
