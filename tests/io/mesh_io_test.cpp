#include "pliant/io/mesh_io.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/obj.hpp"
#include "pliant/io/ply.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using geometry::TriangleMesh;
using geometry::TriangleMeshD;
using test::expect_io_error;
using test::TempDir;

TEST(MeshIo, DispatchesOnExtensionCaseInsensitively) {
    TempDir dir;
    const TriangleMesh mesh = test::tricky_mesh<float>();
    for (const char* name : {"a.obj", "b.OBJ", "c.Obj"}) {
        SCOPED_TRACE(name);
        write_mesh(dir / name, mesh);
        test::expect_rounds_to(mesh, read_mesh(dir / name));
    }
    for (const char* name : {"d.ply", "e.PLY", "f.pLy"}) {
        SCOPED_TRACE(name);
        write_mesh(dir / name, mesh);
        test::expect_bitwise_equal(mesh, read_mesh(dir / name));
    }
    const TriangleMeshD mesh_d = test::tricky_mesh<double>();
    for (const char* name : {"g.obj", "h.ply"}) {
        SCOPED_TRACE(name);
        write_mesh(dir / name, mesh_d);
        test::expect_bitwise_equal(mesh_d, read_mesh(dir / name));
    }
}

TEST(MeshIo, WritesTheFormatOfTheExtension) {
    TempDir dir;
    const TriangleMesh mesh = test::tricky_mesh<float>();
    write_mesh(dir / "m.PLY", mesh);
    EXPECT_EQ(test::read_bytes(dir / "m.PLY").rfind("ply\nformat binary_little_endian 1.0\n", 0),
              0u);
    write_mesh(dir / "m.obj", mesh);
    EXPECT_EQ(test::read_bytes(dir / "m.obj").rfind("# written by pliant", 0), 0u);
    // The readers agree with the dispatcher.
    test::expect_bitwise_equal(mesh, read_ply(dir / "m.PLY"));
    test::expect_rounds_to(mesh, read_obj(dir / "m.obj"));
}

TEST(MeshIo, AMeshWithoutTrianglesIsRefused) {
    TempDir dir;
    const auto vertices_only = dir.path() / "points.obj";
    test::write_bytes(vertices_only, "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    try {
        read_mesh(vertices_only);
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("points.obj: expected a mesh with at least one "
                                             "triangle, got 3 vertices and no triangles"),
                  std::string::npos)
            << e.what();
    }
    // read_obj itself reads what is there.
    EXPECT_EQ(read_obj(vertices_only).positions.size(), 3u);
}

TEST(MeshIo, BinaryBytesUnderAnObjNameAreRefused) {
    TempDir dir;
    const auto binary = dir.path() / "binary.obj";
    test::write_bytes(binary, std::string_view("v 0 0 0\nv 1\0\x01 0 0\n", 18));
    expect_io_error([&] { read_mesh(binary); },
                    {"binary.obj", "line 2", "not a text OBJ file", "byte 0x00"});
}

TEST(MeshIo, UnknownExtension) {
    TempDir dir;
    for (const char* name : {"mesh.stl", "mesh", "mesh.ply.gz", "mesh.objx"}) {
        SCOPED_TRACE(name);
        const auto path = dir / name;
        test::write_bytes(path, "ply\n");
        expect_io_error([&] { read_mesh(path); }, {path.string(), "unsupported mesh file extension",
                                                   "expected one of .obj, .ply"});
    }
    expect_io_error([&] { read_mesh(dir / "x.stl"); }, {"'.stl'"});

    const auto target = dir / "out.stl";
    expect_io_error([&] { write_mesh(target, test::tricky_mesh<float>()); },
                    {target.string(), "'.stl'", "expected one of .obj, .ply"});
    EXPECT_FALSE(std::filesystem::exists(target));
}

TEST(MeshIo, ContentMustMatchTheExtension) {
    TempDir dir;
    write_obj(dir / "really_obj.ply", test::tricky_mesh<float>());
    expect_io_error([&] { read_mesh(dir / "really_obj.ply"); },
                    {"really_obj.ply", "not a PLY file"});
    expect_io_error([&] { read_mesh(dir / "missing.obj"); }, {"missing.obj", "cannot open"});
}

}  // namespace
}  // namespace pliant::io
