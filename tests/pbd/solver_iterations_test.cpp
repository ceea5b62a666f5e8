// SoftBody's iterations per substep and their Chebyshev acceleration (soft_body.hpp,
// "Iterations"; detail/chebyshev.hpp): the ω recurrence, convergence towards a many-substep
// reference, no inversion under the four drivers, determinism, checkpoints, bad options.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/chebyshev.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::pbd {
namespace {

constexpr double DT = 1.0 / 24.0;

// A full-box grid of n³ cells of `voxels` unit voxels each.
TetGrid box_grid(int n, int voxels = 2) {
    const volume::Volume v =
        volume::Volume::allocate({voxels * n, voxels * n, voxels * n}, volume::VoxelType::u8,
                                 {1.0, 1.0, 1.0}, {0.0, 0.0, 0.0});
    return build_tet_grid(v, {.cell_voxels = voxels, .full_box = true});
}

// The accelerated solver the tests exercise: 2 substeps of 3 iterations.
SoftBodyOptions accelerated() {
    return {.stiffness = 0.8,
            .substeps = 2,
            .iterations = 3,
            .chebyshev_rho = 0.9,
            .chebyshev_gamma = 0.9};
}

TEST(SolverIterations, OmegaFollowsWangsRecurrenceToItsLimit) {
    const double rho = 0.9;
    EXPECT_EQ(detail::chebyshev_omega(0, rho), 1.0);
    EXPECT_DOUBLE_EQ(detail::chebyshev_omega(1, rho), 2.0 / (2.0 - rho * rho));
    EXPECT_DOUBLE_EQ(detail::chebyshev_omega(2, rho),
                     4.0 / (4.0 - rho * rho * (2.0 / (2.0 - rho * rho))));
    // The fixed point of ω = 4 / (4 − ρ² ω): 2 / (1 + √(1 − ρ²)).
    EXPECT_NEAR(detail::chebyshev_omega(200, rho), 2.0 / (1.0 + std::sqrt(1.0 - rho * rho)), 1e-12);
    for (int k = 0; k < 10; ++k) {
        EXPECT_EQ(detail::chebyshev_omega(k, 0.0), 1.0);
    }
}

// The update leaves vertices of inverse mass 0 (pinned, driven) bitwise put and moves the others
// by eq. 12.
TEST(SolverIterations, UpdateMovesOnlyFreeVertices) {
    std::vector<detail::Float4> x = {{1.0f, 2.0f, 3.0f, 0.0f}, {1.0f, 0.0f, 0.0f, 1.0f}};
    std::vector<Vec3f> current = {{0.5f, 2.0f, 3.0f}, {0.0f, 0.0f, 0.0f}};
    std::vector<Vec3f> previous = {{0.0f, 0.0f, 0.0f}, {-1.0f, 0.0f, 0.0f}};
    detail::chebyshev_update(x.data(), current, previous, 1.5f, 0.5f);
    EXPECT_EQ(x[0].x, 1.0f);
    EXPECT_EQ(x[0].y, 2.0f);
    // 1.5 · (0.5 · (1 − 0) + 0 − (−1)) + (−1) = 1.25.
    EXPECT_FLOAT_EQ(x[1].x, 1.25f);
    EXPECT_EQ(x[1].w, 1.0f);
    EXPECT_EQ(previous[1].x, 0.0f);
    EXPECT_FLOAT_EQ(current[1].x, 1.25f);
    EXPECT_EQ(current[0].x, 1.0f);
}

double mean_distance(const SoftBody& a, const SoftBody& b) {
    double sum = 0.0;
    for (std::size_t v = 0; v < a.positions().size(); ++v) {
        sum += norm(vec3_cast<double>(a.positions()[v]) - vec3_cast<double>(b.positions()[v]));
    }
    return sum / static_cast<double>(a.positions().size());
}

double mean_displacement(const SoftBody& body) {
    double sum = 0.0;
    for (std::size_t v = 0; v < body.positions().size(); ++v) {
        sum += norm(vec3_cast<double>(body.positions()[v]) -
                    vec3_cast<double>(body.rest_positions()[v]));
    }
    return sum / static_cast<double>(body.positions().size());
}

// A twist ramped in over 0.5 s, after `frames` frames, with heavy damping (10 / s) so that the
// body is near its quasi-static shape and the comparison measures convergence, not the phase of
// a vibration.
SoftBody twisted(const TetGrid& grid, SoftBodyOptions options, int frames) {
    options.damping = 10.0;
    SoftBody body(grid, options);
    body.add_driver(TwistDriver{.axis = Axis::z, .angle = 90.0, .ramp_time = 0.5});
    for (int f = 0; f < frames; ++f) {
        body.step(DT);
    }
    return body;
}

// Convergence: after the twist, against a 40-substep reference, 2 substeps of 3 accelerated
// iterations end nearer than 2 substeps of 3 plain iterations (the same 6 sweeps), which end
// nearer than 2 substeps of one sweep; the accelerated body carries the twist further in.
// (16³ cells, measured: mean distances 3.61, 4.18, 5.76; mean displacements 0.66, 0.61, 0.45 of
// the reference's.)
TEST(SolverIterations, AcceleratedIterationsApproachTheManySubstepReference) {
    const TetGrid grid = box_grid(16);
    const SoftBody reference = twisted(grid, {.stiffness = 0.8, .substeps = 40}, 24);
    const SoftBody one = twisted(grid, {.stiffness = 0.8, .substeps = 2}, 24);
    const SoftBody plain = twisted(grid, {.stiffness = 0.8, .substeps = 2, .iterations = 3}, 24);
    const SoftBody fast = twisted(grid, accelerated(), 24);
    const double d_one = mean_distance(one, reference);
    const double d_plain = mean_distance(plain, reference);
    const double d_fast = mean_distance(fast, reference);
    EXPECT_LT(d_plain, d_one);
    EXPECT_LT(d_fast, 0.95 * d_plain) << d_fast << " vs " << d_plain;
    EXPECT_GT(mean_displacement(fast), mean_displacement(plain));
    EXPECT_EQ(fast.stats().inverted_tets, 0);
}

// No tet inverts under the twist, wave, bubble and a drag with the accelerated solver on a small
// grid (8³ cells). At the source scale, 2 × 4 iterations at ρ 0.97 invert a few tets under the
// bubble and the drag (docs/performance.md, "Soft-body solver").
TEST(SolverIterations, AcceleratedSolverInvertsNothingUnderTheFourDrivers) {
    const TetGrid grid = box_grid(8);
    for (int d = 0; d < 4; ++d) {
        SoftBody body(grid, accelerated());
        switch (d) {
            case 0:
                body.add_driver(TwistDriver{.axis = Axis::z, .angle = 90.0});
                break;
            case 1:
                body.add_driver(WaveDriver{});
                break;
            case 2:
                body.add_driver(BubbleDriver{});
                break;
            default:
                body.set_drag(0, {-4.0f, -4.0f, -4.0f}, 3.0f);
                break;
        }
        std::int64_t worst = 0;
        for (int f = 0; f < 48; ++f) {
            body.step(DT);
            worst = std::max(worst, body.stats().inverted_tets);
        }
        EXPECT_EQ(worst, 0) << "driver " << d;
        EXPECT_GT(mean_displacement(body), 0.0) << "driver " << d;
    }
}

std::vector<Vec3f> run_threads(int threads) {
    set_num_threads(threads);
    // 24³ cells of 1 voxel: 15,625 vertices, several chunks of the per-vertex passes.
    const TetGrid grid = box_grid(24, 1);
    SoftBody body(grid, accelerated());
    body.add_driver(TwistDriver{.angle = 60.0, .ramp_time = 0.2});
    body.add_driver(BubbleDriver{.inflation = 1.5, .ramp_time = 0.2});
    body.set_drag(5, {-1.0f, 0.0f, 0.0f}, 2.0f);
    for (int f = 0; f < 6; ++f) {
        body.step(DT);
    }
    set_num_threads(0);
    return {body.positions().begin(), body.positions().end()};
}

TEST(SolverIterations, OneAndTwoThreadsAreBitwiseIdentical) {
    const std::vector<Vec3f> one = run_threads(1);
    const std::vector<Vec3f> two = run_threads(2);
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(Vec3f)), 0);
}

// The iterations keep no state across steps: a loaded state continues bit for bit.
TEST(SolverIterations, SavedStateContinuesBitForBit) {
    const TetGrid grid = box_grid(4);
    SoftBody original(grid, accelerated());
    original.add_driver(TwistDriver{.axis = Axis::z, .angle = 90.0});
    for (int f = 0; f < 5; ++f) {
        original.step(DT);
    }
    ByteWriter saved;
    original.save_state(saved);
    SoftBody resumed(grid, accelerated());
    resumed.add_driver(TwistDriver{.axis = Axis::z, .angle = 90.0});
    ByteReader in(saved.bytes(), "state");
    resumed.load_state(in);
    in.expect_end();
    for (int f = 0; f < 5; ++f) {
        original.step(DT);
        resumed.step(DT);
    }
    EXPECT_EQ(std::memcmp(original.positions().data(), resumed.positions().data(),
                          original.positions().size_bytes()),
              0);
}

// One iteration without acceleration is today's solver bit for bit.
TEST(SolverIterations, OnePlainIterationIsTheDefaultSolver) {
    const TetGrid grid = box_grid(4);
    const SoftBody a = twisted(grid, {.substeps = 3}, 4);
    const SoftBody b = twisted(grid, {.substeps = 3, .iterations = 1, .chebyshev_rho = 0.0}, 4);
    EXPECT_EQ(std::memcmp(a.positions().data(), b.positions().data(), a.positions().size_bytes()),
              0);
}

TEST(SolverIterations, BadOptionsAreInvalidInput) {
    const TetGrid grid = box_grid(2);
    const auto expect_invalid = [&](const SoftBodyOptions& o, const std::string& needle) {
        try {
            SoftBody body(grid, o);
            ADD_FAILURE() << "no exception for " << needle;
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    expect_invalid({.iterations = 0}, "iterations");
    expect_invalid({.chebyshev_rho = 1.0}, "chebyshev_rho");
    expect_invalid({.chebyshev_rho = -0.1}, "chebyshev_rho");
    expect_invalid({.chebyshev_rho = std::nan("")}, "chebyshev_rho");
    expect_invalid({.chebyshev_gamma = 0.0}, "chebyshev_gamma");
    expect_invalid({.chebyshev_gamma = 1.5}, "chebyshev_gamma");
}

}  // namespace
}  // namespace pliant::pbd
