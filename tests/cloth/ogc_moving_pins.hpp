// A scene shared by the OGC tests of both steppers (xpbd_ogc_test.cpp, ogc_contact_test.cpp):
// a sheet hanging from pins that turn it about the vertical faster than the OGC ball lets a free
// vertex move in one substep, and what a run of it measures.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "pliant/cloth/edge_strain.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "support/sheets.hpp"

namespace pliant::test {

// OGC options whose ball (bound_share · query_factor · thickness = 0.1 · 2 · 5 mm = 1 mm) is
// smaller than the pins' move per substep (they chase their target at up to half the thickness,
// 2.5 mm, per substep; at 16 substeps per frame the row's ends move 2.45 mm), and whose
// re-detection share (20 %) is more than the pinned row's neighbours (13 of 156 free vertices):
// only a rule that follows the motion re-detects for them.
inline cloth::OgcOptions small_ball_ogc() {
    cloth::OgcOptions options;
    options.bound_share = 0.1;
    options.redetect_share = 0.2;
    return options;
}

// A sheet of 12 × 12 quads, 0.3 m wide, hanging in the plane y = 0 with self-collision, its top
// row (z = 0.15 m) pinned; the pins turn 360° about the vertical through the row's middle and
// rise 0.1 m in one second (the row's ends at 0.94 m/s) and twist the sheet; `use` picks the
// stepper.
inline std::unique_ptr<cloth::ClothSolver> sheet_on_turning_pins(
    const std::function<void(cloth::ClothSolver&)>& use) {
    geometry::TriangleMeshD mesh = flat_sheet(12, 0.3, 0.0);
    for (Vec3d& p : mesh.positions) {
        p = {p.x, 0.0, p.y};  // hanging in the plane y = 0
    }
    const double top = std::max_element(mesh.positions.begin(), mesh.positions.end(),
                                        [](const Vec3d& a, const Vec3d& b) { return a.z < b.z; })
                           ->z;
    std::vector<std::int32_t> row;
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        if (mesh.positions[v].z > top - 1e-9) {
            row.push_back(static_cast<std::int32_t>(v));
        }
    }
    auto solver = std::make_unique<cloth::ClothSolver>(mesh, cloth::ClothMaterial{});
    cloth::Motion motion;
    motion.pivot = {0.0, 0.0, top};
    motion.keyframes = {cloth::Keyframe{0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
                        cloth::Keyframe{1.0, {0.0, 0.0, 0.1}, {0.0, 0.0, 360.0}}};
    solver->add_moving_pins(row, motion);
    solver->enable_self_collision(true);
    use(*solver);
    return solver;
}

// What `frames` frames of `substeps` substeps measure: the largest intersecting-pair count of any
// frame, the worst frame's strain p99 (an independent measure: edge lengths against the rest
// shape), the vertices the CCD audit or fail-safe put back, the OGC detections.
struct MovingPinsRun {
    std::int64_t max_intersecting_pairs = 0;
    double worst_strain_p99 = 0.0;
    std::int64_t reverted_vertices = 0;
    std::int64_t detections = 0;
};

inline MovingPinsRun run_moving_pins(cloth::ClothSolver& solver, int frames, int substeps) {
    const cloth::EdgeStrain strain(solver.positions(), solver.triangles());
    MovingPinsRun run;
    for (int f = 0; f < frames; ++f) {
        const cloth::ClothStepStats stats = solver.step(1.0 / 24.0, substeps);
        run.max_intersecting_pairs =
            std::max(run.max_intersecting_pairs,
                     collision::count_intersecting_pairs(solver.positions(), solver.triangles()));
        run.worst_strain_p99 =
            std::max(run.worst_strain_p99, strain.measure(solver.positions()).p99);
        run.reverted_vertices += stats.self.reverted_vertices;
        run.detections += stats.ogc_detections;
    }
    return run;
}

// An OGC run follows the pins as the proximity path's `reference` run of the same scene does:
// both free of intersections, no vertex put back by the audit, more than one detection per frame
// of `frames`, and strain p99 at worst 1.5 times the reference's plus 2 %.
inline void expect_follows_pins(const MovingPinsRun& reference, const MovingPinsRun& run,
                                int frames) {
    EXPECT_EQ(reference.max_intersecting_pairs, 0);
    EXPECT_EQ(run.max_intersecting_pairs, 0);
    EXPECT_EQ(run.reverted_vertices, 0);
    EXPECT_GT(run.detections, frames);
    EXPECT_LT(run.worst_strain_p99, 1.5 * reference.worst_strain_p99 + 0.02)
        << "proximity " << reference.worst_strain_p99;
}

}  // namespace pliant::test
