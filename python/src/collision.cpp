// Self-collision: the broad phase (LBVH + R-triangles + orphan sets), CCD, the continuous narrow
// phase, exact intersecting-pair counts, and `pliant collide` as a function.
#include <fmt/format.h>

#include <cstring>
#include <memory>
#include <optional>

#include "common.hpp"
#include "pliant/collision/ccd.hpp"
#include "pliant/collision/feature_pairs.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/collision/narrow_phase.hpp"
#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/pipeline/broad_phase_report.hpp"

namespace pliant::python {
namespace {

using collision::EdgeEdgePair;
using collision::FeaturePairs;
using collision::VertexFacePair;
using BroadPhase = collision::SelfCollisionBroadPhase<double>;

static_assert(sizeof(VertexFacePair) == 8 && sizeof(EdgeEdgePair) == 8);

collision::CcdOptions ccd_options(double min_separation, double tolerance, int max_iterations) {
    return {
        .min_separation = min_separation, .tolerance = tolerance, .max_iterations = max_iterations};
}

// positions_t1 or, when None, positions_t0 (a static query).
const DoubleArray& end_positions(const DoubleArray& positions_t0,
                                 const std::optional<DoubleArray>& positions_t1) {
    return positions_t1 ? *positions_t1 : positions_t0;
}

}  // namespace

void bind_collision(py::module_& m) {
    py::class_<FeaturePairs>(m, "FeaturePairs", R"doc(
Feature pairs of a broad phase (or the hits of a narrow phase), owned by this object.

vertex_face: (P, 2) int32 view, rows (vertex, face) with the vertex not in the face.
edge_edge:   (Q, 2) int32 view, rows (edge_a, edge_b), edge_a < edge_b, indices into
             BroadPhase.edges; the two edges share no vertex.
Read-only views of this object's memory (no copy); they keep it alive.
)doc")
        .def_property_readonly("vertex_face",
                               [](const py::object& self) {
                                   const auto& pairs = self.cast<const FeaturePairs&>().vertex_face;
                                   return records_view(pairs.empty() ? nullptr : &pairs[0].vertex,
                                                       pairs.size(), 2, self, false);
                               })
        .def_property_readonly("edge_edge",
                               [](const py::object& self) {
                                   const auto& pairs = self.cast<const FeaturePairs&>().edge_edge;
                                   return records_view(pairs.empty() ? nullptr : &pairs[0].edge_a,
                                                       pairs.size(), 2, self, false);
                               })
        .def_property_readonly("num_vertex_face",
                               [](const FeaturePairs& p) { return p.vertex_face.size(); })
        .def_property_readonly("num_edge_edge",
                               [](const FeaturePairs& p) { return p.edge_edge.size(); })
        .def("__repr__", [](const FeaturePairs& p) {
            return fmt::format("pliant.FeaturePairs({} vertex-face, {} edge-edge)",
                               p.vertex_face.size(), p.edge_edge.size());
        });

    py::class_<collision::BroadPhaseStats>(m, "BroadPhaseStats")
        .def_readonly("build_ms", &collision::BroadPhaseStats::build_ms)
        .def_readonly("refit_ms", &collision::BroadPhaseStats::refit_ms)
        .def_readonly("traverse_ms", &collision::BroadPhaseStats::traverse_ms)
        .def_readonly("features_ms", &collision::BroadPhaseStats::features_ms)
        .def_readonly("triangle_pairs", &collision::BroadPhaseStats::triangle_pairs);

    py::class_<BroadPhase>(m, "BroadPhase", R"doc(
The self-collision broad phase of one triangle mesh (collision::SelfCollisionBroadPhase<double>):
every non-incident vertex-face and edge-edge pair whose feature boxes overlap, exactly once, in an
order identical for any number of threads.

    bp = pliant.BroadPhase(mesh.triangles, mesh.num_vertices)
    pairs = bp.update(positions_t0, positions_t1, inflation=0.0)   # swept over a step
    pairs = bp.update(positions)                                   # static query

The first update builds the LBVH, later ones refit it. Not thread-safe: one update at a time.
)doc")
        .def(py::init([](const IndexArray& triangles, std::size_t num_vertices) {
                 return std::make_unique<BroadPhase>(
                     index_rows<3>(triangles, "BroadPhase: triangles"), num_vertices);
             }),
             py::arg("triangles"), py::arg("num_vertices"),
             "Topology, R-triangle owners and the orphan set of a mesh of (T, 3) triangles over "
             "num_vertices vertices. InvalidInput for indices out of range or triangles that "
             "repeat a vertex.")
        .def(
            "update",
            [](BroadPhase& bp, const DoubleArray& positions_t0,
               const std::optional<DoubleArray>& positions_t1, double inflation) {
                const auto p0 = vec3d_rows(positions_t0, "BroadPhase.update: positions_t0");
                const auto p1 = vec3d_rows(end_positions(positions_t0, positions_t1),
                                           "BroadPhase.update: positions_t1");
                py::gil_scoped_release release;
                return FeaturePairs(bp.update(p0, p1, inflation));
            },
            py::arg("positions_t0"), py::arg("positions_t1") = py::none(),
            py::arg("inflation") = 0.0,
            "The feature pairs of the step positions_t0 -> positions_t1 ((N, 3) each; None: a "
            "static query at positions_t0), boxes grown by `inflation` (world units, >= 0) on "
            "every side. Returns a FeaturePairs (a copy of the result). Releases the GIL.")
        .def("request_rebuild", &BroadPhase::request_rebuild,
             "The next update builds the BVH from scratch instead of refitting it.")
        .def_property_readonly(
            "edges",
            [](const py::object& self) {
                return index_view<2>(std::span<const geometry::Edge>(
                                         self.cast<const BroadPhase&>().topology().edges),
                                     self, false);
            },
            "(E, 2) int32 view of the mesh's unique edges (a < b); EE pairs index it.")
        .def_property_readonly(
            "stats", [](const BroadPhase& bp) { return bp.stats(); },
            "Timings and the triangle-pair count of the last update.")
        .def_property_readonly("memory_bytes", &BroadPhase::memory_bytes);

    py::class_<collision::CcdResult>(m, "CcdResult")
        .def_readonly("hit", &collision::CcdResult::hit,
                      "A contact within min_separation cannot be excluded in t in [0, 1].")
        .def_readonly("toi", &collision::CcdResult::toi,
                      "Earliest time in [0, 1] a contact cannot be excluded (1 without a hit).")
        .def_readonly("iterations", &collision::CcdResult::iterations)
        .def_readonly("hit_iteration_limit", &collision::CcdResult::hit_iteration_limit)
        .def("__repr__", [](const collision::CcdResult& r) {
            return fmt::format("pliant.CcdResult(hit={}, toi={})", r.hit ? "True" : "False", r.toi);
        });

    const char* ccd_note =
        " Every point moves on a straight line from its _t0 to its _t1 position over the step. "
        "Conservative (Tight-Inclusion style): a contact is never missed; toi is a lower bound.";
    m.def(
        "vertex_face_ccd",
        [](const Vec3d& v_t0, const Vec3d& f0_t0, const Vec3d& f1_t0, const Vec3d& f2_t0,
           const Vec3d& v_t1, const Vec3d& f0_t1, const Vec3d& f1_t1, const Vec3d& f2_t1,
           double min_separation, double tolerance, int max_iterations) {
            return collision::vertex_face_ccd(
                v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1,
                ccd_options(min_separation, tolerance, max_iterations));
        },
        py::arg("v_t0"), py::arg("f0_t0"), py::arg("f1_t0"), py::arg("f2_t0"), py::arg("v_t1"),
        py::arg("f0_t1"), py::arg("f1_t1"), py::arg("f2_t1"), py::kw_only(),
        py::arg("min_separation") = 0.0, py::arg("tolerance") = 1e-6,
        py::arg("max_iterations") = 1'000'000,
        (std::string("Vertex v against triangle (f0, f1, f2) over one step.") + ccd_note).c_str());
    m.def(
        "edge_edge_ccd",
        [](const Vec3d& ea0_t0, const Vec3d& ea1_t0, const Vec3d& eb0_t0, const Vec3d& eb1_t0,
           const Vec3d& ea0_t1, const Vec3d& ea1_t1, const Vec3d& eb0_t1, const Vec3d& eb1_t1,
           double min_separation, double tolerance, int max_iterations) {
            return collision::edge_edge_ccd(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1,
                                            eb1_t1,
                                            ccd_options(min_separation, tolerance, max_iterations));
        },
        py::arg("ea0_t0"), py::arg("ea1_t0"), py::arg("eb0_t0"), py::arg("eb1_t0"),
        py::arg("ea0_t1"), py::arg("ea1_t1"), py::arg("eb0_t1"), py::arg("eb1_t1"), py::kw_only(),
        py::arg("min_separation") = 0.0, py::arg("tolerance") = 1e-6,
        py::arg("max_iterations") = 1'000'000,
        (std::string("Edge (ea0, ea1) against edge (eb0, eb1) over one step.") + ccd_note).c_str());

    py::class_<collision::NarrowPhaseResult>(m, "NarrowPhaseResult")
        .def_readonly("vf_hits", &collision::NarrowPhaseResult::vf_hits)
        .def_readonly("ee_hits", &collision::NarrowPhaseResult::ee_hits)
        .def_readonly("earliest_toi", &collision::NarrowPhaseResult::earliest_toi)
        .def_readonly("hits", &collision::NarrowPhaseResult::hits,
                      "The pairs the CCD cannot exclude, in the order of the input pairs.");
    m.def(
        "continuous_narrow_phase",
        [](const DoubleArray& positions_t0, const DoubleArray& positions_t1,
           const IndexArray& triangles, const IndexArray& edges, const FeaturePairs& pairs,
           double min_separation, double tolerance, int max_iterations) {
            const auto p0 = vec3d_rows(positions_t0, "continuous_narrow_phase: positions_t0");
            const auto p1 = vec3d_rows(positions_t1, "continuous_narrow_phase: positions_t1");
            const auto t = index_rows<3>(triangles, "continuous_narrow_phase: triangles");
            const auto e = index_rows<2>(edges, "continuous_narrow_phase: edges");
            py::gil_scoped_release release;
            return collision::continuous_narrow_phase<double>(
                p0, p1, t, e, pairs, ccd_options(min_separation, tolerance, max_iterations));
        },
        py::arg("positions_t0"), py::arg("positions_t1"), py::arg("triangles"), py::arg("edges"),
        py::arg("pairs"), py::kw_only(), py::arg("min_separation") = 0.0,
        py::arg("tolerance") = 1e-6, py::arg("max_iterations") = 1'000'000,
        "CCD on every pair of a broad phase's FeaturePairs over the step positions_t0 -> "
        "positions_t1; edges as BroadPhase.edges. Releases the GIL.");

    m.def(
        "count_intersecting_pairs",
        [](const DoubleArray& positions, const IndexArray& triangles) {
            const auto p = vec3d_rows(positions, "count_intersecting_pairs: positions");
            const auto t = index_rows<3>(triangles, "count_intersecting_pairs: triangles");
            py::gil_scoped_release release;
            return collision::count_intersecting_pairs(p, t);
        },
        py::arg("positions"), py::arg("triangles"),
        "Number of intersecting pairs of triangles that share no vertex, decided exactly "
        "(0: the mesh does not intersect itself). Releases the GIL.");
    m.def(
        "find_intersecting_pairs",
        [](const DoubleArray& positions, const IndexArray& triangles) {
            const auto p = vec3d_rows(positions, "find_intersecting_pairs: positions");
            const auto t = index_rows<3>(triangles, "find_intersecting_pairs: triangles");
            std::vector<std::array<std::int32_t, 2>> pairs;
            {
                py::gil_scoped_release release;
                pairs = collision::find_intersecting_pairs(p, t);
            }
            const auto n = static_cast<py::ssize_t>(pairs.size());
            std::vector<std::int32_t> flat(2 * pairs.size());
            std::memcpy(flat.data(), pairs.data(), flat.size() * sizeof(std::int32_t));
            return owning_array(std::move(flat), {n, 2});
        },
        py::arg("positions"), py::arg("triangles"),
        "The intersecting pairs as a (K, 2) int32 array of triangle indices i < j, sorted.");

    m.def(
        "collide",
        [](const geometry::TriangleMeshD& mesh, const std::optional<DoubleArray>& positions_t1,
           double inflation, int repeat, bool ccd) {
            const std::span<const Vec3d> p1 =
                positions_t1 ? vec3d_rows(*positions_t1, "collide: positions_t1")
                             : std::span<const Vec3d>(mesh.positions);
            pipeline::BroadPhaseReport report;
            {
                py::gil_scoped_release release;
                report = pipeline::measure_broad_phase(mesh, p1, inflation, repeat,
                                                       positions_t1.has_value(),
                                                       /*warm_up=*/false, ccd);
            }
            return to_python(pipeline::to_json(report));
        },
        py::arg("mesh"), py::arg("positions_t1") = py::none(), py::kw_only(),
        py::arg("inflation") = 0.0, py::arg("repeat") = 1, py::arg("ccd") = false,
        "What `pliant collide MESH [--to MESH_T1] --json` reports, as a dict: the broad phase "
        "on the step mesh.positions -> positions_t1 (None: static), vf_pairs, ee_pairs, "
        "timings (medians of `repeat` builds and refits); with ccd, the narrow phase's hits.");
}

}  // namespace pliant::python
