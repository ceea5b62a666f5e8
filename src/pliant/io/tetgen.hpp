// TetGen tetrahedral meshes: a `.node` file (points) and an `.ele` file (tetrahedra), the format
// of TetGen (Si 2015, "TetGen, a Delaunay-based quality tetrahedral mesh generator", file formats
// section of the user manual).
//
//   mesh.node   first line: <#points> <dimension = 3> <#attributes> <#boundary markers 0|1>
//               then per point: <index> <x> <y> <z> [attributes…] [boundary marker]
//   mesh.ele    first line: <#tets> <nodes per tet = 4|10> <#region attributes 0|1>
//               then per tet: <index> <n1> <n2> <n3> <n4> [6 more nodes of a quadratic tet]
//               [region]
//
// `#` starts a comment to the end of the line; blank lines are skipped. Points are numbered from
// the first point's index (0 or 1, as TetGen's -z switch chooses), consecutively; .ele node
// indices use the same base. Quadratic tets keep their 4 corner nodes.
//
// read_tetgen(path): path is `X.node`, `X.ele` or `X`; both `X.node` and `X.ele` are read.
// Tets are returned positively oriented (geometry/tet_mesh.hpp): a tet of negative signed volume
// gets its last two nodes swapped (orientation conventions differ between tools), so a mesh
// and its mirror image read alike.
// Throws IoError "<file>: line <n>: <what>, expected <x>, got <y>" for a missing file, a bad
// header, a count larger than the file can hold or than 32-bit indices allow, a missing or
// malformed number, a NaN/Inf coordinate, a point index out of sequence, a node index outside
// the points, a tet repeating a node, a tet of zero volume (degenerate: no rest volume to keep),
// and extra data after the declared records.
//
// write_tetgen(base, mesh) writes base.node and base.ele (0-based, 9 significant digits, so
// floats read back bit for bit), each replaced atomically (atomic_file.hpp). InvalidInput
// before touching a file when an index is out of range or a position not finite.
#pragma once

#include <filesystem>

#include "pliant/geometry/tet_mesh.hpp"

namespace pliant::io {

geometry::TetMesh read_tetgen(const std::filesystem::path& path);

void write_tetgen(const std::filesystem::path& base, const geometry::TetMesh& mesh);

}  // namespace pliant::io
