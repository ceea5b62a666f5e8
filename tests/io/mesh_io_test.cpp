#include "pliant/io/mesh_io.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

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
