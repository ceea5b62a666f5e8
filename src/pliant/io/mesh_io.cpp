#include "pliant/io/mesh_io.hpp"

#include <fmt/format.h>

#include <cctype>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/io/obj.hpp"
#include "pliant/io/ply.hpp"

namespace pliant::io {

namespace {

enum class MeshFormat { obj, ply };

MeshFormat format_from_extension(const std::filesystem::path& path) {
    std::string extension = path.extension().string();
    for (char& c : extension) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    if (extension == ".obj") {
        return MeshFormat::obj;
    }
    if (extension == ".ply") {
        return MeshFormat::ply;
    }
    throw IoError(
        fmt::format("{}: unsupported mesh file extension '{}', expected one of .obj, .ply",
                    path.string(), path.extension().string()));
}

template <typename Real>
void write_mesh_impl(const std::filesystem::path& path,
                     const geometry::BasicTriangleMesh<Real>& mesh) {
    switch (format_from_extension(path)) {
        case MeshFormat::obj:
            write_obj(path, mesh);
            return;
        case MeshFormat::ply:
            write_ply(path, mesh, PlyFormat::binary_little_endian);
            return;
    }
}

}  // namespace

geometry::TriangleMeshD read_mesh(const std::filesystem::path& path) {
    geometry::TriangleMeshD mesh;
    switch (format_from_extension(path)) {
        case MeshFormat::obj:
            mesh = read_obj(path);
            break;
        case MeshFormat::ply:
            mesh = read_ply(path);
            break;
    }
    if (mesh.triangles.empty()) {
        throw InvalidInput(fmt::format(
            "{}: expected a mesh with at least one triangle, got {} vertices and no triangles",
            path.string(), mesh.positions.size()));
    }
    return mesh;
}

void write_mesh(const std::filesystem::path& path, const geometry::TriangleMesh& mesh) {
    write_mesh_impl(path, mesh);
}

void write_mesh(const std::filesystem::path& path, const geometry::TriangleMeshD& mesh) {
    write_mesh_impl(path, mesh);
}

}  // namespace pliant::io
