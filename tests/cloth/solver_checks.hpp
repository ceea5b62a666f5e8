// A scene and checks shared by the cloth solver tests: the OGC contact tests of the VBD stepper
// (ogc_contact_test.cpp) and of the XPBD stepper (xpbd_ogc_test.cpp), and vbd_stepper_test.cpp.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/core/parallel.hpp"
#include "support/sheets.hpp"

namespace pliant::test {

// Two sheets of n × n quads, 0.5 m wide, 2 cm apart over the plane z = 0 (the lower one at the
// thickness, 5 mm, above it), the upper one shifted by (13, 7) mm and thrown down at 2 m/s onto
// the lower one, with gravity and self-collision; the caller chooses the stepper.
inline std::unique_ptr<cloth::ClothSolver> colliding_sheets(int n) {
    geometry::TriangleMeshD mesh = flat_sheet(n, 0.5, 0.005);
    const geometry::TriangleMeshD upper = flat_sheet(n, 0.5, 0.025);
    const auto offset = static_cast<std::int32_t>(mesh.positions.size());
    for (const Vec3d& p : upper.positions) {
        mesh.positions.push_back(p + Vec3d{0.013, 0.007, 0.0});
    }
    for (const geometry::Triangle& t : upper.triangles) {
        mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    auto solver = std::make_unique<cloth::ClothSolver>(mesh, cloth::ClothMaterial{});
    solver->add_obstacle(cloth::PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
    std::vector<Vec3d> velocities(mesh.positions.size());
    for (std::size_t v = static_cast<std::size_t>(offset); v < velocities.size(); ++v) {
        velocities[v] = {0.0, 0.0, -2.0};
    }
    solver->set_velocities(velocities);
    solver->enable_self_collision(true);
    return solver;
}

// The positions of make()'s solver after 8 frames of 1/24 s, `substeps` substeps each, run with
// `threads` threads.
template <class Make>
std::vector<Vec3d> positions_after_8_frames(const Make& make, int threads, int substeps) {
    set_num_threads(threads);
    auto solver = make();
    for (int f = 0; f < 8; ++f) {
        solver->step(1.0 / 24.0, substeps);
    }
    set_num_threads(0);
    return {solver->positions().begin(), solver->positions().end()};
}

// make()'s solver run `frames_before` frames, its state saved and loaded into a second one, then
// both run 6 more frames (`substeps` substeps each): positions and velocities equal bit for bit.
template <class Make>
void expect_saved_state_continues_bit_for_bit(const Make& make, int frames_before, int substeps) {
    auto a = make();
    for (int f = 0; f < frames_before; ++f) {
        a->step(1.0 / 24.0, substeps);
    }
    ByteWriter out;
    a->save_state(out);
    auto b = make();
    ByteReader in(out.bytes(), "state");
    b->load_state(in);
    for (int f = 0; f < 6; ++f) {
        a->step(1.0 / 24.0, substeps);
        b->step(1.0 / 24.0, substeps);
    }
    for (std::size_t v = 0; v < a->positions().size(); ++v) {
        ASSERT_EQ(a->positions()[v], b->positions()[v]) << v;
        ASSERT_EQ(a->velocities()[v], b->velocities()[v]) << v;
    }
}

}  // namespace pliant::test
