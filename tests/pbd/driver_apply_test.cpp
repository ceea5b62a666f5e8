#include "pliant/pbd/detail/driver_apply.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <variant>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/lattice_sweep.hpp"
#include "pliant/pbd/detail/wave_rest.hpp"
#include "pliant/pbd/tet_edges.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "support/grid_constraints.hpp"
#include "support/tet_grids.hpp"

namespace pliant::pbd::detail {
namespace {

BodyBox box_of(const std::vector<Vec3f>& rest) {
    BodyBox box{vec3_cast<double>(rest[0]), vec3_cast<double>(rest[0]), {}, 1.0};
    for (const Vec3f& p : rest) {
        box.lo = min(box.lo, vec3_cast<double>(p));
        box.hi = max(box.hi, vec3_cast<double>(p));
    }
    box.centre = (box.lo + box.hi) * 0.5;
    box.size = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    return box;
}

// The rest state at time t straight from the formulas (driver_apply.hpp): every vertex displaced
// by every wave (summed in double, rounded to float), the lengths and volumes of the displaced
// positions (wave_rest.hpp's scalar formulas), every constraint scaled by every bubble, no
// shortcut.
void reference_rest_state(const std::vector<Driver>& drivers, const BodyBox& box,
                          const std::vector<Vec3f>& rest, double t, test::GridConstraints& out) {
    std::vector<Vec3f> displacement;
    bool has_wave = false;
    int axes = 0;  // the axes the waves displace along
    for (const Driver& d : drivers) {
        if (const auto* w = std::get_if<WaveDriver>(&d)) {
            axes |= 1 << static_cast<int>(w->displacement);
        }
    }
    for (const Vec3f& r : rest) {
        Vec3d u{};
        for (const Driver& d : drivers) {
            if (const auto* w = std::get_if<WaveDriver>(&d)) {
                u += wave_displacement(*w, box, vec3_cast<double>(r), t);
                has_wave = true;
            }
        }
        displacement.push_back(vec3_cast<float>(u));
    }
    const auto bubble = [&](const Vec3d& p) {
        double f = 1.0;
        for (const Driver& d : drivers) {
            if (const auto* b = std::get_if<BubbleDriver>(&d)) {
                f *= bubble_factor(*b, box, p, t);
            }
        }
        return f;
    };
    const auto at = [&](std::int32_t v) {
        return vec3_cast<double>(rest[static_cast<std::size_t>(v)]);
    };
    const auto r = [&](std::int32_t v) {
        return rest[static_cast<std::size_t>(v)];
    };
    const auto u = [&](std::int32_t v) {
        return displacement[static_cast<std::size_t>(v)];
    };
    for (std::size_t k = 0; k < out.edges.vertices.size(); ++k) {
        const auto& e = out.edges.vertices[k];
        double length = has_wave ? displaced_length(r(e[0]), u(e[0]), r(e[1]), u(e[1]), axes)
                                 : out.edges.rest_lengths0[k];
        length *= std::cbrt(bubble((at(e[0]) + at(e[1])) * 0.5));
        out.edges.rest_lengths[k] = static_cast<float>(length);
    }
    for (std::size_t k = 0; k < out.tets.vertices.size(); ++k) {
        const geometry::Tet& q = out.tets.vertices[k];
        const std::array<Vec3f, 4> rq{r(q[0]), r(q[1]), r(q[2]), r(q[3])};
        const std::array<Vec3f, 4> uq{u(q[0]), u(q[1]), u(q[2]), u(q[3])};
        double volume =
            has_wave ? displaced_volume(rq.data(), uq.data(), axes) : out.tets.rest_volumes0[k];
        volume *= bubble((at(q[0]) + at(q[1]) + at(q[2]) + at(q[3])) * 0.25);
        out.tets.rest_volumes[k] = static_cast<float>(volume);
    }
}

// apply_rest_drivers over a sequence of times (one cache, as SoftBody calls it frame by frame:
// through the ramps, then ramped in) against the formulas at every time, bitwise, on 1 and 2
// threads, with and without the lattice sweep's runs (the waves' AVX2 kernels where the CPU has
// them); a ball (rows of different lengths, so runs of every length) with a bubble reaching past
// it.
TEST(ApplyRestDrivers, ShortcutsGiveTheFormulasBitForBit) {
    const TetGrid grid = test::ball_tet_grid({24, 20, 18}, false);
    const std::vector<Vec3f>& rest = grid.mesh.positions;
    const BodyBox box = box_of(rest);
    const std::vector<std::vector<Driver>> cases = {
        {Driver{BubbleDriver{.centre = {0.8, 0.2, 0.5}, .radius = 0.4, .ramp_time = 0.1}},
         Driver{BubbleDriver{.radius = 0.2, .inflation = 0.5, .ramp_time = 0.0}}},
        {Driver{WaveDriver{.amplitude = 0.05, .ramp_time = 0.1}},
         Driver{WaveDriver{.direction = Axis::z, .displacement = Axis::y, .speed = 0.0}},
         Driver{WaveDriver{.direction = Axis::y, .displacement = Axis::x, .wavelength = 0.3}}},
        {Driver{WaveDriver{}}, Driver{BubbleDriver{}}}};
    for (const int threads : {1, 2}) {
        set_num_threads(threads);
        for (std::size_t c = 0; c < cases.size() * 2; ++c) {
            test::GridConstraints got = test::grid_constraints(grid);
            test::GridConstraints expected = test::grid_constraints(grid);
            LatticeSweep lattice;
            if (c % 2 == 1) {
                lattice = build_lattice_sweep(grid, got.edges, got.tets);
                build_lattice_sweep(grid, expected.edges, expected.tets);
            }
            RestDriverCache cache;
            for (int frame = 1; frame <= 6; ++frame) {
                const double t = frame / 24.0;
                apply_rest_drivers(cases[c / 2], box, rest, t, got.edges, got.tets, cache,
                                   c % 2 == 1 ? &lattice : nullptr);
                reference_rest_state(cases[c / 2], box, rest, t, expected);
                ASSERT_EQ(
                    std::memcmp(got.edges.rest_lengths.data(), expected.edges.rest_lengths.data(),
                                got.edges.rest_lengths.size() * sizeof(float)),
                    0)
                    << "case " << c << " frame " << frame << ", " << threads << " threads";
                ASSERT_EQ(
                    std::memcmp(got.tets.rest_volumes.data(), expected.tets.rest_volumes.data(),
                                got.tets.rest_volumes.size() * sizeof(float)),
                    0)
                    << "case " << c << " frame " << frame << ", " << threads << " threads";
            }
            EXPECT_TRUE(cache.is_valid);
            EXPECT_NE(got.edges.rest_lengths, got.edges.rest_lengths0) << "case " << c;
        }
        // Bubbles alone: only the constraints they reach are listed, fewer than all.
        test::GridConstraints laid = test::grid_constraints(grid);
        RestDriverCache cache;
        apply_rest_drivers(cases[0], box, rest, 0.05, laid.edges, laid.tets, cache);
        EXPECT_GT(cache.tets.size(), 0u);
        EXPECT_LT(cache.tets.size(), laid.tets.vertices.size());
    }
    set_num_threads(0);
}

}  // namespace
}  // namespace pliant::pbd::detail
