#include "pliant/pipeline/cloth_setup.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <variant>

#include "pliant/cloth/material_preset.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/validate.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/ply_polygons.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/memory_budget.hpp"

namespace pliant::pipeline {
namespace {

constexpr int SPHERE_SEGMENTS = 48;
// A deforming obstacle whose vertices move more than this many thicknesses per substep is warned
// about (warn_fast_deformation).
constexpr double FAST_OBSTACLE_IN_THICKNESS = 2.0;

// Applies a placement (rotation, then translation) to points, the rotation built once.
void place(std::span<Vec3d> points, const cloth::Placement& placement) {
    const cloth::Rotation rotation = cloth::Rotation::from_degrees(placement.rotate_degrees);
    for (Vec3d& p : points) {
        p = rotation.apply(p) + placement.translate;
    }
}

// A mesh file's triangles, or an error naming the scene key when it has none or a coordinate
// beyond pipeline::MAX_SCENE_COORDINATE (a run would end as "diverged" at its first frame).
// With `polygons`, an OBJ or PLY file is read as polygons (kept there) and triangulated.
geometry::TriangleMeshD read_nonempty_mesh(const std::filesystem::path& file,
                                           const std::string& scene_name, const std::string& key,
                                           std::optional<io::PolygonMesh>* polygons = nullptr) {
    geometry::TriangleMeshD mesh;
    std::string extension = file.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    try {
        if (polygons != nullptr && (extension == ".obj" || extension == ".ply")) {
            *polygons =
                extension == ".obj" ? io::read_obj_polygons(file) : io::read_ply_polygons(file);
            mesh = io::triangulate(**polygons);
            if (mesh.triangles.empty()) {  // as io::read_mesh says it
                throw InvalidInput(fmt::format(
                    "{}: expected a mesh with at least one triangle, got {} vertices and no "
                    "triangles",
                    file.string(), mesh.positions.size()));
            }
        } else {
            mesh = io::read_mesh(file);
        }
    } catch (const InvalidInput& e) {  // a file without triangles: say which key named it
        throw InvalidInput(fmt::format("{}: {}: {}", scene_name, key, e.what()));
    }
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec3d& p = mesh.positions[v];
        if (!within_cube(p, pipeline::MAX_SCENE_COORDINATE)) {
            throw InvalidInput(fmt::format(
                "{}: {}: {}: vertex {} at ({}, {}, {}): expected coordinates within {:g} m",
                scene_name, key, file.string(), v, p.x, p.y, p.z, pipeline::MAX_SCENE_COORDINATE));
        }
    }
    return mesh;
}

// How many vertices have the exact position of another vertex (each such group counts all but
// one).
std::int64_t vertices_on_others(std::span<const Vec3d> positions) {
    std::vector<Vec3d> sorted(positions.begin(), positions.end());
    const auto less = [](const Vec3d& a, const Vec3d& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    };
    std::sort(sorted.begin(), sorted.end(), less);
    std::int64_t doubled = 0;
    for (std::size_t k = 1; k < sorted.size(); ++k) {
        doubled += sorted[k] == sorted[k - 1] ? 1 : 0;
    }
    return doubled;
}

// Warns when the cloth's size (the diagonal of its box) is implausible for a garment or sheet,
// or its mean edge length is far from the thickness (units or scale wrong, or a thickness that
// either swallows the triangles or lets them pass through each other between substeps).
// Warns about seams that will leave the cloth stretched: its rest shape is the shape it is given
// in, so two panels placed a gap apart are that gap too short once sewn, and the seam (held with
// compliance 0) puts about half the gap into the edges beside each of its vertices. Names the
// worst pair when that strain exceeds MAX_SEAM_STRAIN.
constexpr double MAX_SEAM_STRAIN = 0.05;

void warn_seam_stretch(const cloth::ClothScene& scene, const std::string& scene_name,
                       const geometry::TriangleMeshD& mesh) {
    if (scene.seams.empty()) {
        return;
    }
    // Mean length of the edges at each vertex (each triangle's two edges at it).
    std::vector<double> sum(mesh.positions.size(), 0.0);
    std::vector<int> count(mesh.positions.size(), 0);
    for (const geometry::Triangle& t : mesh.triangles) {
        for (std::size_t k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(t[k]);
            const auto b = static_cast<std::size_t>(t[(k + 1) % 3]);
            const double length = norm(mesh.positions[a] - mesh.positions[b]);
            sum[a] += length;
            sum[b] += length;
            ++count[a];
            ++count[b];
        }
    }
    const auto mean_edge = [&](std::size_t v) {
        return count[v] > 0 ? sum[v] / count[v] : 0.0;
    };
    for (const cloth::SceneSeam& seam : scene.seams) {
        double worst = 0.0;
        std::size_t worst_pair = 0;
        double worst_gap = 0.0;
        for (std::size_t k = 0; k < std::min(seam.a.size(), seam.b.size()); ++k) {
            const auto a = static_cast<std::size_t>(seam.a[k]);
            const auto b = static_cast<std::size_t>(seam.b[k]);
            const double gap =
                norm(mesh.positions[a] - mesh.positions[b]) - scene.material.thickness;
            const double edge = std::min(mean_edge(a), mean_edge(b));
            const double strain = edge > 0.0 ? 0.5 * gap / edge : 0.0;
            if (strain > worst) {
                worst = strain;
                worst_pair = k;
                worst_gap = gap;
            }
        }
        if (worst > MAX_SEAM_STRAIN) {
            const double edge = std::min(mean_edge(static_cast<std::size_t>(seam.a[worst_pair])),
                                         mean_edge(static_cast<std::size_t>(seam.b[worst_pair])));
            log_warning(
                "{}: {}: pair {} (vertices {} and {}) is {:.3g} m farther apart than the "
                "thickness it is sewn to; the cloth's rest shape is as placed, so sewing stretches "
                "the edges beside it by about {:.0f} % (expected at most {:.0f} %): place the "
                "panels at most {:.2g} m apart at their seams",
                scene_name, seam.key, worst_pair, seam.a[worst_pair], seam.b[worst_pair], worst_gap,
                100.0 * worst, 100.0 * MAX_SEAM_STRAIN,
                scene.material.thickness + 2.0 * MAX_SEAM_STRAIN * edge);
        }
    }
}

void warn_implausible_size(const cloth::ClothScene& scene, const std::string& scene_name,
                           const geometry::TriangleMeshD& mesh) {
    AABBd box;
    for (const Vec3d& p : mesh.positions) {
        box.extend(p);
    }
    const double size = norm(box.hi - box.lo);
    const std::string what =
        scene.grid ? std::string("cloth.grid") : fmt::format("cloth.mesh {}", scene.mesh.string());
    const std::string hint = scene.grid ? "check cloth.grid.size"
                                        : fmt::format(
                                              "check the file's units (cloth.units or "
                                              "cloth.scale; read as {:g} m per unit)",
                                              scene.mesh_scale);
    if (size > MAX_PLAUSIBLE_CLOTH_SIZE || size < MIN_PLAUSIBLE_CLOTH_SIZE) {
        log_warning(
            "{}: {} is {:.4g} m across, implausible for cloth (expected {:g} m to {:g} m): "
            "{}",
            scene_name, what, size, MIN_PLAUSIBLE_CLOTH_SIZE, MAX_PLAUSIBLE_CLOTH_SIZE, hint);
    }
    double sum = 0.0;
    for (const geometry::Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
            sum += norm(
                mesh.positions[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])] -
                mesh.positions[static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)])]);
        }
    }
    const double edge = mesh.triangles.empty() ? 0.0 : sum / (3.0 * mesh.triangles.size());
    const double thickness = scene.material.thickness;
    if (edge > 0.0 && thickness > 0.0 &&
        (thickness > edge * MAX_THICKNESS_PER_EDGE || thickness < edge * MIN_THICKNESS_PER_EDGE)) {
        log_warning(
            "{}: {}: the thickness {:g} m is {:.3g} times the mean edge length {:.4g} m (expected "
            "{:g} to {:g}): {}; {}",
            scene_name, what, thickness, thickness / edge, edge, MIN_THICKNESS_PER_EDGE,
            MAX_THICKNESS_PER_EDGE,
            thickness > edge * MAX_THICKNESS_PER_EDGE
                ? "every vertex is in contact with its neighbours' triangles and self-collision "
                  "holds the cloth stiff"
                : "cloth moving more than the thickness per substep depends on the CCD fail-safe "
                  "alone",
            scene.grid
                ? std::string("check material.thickness and cloth.grid")
                : "check material.thickness and " + hint.substr(std::string("check ").size()));
    }
}

// The cloth as simulated: the grid or mesh, transformed, then copied once per instance.
geometry::TriangleMeshD load_cloth(const cloth::ClothScene& scene, const std::string& scene_name,
                                   std::uint64_t max_memory_bytes,
                                   std::optional<io::PolygonMesh>& garment) {
    geometry::TriangleMeshD mesh;
    const std::uint64_t copies_of_the_cloth = std::max<std::size_t>(scene.instances.size(), 1);
    const std::string instances =
        scene.instances.empty() ? "" : fmt::format(" in {} instances", scene.instances.size());
    if (scene.grid) {
        // Checked before the grid is generated (the reader allows up to 50 million quads).
        require_cloth_fits_in_memory(
            fmt::format("{}: cloth.grid of {} x {} quads{}", scene_name, scene.grid->quads[0],
                        scene.grid->quads[1], instances),
            2 * static_cast<std::uint64_t>(scene.grid->quads[0]) *
                static_cast<std::uint64_t>(scene.grid->quads[1]) * copies_of_the_cloth,
            scene.self_collision, max_memory_bytes);
        mesh = geometry::convert_precision<double>(geometry::make_grid_sheet(
            scene.grid->quads[0], scene.grid->quads[1], static_cast<float>(scene.grid->size[0]),
            static_cast<float>(scene.grid->size[1])));
    } else {
        mesh = read_nonempty_mesh(scene.mesh, scene_name, "cloth.mesh", &garment);
        for (Vec3d& p : mesh.positions) {
            p = p * scene.mesh_scale;
        }
        require_cloth_fits_in_memory(
            fmt::format("{}: cloth.mesh {}{}", scene_name, scene.mesh.string(), instances),
            mesh.triangles.size() * copies_of_the_cloth, scene.self_collision, max_memory_bytes);
        // Edges of more than two triangles: the cloth is not a surface there (bending and the
        // self-collision's feature ownership assume at most two).
        geometry::validate_triangles(mesh.triangles, mesh.positions.size(), "cloth mesh");
        const geometry::MeshTopology topology =
            geometry::build_topology(mesh.triangles, mesh.positions.size());
        std::int64_t non_manifold = 0;
        for (std::size_t e = 0; e < topology.num_edges(); ++e) {
            non_manifold += topology.triangles_of_edge(static_cast<std::int32_t>(e)).size() > 2;
        }
        if (non_manifold > 0) {
            log_warning(
                "{}: cloth.mesh {}: {} of its {} edges are shared by more than two triangles "
                "(non-manifold): cloth is a surface, and there it is not one; check the mesh for "
                "duplicated or fused faces",
                scene_name, scene.mesh.string(), non_manifold, topology.num_edges());
        }
        // A file's seams (a generated grid has none; instances are checked for overlap later).
        if (const std::int64_t doubled = vertices_on_others(mesh.positions); doubled > 0) {
            log_warning(
                "{}: {} of the cloth's {} vertices lie exactly on another vertex (seams left "
                "unwelded in the file?): the cloth is not joined there, and its pieces start "
                "touching; weld those vertices in the file to sew them",
                scene_name, doubled, mesh.positions.size());
        }
    }
    warn_implausible_size(scene, scene_name, mesh);
    const cloth::Placement transform{scene.rotate_degrees, scene.translate};
    place(mesh.positions, transform);
    if (garment) {
        garment->positions = mesh.positions;
        if (!scene.instances.empty()) {  // the faces once per copy (vertex offsets as below)
            const io::PolygonMesh one = *garment;
            for (std::size_t k = 1; k < scene.instances.size(); ++k) {
                const auto offset = static_cast<std::int32_t>(k * one.positions.size());
                const auto corner_offset =
                    static_cast<std::int32_t>(garment->corner_vertices.size());
                for (const std::int32_t v : one.corner_vertices) {
                    garment->corner_vertices.push_back(v + offset);
                }
                garment->corner_uvs.insert(garment->corner_uvs.end(), one.corner_uvs.begin(),
                                           one.corner_uvs.end());
                garment->corner_normals.insert(garment->corner_normals.end(),
                                               one.corner_normals.begin(),
                                               one.corner_normals.end());
                for (std::size_t f = 1; f < one.face_starts.size(); ++f) {
                    garment->face_starts.push_back(one.face_starts[f] + corner_offset);
                }
                garment->face_tags.insert(garment->face_tags.end(), one.face_tags.begin(),
                                          one.face_tags.end());
                for (std::size_t a = 0; a < one.vertex_attributes.size(); ++a) {
                    const std::vector<double>& values = one.vertex_attributes[a].values;
                    std::vector<double>& all = garment->vertex_attributes[a].values;
                    all.insert(all.end(), values.begin(), values.end());
                }
                for (std::size_t a = 0; a < one.face_attributes.size(); ++a) {
                    const std::vector<double>& values = one.face_attributes[a].values;
                    std::vector<double>& all = garment->face_attributes[a].values;
                    all.insert(all.end(), values.begin(), values.end());
                }
            }
        }
    }
    if (scene.instances.empty()) {
        return mesh;
    }
    const auto num_vertices = static_cast<std::int64_t>(mesh.positions.size());
    if (num_vertices * static_cast<std::int64_t>(scene.instances.size()) >
        std::numeric_limits<std::int32_t>::max()) {
        throw InvalidInput(fmt::format(
            "cloth: {} instances of {} vertices exceed the 2^31 - 1 vertex indices a mesh has",
            scene.instances.size(), num_vertices));
    }
    geometry::TriangleMeshD copies;
    for (std::size_t k = 0; k < scene.instances.size(); ++k) {
        const auto offset = static_cast<std::int32_t>(k * mesh.positions.size());
        const std::size_t first = copies.positions.size();
        copies.positions.insert(copies.positions.end(), mesh.positions.begin(),
                                mesh.positions.end());
        place(std::span<Vec3d>(copies.positions).subspan(first), scene.instances[k]);
        for (const geometry::Triangle& t : mesh.triangles) {
            copies.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
    }
    return copies;
}

// The vertices of a pin group: its listed indices and every vertex inside one of its regions.
std::vector<std::int32_t> pinned_vertices(const cloth::PinGroup& group,
                                          const geometry::TriangleMeshD& mesh,
                                          const std::string& scene_name) {
    std::vector<std::int32_t> pinned = group.vertices;
    for (const std::int32_t v : pinned) {
        if (static_cast<std::size_t>(v) >= mesh.positions.size()) {
            throw InvalidInput(fmt::format(
                "{}: {}.vertices: vertex {} out of range, expected an index below {} (the "
                "cloth's vertices, all copies)",
                scene_name, group.key, v, mesh.positions.size()));
        }
    }
    for (std::size_t r = 0; r < group.regions.size(); ++r) {
        const cloth::PinRegion& region = group.regions[r];
        const std::size_t before = pinned.size();
        for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
            const Vec3d& p = mesh.positions[v];
            if (p.x >= region.min.x && p.x <= region.max.x && p.y >= region.min.y &&
                p.y <= region.max.y && p.z >= region.min.z && p.z <= region.max.z) {
                pinned.push_back(static_cast<std::int32_t>(v));
            }
        }
        if (pinned.size() == before) {  // legal, but almost certainly not meant
            AABBd cloth_box;
            for (const Vec3d& p : mesh.positions) {
                cloth_box.extend(p);
            }
            log_warning(
                "{}: {} region {} (min ({:g}, {:g}, {:g}), max ({:g}, {:g}, {:g})) holds none of "
                "the cloth's {} vertices, which span ({:.3g}, {:.3g}, {:.3g}) to ({:.3g}, {:.3g}, "
                "{:.3g}) as placed: it pins nothing; check the box against the cloth's placement",
                scene_name, group.key, r, region.min.x, region.min.y, region.min.z, region.max.x,
                region.max.y, region.max.z, mesh.positions.size(), cloth_box.lo.x, cloth_box.lo.y,
                cloth_box.lo.z, cloth_box.hi.x, cloth_box.hi.y, cloth_box.hi.z);
        }
    }
    return pinned;
}

// The largest distance of `points[indices]` (all points when indices is empty) from `pivot`.
double reach_from(const Vec3d& pivot, std::span<const Vec3d> points,
                  std::span<const std::int32_t> indices) {
    double reach = 0.0;
    const auto add = [&](const Vec3d& p) {
        reach = std::max(reach, norm(p - pivot));
    };
    if (indices.empty()) {
        std::for_each(points.begin(), points.end(), add);
    } else {
        for (const std::int32_t v : indices) {
            add(points[static_cast<std::size_t>(v)]);
        }
    }
    return reach;
}

// Warns about a keyframed pin group or obstacle that moves farther than the cloth's thickness in
// one substep. With self-collision, such pins do not follow their keyframes: they chase their
// target at half the thickness per substep (XPBDStepper, CATCH_UP_IN_THICKNESS) and lag behind
// it. Such obstacles can pass through cloth between substeps (docs/formats.md, "Choosing
// substeps", rule 1), and contact with them is first seen by the self-collision's fail-safe,
// which holds vertices back instead of pushing them apart (stiff, jerky cloth).
void warn_fast_motion(const std::string& scene_name, const std::string& key, bool pins,
                      const cloth::Motion& motion, double reach, const cloth::ClothScene& scene) {
    const double h = 1.0 / (scene.frames_per_second * scene.substeps);
    const double bound = scene.material.thickness;
    const cloth::Motion::FastestStep fastest = motion.fastest_step(reach, h);
    if (!(fastest.distance > bound)) {
        return;
    }
    const char* consequence =
        pins && scene.self_collision
            ? "the pins chase their keyframed target at half the thickness per substep and lag "
              "behind it (stats.json: pins_lagging, pins_max_lag)"
            : "cloth it pulls or hits is caught only by the self-collision fail-safe, which holds "
              "vertices back (stiff, slow frames)";
    log_warning(
        "{}: {}: its motion covers up to {:.3g} m in one substep ({:.3g} m/s) from t = {:.4g} s "
        "(frame {}), more than the thickness ({:.3g} m) per substep: {}; spread its keyframes "
        "over more time or raise substeps",
        scene_name, key, fastest.distance, fastest.distance / h, fastest.time,
        static_cast<long long>(std::floor(fastest.time * scene.frames_per_second)) + 1, bound,
        consequence);
}

// Warns about a deforming obstacle whose vertices move more than a few thicknesses in one
// substep: the swept test still keeps cloth out of it, but pushes are bounded with
// self-collision (the cloth lags behind the surface, stats.json: obstacles_lagging).
void warn_fast_deformation(const std::string& scene_name, const std::string& key,
                           const cloth::MeshAnimation& animation, const cloth::ClothScene& scene) {
    const double h = 1.0 / (scene.frames_per_second * scene.substeps);
    const double step = animation.max_vertex_step(h);
    const double bound = FAST_OBSTACLE_IN_THICKNESS * scene.material.thickness;
    if (!(step > bound)) {
        return;
    }
    log_warning(
        "{}: {}: its frames move a vertex up to {:.3g} m in one substep ({:.3g} m/s), more than "
        "{:g} thicknesses ({:.3g} m): cloth it hits is pushed out at a bounded speed and lags "
        "behind its surface (stats.json: obstacle_max_step, obstacles_lagging, "
        "obstacle_max_lag); raise substeps or slow the animation (its fps)",
        scene_name, key, step, step / h, FAST_OBSTACLE_IN_THICKNESS, bound);
}

// A pattern with one %d or %0Nd: the text before and after it, and the width (0: none).
struct FramePattern {
    std::string before;
    std::string after;
    int width = 0;
};

FramePattern parse_frame_pattern(const std::string& pattern, const std::string& scene_name,
                                 const std::string& key) {
    const auto fail = [&]() {
        throw InvalidInput(
            fmt::format("{}: {}: \"{}\": expected a file pattern with one frame number, %d or %0Nd "
                        "(\"body/frame_%04d.obj\")",
                        scene_name, key, pattern));
    };
    const std::size_t at = pattern.find('%');
    if (at == std::string::npos) {
        fail();
    }
    std::size_t k = at + 1;
    int width = 0;
    if (k < pattern.size() && pattern[k] == '0') {
        ++k;
        while (k < pattern.size() && pattern[k] >= '0' && pattern[k] <= '9' && width < 100) {
            width = width * 10 + (pattern[k] - '0');
            ++k;
        }
        if (width == 0) {
            fail();
        }
    }
    if (k >= pattern.size() || pattern[k] != 'd' || pattern.find('%', k + 1) != std::string::npos) {
        fail();
    }
    return {pattern.substr(0, at), pattern.substr(k + 1), width};
}

// Vertex positions of one frame file, checked against frame 0's topology.
std::vector<Vec3d> read_frame(const std::filesystem::path& file,
                              const geometry::TriangleMeshD& first, std::size_t k,
                              const std::string& scene_name, const std::string& key) {
    geometry::TriangleMeshD frame = read_nonempty_mesh(file, scene_name, key);
    if (frame.positions.size() != first.positions.size() ||
        frame.triangles.size() != first.triangles.size()) {
        throw InvalidInput(fmt::format(
            "{}: {}: frame {} ({}) has {} vertices and {} triangles, frame 0 has {} and {}: "
            "expected the same mesh in every frame (one topology, moved vertices)",
            scene_name, key, k, file.string(), frame.positions.size(), frame.triangles.size(),
            first.positions.size(), first.triangles.size()));
    }
    for (std::size_t t = 0; t < frame.triangles.size(); ++t) {
        if (frame.triangles[t] != first.triangles[t]) {
            throw InvalidInput(fmt::format(
                "{}: {}: frame {} ({}): triangle {} is ({}, {}, {}), in frame 0 ({}, {}, {}): "
                "expected the same triangles in every frame",
                scene_name, key, k, file.string(), t, frame.triangles[t][0], frame.triangles[t][1],
                frame.triangles[t][2], first.triangles[t][0], first.triangles[t][1],
                first.triangles[t][2]));
        }
    }
    return std::move(frame.positions);
}

}  // namespace

std::vector<std::filesystem::path> obstacle_frame_files(const cloth::SceneObstacle& obstacle,
                                                        const std::string& scene_name,
                                                        const std::string& key) {
    if (obstacle.frames_pattern.empty()) {
        return obstacle.frames;
    }
    const std::string pattern = obstacle.frames_pattern.string();
    const FramePattern parts = parse_frame_pattern(pattern, scene_name, key);
    const auto name = [&](std::int64_t i) {
        return std::filesystem::path(parts.before + fmt::format("{:0{}d}", i, parts.width) +
                                     parts.after);
    };
    std::int64_t start = obstacle.frame_start;
    if (start < 0) {
        start = std::filesystem::exists(name(0)) ? 0 : 1;
    }
    std::vector<std::filesystem::path> files;
    if (obstacle.frame_count > 0) {
        for (std::int64_t i = start; i < start + obstacle.frame_count; ++i) {
            if (!std::filesystem::exists(name(i))) {
                throw InvalidInput(fmt::format(
                    "{}: {}: frame file {} is missing: expected {} files numbered from {} "
                    "(\"count\")",
                    scene_name, key, name(i).string(), obstacle.frame_count, start));
            }
            files.push_back(name(i));
        }
        return files;
    }
    for (std::int64_t i = start; std::filesystem::exists(name(i)); ++i) {
        files.push_back(name(i));
    }
    if (files.empty()) {
        throw InvalidInput(fmt::format("{}: {}: no file matches \"{}\" (tried {}{})", scene_name,
                                       key, pattern, name(start).string(),
                                       obstacle.frame_start < 0 ? " and " + name(0).string() : ""));
    }
    return files;
}

ClothSetup load_cloth_setup(const cloth::ClothScene& scene, const std::string& scene_name,
                            std::uint64_t max_memory_bytes) {
    ClothSetup setup;
    setup.mesh = load_cloth(scene, scene_name,
                            max_memory_bytes > 0 ? max_memory_bytes : available_memory_bytes(),
                            setup.garment);
    if (setup.garment) {
        setup.garment->positions = setup.mesh.positions;
    }
    for (const cloth::SceneSeam& seam : scene.seams) {
        for (const auto& [side, vertices] : {std::pair{"a", &seam.a}, std::pair{"b", &seam.b}}) {
            for (std::size_t k = 0; k < vertices->size(); ++k) {
                const std::int32_t v = (*vertices)[k];
                if (static_cast<std::size_t>(v) >= setup.mesh.positions.size()) {
                    throw InvalidInput(fmt::format(
                        "{}: {}.{}[{}]: vertex {} out of range, expected an index in [0, {}) "
                        "(the cloth's vertices{})",
                        scene_name, seam.key, side, k, v, setup.mesh.positions.size(),
                        scene.instances.empty() ? "" : ", all instances"));
                }
                if (v == (side[0] == 'a' ? seam.b : seam.a)[k]) {
                    throw InvalidInput(fmt::format("{}: {}: pair {}: vertex {} is sewn to itself",
                                                   scene_name, seam.key, k, v));
                }
            }
        }
    }
    warn_seam_stretch(scene, scene_name, setup.mesh);
    // Physical stiffnesses become compliances for this mesh (material_preset.hpp).
    setup.material = scene.material;
    if (scene.stretch_stiffness) {
        setup.material.stretch_compliance = cloth::stretch_compliance_for(
            *scene.stretch_stiffness, setup.mesh.positions, setup.mesh.triangles);
    }
    if (scene.bend_stiffness) {
        setup.material.bend_compliance = cloth::bend_compliance_for(
            *scene.bend_stiffness, setup.mesh.positions, setup.mesh.triangles);
    }
    for (const cloth::PinGroup& group : scene.pins) {
        setup.pins.push_back(pinned_vertices(group, setup.mesh, scene_name));
    }
    // Obstacles, and their shapes (planes as squares around the cloth).
    AABBd cloth_box;
    for (const Vec3d& p : setup.mesh.positions) {
        cloth_box.extend(p);
    }
    const Vec3d centre = (cloth_box.lo + cloth_box.hi) * 0.5;
    const double plane_half_size = 0.75 * norm(cloth_box.hi - cloth_box.lo) + 0.5;
    for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
        const cloth::SceneObstacle& obstacle = scene.obstacles[k];
        if (obstacle.mesh.empty()) {
            setup.mesh_obstacles.push_back(nullptr);
            setup.animations.push_back(nullptr);
            setup.shapes.push_back(obstacle_shape(obstacle, nullptr, centre, plane_half_size));
            continue;
        }
        const bool deforming = !obstacle.frames.empty() || !obstacle.frames_pattern.empty();
        const std::string key =
            fmt::format("obstacles[{}].mesh.{}", k, deforming ? "frames" : "file");
        const std::vector<std::filesystem::path> frame_files =
            deforming ? obstacle_frame_files(obstacle, scene_name, key)
                      : std::vector<std::filesystem::path>{};
        geometry::TriangleMeshD shape =
            read_nonempty_mesh(deforming ? frame_files.front() : obstacle.mesh, scene_name, key);
        std::shared_ptr<const cloth::MeshAnimation> animation;
        if (deforming) {
            std::vector<std::vector<Vec3d>> frames;
            const geometry::TriangleMeshD first = shape;
            for (std::size_t f = 0; f < frame_files.size(); ++f) {
                frames.push_back(f == 0 ? first.positions
                                        : read_frame(frame_files[f], first, f, scene_name, key));
                place(frames.back(), obstacle.mesh_placement);
            }
            animation = std::make_shared<const cloth::MeshAnimation>(
                std::move(frames),
                obstacle.frames_fps > 0.0 ? obstacle.frames_fps : scene.frames_per_second,
                obstacle.loop);
        }
        place(shape.positions, obstacle.mesh_placement);
        setup.animations.push_back(animation);
        setup.shapes.push_back(obstacle_shape(obstacle, &shape, centre, plane_half_size));
        setup.shapes.back().animation = animation;
        auto mesh_obstacle = std::make_shared<const cloth::MeshObstacle>(std::move(shape));
        if (const std::optional<double> volume = mesh_obstacle->enclosed_volume();
            volume && *volume < 0.0) {
            log_warning(
                "{}: obstacles[{}].mesh.file ({}): a closed mesh wound inward (its normals point "
                "in; enclosed volume {:.3g} m³): cloth is kept inside it, as in a container; "
                "reverse its triangles' winding to keep cloth outside",
                scene_name, k, obstacle.mesh.string(), *volume);
        }
        setup.mesh_obstacles.push_back(std::move(mesh_obstacle));
    }
    // Pins and obstacles that jump.
    for (std::size_t g = 0; g < scene.pins.size(); ++g) {
        const cloth::PinGroup& group = scene.pins[g];
        if (!group.motion.is_static() && !setup.pins[g].empty()) {
            warn_fast_motion(scene_name, group.key, true, group.motion,
                             reach_from(group.motion.pivot, setup.mesh.positions, setup.pins[g]),
                             scene);
        }
    }
    for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
        const cloth::Motion& motion = scene.obstacles[k].motion;
        if (!motion.is_static()) {
            warn_fast_motion(scene_name, fmt::format("obstacles[{}]", k), false, motion,
                             reach_from(motion.pivot, setup.shapes[k].rest.positions, {}), scene);
        }
        if (setup.animations[k]) {
            warn_fast_deformation(scene_name, fmt::format("obstacles[{}]", k), *setup.animations[k],
                                  scene);
        }
    }
    return setup;
}

StartState prepare_start(const cloth::ClothScene& scene, const std::string& scene_name,
                         cloth::ClothSolver& solver) {
    StartState start;
    const cloth::ClothSolver::Penetration inside = solver.obstacle_penetration();
    if (inside.vertices > 0) {
        log_warning(
            "{}: {} of the cloth's {} vertices start inside an obstacle (the deepest {:.3g} m "
            "in): the first substeps put them on its surface (with self-collision at most half "
            "the thickness deeper per substep), stretching the cloth; check the obstacles' "
            "placement and, for planes and open meshes, which side their normals face",
            scene_name, inside.vertices, solver.positions().size(), inside.deepest);
    }
    start.initial_intersections =
        collision::count_intersecting_pairs(solver.positions(), solver.triangles());
    const auto num_triangles = static_cast<std::int64_t>(solver.triangles().size());
    if (start.initial_intersections > MAX_INITIAL_PAIRS_PER_TRIANGLE * num_triangles) {
        throw InvalidInput(fmt::format(
            "{}: the cloth intersects itself in {} pairs of triangles ({:.1f} per triangle, more "
            "than {}): layers lie on or through each other, which cannot be untangled; check "
            "the mesh and the scene's instances",
            scene_name, start.initial_intersections,
            static_cast<double>(start.initial_intersections) / static_cast<double>(num_triangles),
            MAX_INITIAL_PAIRS_PER_TRIANGLE));
    }
    if (start.initial_intersections > 0) {
        log_warning("{}: the cloth intersects itself at the start ({} pairs of triangles)",
                    scene_name, start.initial_intersections);
    }
    if (scene.untangle && start.initial_intersections > 0) {
        start.untangled = solver.untangle();
        const cloth::UntangleResult& u = *start.untangled;
        if (u.final_pairs == 0) {
            log_info(
                "{}: untangled in {} iterations ({:.1f} ms), no vertex moved more than "
                "{:.2f} mm",
                scene_name, u.iterations, u.ms, u.max_displacement * 1e3);
        } else {
            log_warning(
                "{}: untangling left {} of {} pairs after {} iterations; the simulation keeps "
                "those from growing but does not undo them",
                scene_name, u.final_pairs, start.initial_intersections, u.iterations);
        }
    }
    return start;
}

nlohmann::ordered_json untangle_report(const StartState& start) {
    if (!start.untangled) {
        return nullptr;
    }
    const cloth::UntangleResult& u = *start.untangled;
    return {{"iterations", u.iterations},
            {"region_moves", u.region_moves},
            {"pairs_left", u.final_pairs},
            {"max_displacement_m", u.max_displacement},
            {"ms", u.ms}};
}

std::unique_ptr<cloth::ClothSolver> make_solver(const cloth::ClothScene& scene,
                                                const ClothSetup& setup) {
    auto solver = std::make_unique<cloth::ClothSolver>(setup.mesh, setup.material);
    for (std::size_t g = 0; g < scene.pins.size(); ++g) {
        if (!scene.pins[g].attach) {
            solver->add_moving_pins(setup.pins[g], scene.pins[g].motion);
        }
    }
    std::vector<std::size_t> mesh_index(scene.obstacles.size(), 0);
    std::size_t num_meshes = 0;
    for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
        const cloth::SceneObstacle& obstacle = scene.obstacles[k];
        if (setup.animations[k]) {
            solver->add_animated_mesh_obstacle(*setup.mesh_obstacles[k], setup.animations[k],
                                               obstacle.motion);
            mesh_index[k] = num_meshes++;
        } else if (setup.mesh_obstacles[k]) {
            solver->add_mesh_obstacle(setup.mesh_obstacles[k], obstacle.motion);
            mesh_index[k] = num_meshes++;
        } else {
            solver->add_obstacle(obstacle.shape, obstacle.motion);
        }
    }
    for (std::size_t g = 0; g < scene.pins.size(); ++g) {
        if (const std::optional<cloth::PinAttach>& attach = scene.pins[g].attach) {
            try {
                solver->add_attached_pins(
                    setup.pins[g], mesh_index[static_cast<std::size_t>(attach->obstacle_index)],
                    attach->max_distance);
            } catch (const InvalidInput& e) {
                throw InvalidInput(fmt::format("{}.attach: {}", scene.pins[g].key, e.what()));
            }
        }
    }
    for (const cloth::SceneSeam& seam : scene.seams) {
        solver->add_seam(seam.a, seam.b, seam.seconds);
    }
    solver->set_gravity(scene.gravity);
    solver->set_air(scene.air);
    solver->enable_self_collision(scene.self_collision);
    if (scene.vbd) {
        solver->use_vbd(*scene.vbd);
    } else if (scene.xpbd_ogc) {
        solver->use_xpbd_ogc(scene.xpbd_ogc);
    }
    return solver;
}

AABBd framing_box(std::span<const Vec3d> cloth, const std::vector<ObstacleShape>& obstacles) {
    AABBd box;
    for (const Vec3d& p : cloth) {
        box.extend(p);
    }
    for (const ObstacleShape& shape : obstacles) {
        if (shape.bounded) {
            for (const Vec3d& p : shape.rest.positions) {
                box.extend(p);
            }
        }
    }
    return box;
}

ObstacleShape obstacle_shape(const cloth::SceneObstacle& obstacle,
                             const geometry::TriangleMeshD* mesh, const Vec3d& centre,
                             double plane_half_size) {
    ObstacleShape shape;
    shape.motion = obstacle.motion;
    if (mesh != nullptr) {
        shape.rest = *mesh;
        shape.smooth = false;
    } else if (const auto* sphere = std::get_if<cloth::SphereObstacle>(&obstacle.shape)) {
        shape.rest = geometry::make_uv_sphere(sphere->center, sphere->radius, SPHERE_SEGMENTS);
    } else if (const auto* box = std::get_if<cloth::BoxObstacle>(&obstacle.shape)) {
        shape.rest = geometry::make_box(box->min, box->max);
        shape.smooth = false;
    } else {
        const auto& plane = std::get<cloth::PlaneObstacle>(obstacle.shape);
        const Vec3d n = plane.normal * (1.0 / norm(plane.normal));
        const Vec3d foot = centre - n * dot(centre - plane.point, n);
        shape.rest = geometry::make_plane_square(foot, n, plane_half_size);
        shape.smooth = false;
        shape.bounded = false;
    }
    return shape;
}

}  // namespace pliant::pipeline
