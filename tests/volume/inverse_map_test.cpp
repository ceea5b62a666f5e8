#include "pliant/volume/inverse_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/resample.hpp"

namespace pliant::volume {
namespace {

pbd::TetGrid full_grid(const Volume& v, int cell_voxels) {
    return pbd::build_tet_grid(v, {.cell_voxels = cell_voxels, .full_box = true});
}

Volume like(const Volume& v) {
    return Volume::allocate(v.dims(), v.type(), v.spacing(), v.origin());
}

Vec3d box_center(const Volume& v) {
    const AABBd b = v.bounds();
    return (b.lo + b.hi) * 0.5;
}

// Rotation about z through c by an angle growing linearly with height: 0 at the bottom of the box,
// `top_degrees` at its top (a twist; top_degrees constant over z when rigid).
std::vector<Vec3f> twisted(const std::vector<Vec3f>& rest, const Volume& v, double top_degrees,
                           bool rigid) {
    const AABBd box = v.bounds();
    const Vec3d c = box_center(v);
    std::vector<Vec3f> out(rest.size());
    for (std::size_t i = 0; i < rest.size(); ++i) {
        const Vec3d d = vec3_cast<double>(rest[i]) - c;
        const double h = rigid ? 1.0 : (rest[i].z - box.lo.z) / (box.hi.z - box.lo.z);
        const double a = top_degrees * h * std::numbers::pi / 180.0;
        out[i] = vec3_cast<float>(Vec3d{std::cos(a) * d.x - std::sin(a) * d.y,
                                        std::sin(a) * d.x + std::cos(a) * d.y, d.z} +
                                  c);
    }
    return out;
}

TEST(InverseMap, IdentityMapsEveryVoxelCentreToItself) {
    const Volume source = shepp_logan_3d({20, 24, 17});
    const pbd::TetGrid g = full_grid(source, 4);
    InverseMap map;
    const InverseMapStats stats =
        map.build(source, source, g.mesh.tets, g.mesh.positions, g.mesh.positions);
    EXPECT_EQ(map.nodes(), (std::array<std::int64_t, 3>{6, 7, 6}));
    EXPECT_GT(stats.num_inside, 0);
    EXPECT_GT(stats.num_extrapolated, 0);  // the nodes beyond the last voxel centre
    double worst = 0.0;
    for (int k = 0; k < 17; ++k) {
        for (int j = 0; j < 24; ++j) {
            for (int i = 0; i < 20; ++i) {
                const double t[3] = {static_cast<double>(i), static_cast<double>(j),
                                     static_cast<double>(k)};
                double s[3];
                ASSERT_TRUE(map.source_coordinate(t, s)) << i << " " << j << " " << k;
                for (int a = 0; a < 3; ++a) {
                    worst = std::max(worst, std::abs(s[a] - t[a]));
                }
            }
        }
    }
    EXPECT_LT(worst, 1e-4);
}

TEST(InverseMap, RigidRotationIsTheAnalyticInverseInsideTheBody) {
    // A rotation is affine: the trilinear interpolation of its nodes is exact wherever the
    // eight nodes of a cell are inside the rotated body.
    const Volume source = shepp_logan_3d({32, 32, 32});
    const pbd::TetGrid g = full_grid(source, 4);
    const std::vector<Vec3f> deformed = twisted(g.mesh.positions, source, 30.0, true);
    InverseMap map;
    map.build(source, source, g.mesh.tets, g.mesh.positions, deformed);
    const double a = 30.0 * std::numbers::pi / 180.0;
    const double c = 15.5;  // the box centre in grid coordinates
    int checked = 0;
    double worst = 0.0;
    for (int k = 0; k < 32; ++k) {
        for (int j = 0; j < 32; ++j) {
            for (int i = 0; i < 32; ++i) {
                const double t[3] = {static_cast<double>(i), static_cast<double>(j),
                                     static_cast<double>(k)};
                // Only centres well inside the rotated body (8 nodes inside tets).
                if (std::hypot(t[0] - c, t[1] - c) > 11.0) {
                    continue;
                }
                double s[3];
                ASSERT_TRUE(map.source_coordinate(t, s)) << i << " " << j << " " << k;
                const double dx = t[0] - c;
                const double dy = t[1] - c;
                const double expected[3] = {c + std::cos(a) * dx + std::sin(a) * dy,
                                            c - std::sin(a) * dx + std::cos(a) * dy, t[2]};
                for (int d = 0; d < 3; ++d) {
                    worst = std::max(worst, std::abs(s[d] - expected[d]));
                }
                ++checked;
            }
        }
    }
    EXPECT_GT(checked, 10000);
    EXPECT_LT(worst, 1e-3);
}

TEST(InverseMap, TwistSampledThroughTheMapMatchesTheExactResample) {
    const Volume source = rgba_test_object({48, 48, 48}, VoxelType::rgba32f);
    const pbd::TetGrid g = full_grid(source, 4);
    const std::vector<Vec3f> deformed = twisted(g.mesh.positions, source, 60.0, false);
    Volume exact = like(source);
    resample(source, g.mesh.tets, g.mesh.positions, deformed, exact);
    InverseMap map;
    map.build(source, source, g.mesh.tets, g.mesh.positions, deformed);
    Volume through = like(source);
    resample_through(map, source, through);
    // Premultiplied colour and alpha (what compositing sees), peak 1.
    const auto x = exact.values<VoxelType::rgba32f>();
    const auto y = through.values<VoxelType::rgba32f>();
    double sum = 0.0;
    for (std::size_t v = 0; v < x.size(); v += 4) {
        for (std::size_t c = 0; c < 4; ++c) {
            const double d =
                (c < 3 ? x[v + 3] * x[v + c] : x[v + 3]) - (c < 3 ? y[v + 3] * y[v + c] : y[v + 3]);
            sum += d * d;
        }
    }
    const double psnr = 10.0 * std::log10(static_cast<double>(x.size()) / sum);
    std::cout << "twist 60 degrees, 48^3: PSNR " << psnr << " dB\n";
    EXPECT_GE(psnr, 40.0);
}

TEST(InverseMap, OneAndTwoThreadsGiveTheSameMap) {
    const Volume source = shepp_logan_3d({40, 36, 44});
    const pbd::TetGrid g = full_grid(source, 4);
    const std::vector<Vec3f> deformed = twisted(g.mesh.positions, source, 45.0, false);
    InverseMap one;
    InverseMap two;
    set_num_threads(1);
    one.build(source, source, g.mesh.tets, g.mesh.positions, deformed);
    set_num_threads(2);
    two.build(source, source, g.mesh.tets, g.mesh.positions, deformed);
    set_num_threads(0);
    ASSERT_EQ(one.node_coordinates().size(), two.node_coordinates().size());
    EXPECT_EQ(std::memcmp(one.node_coordinates().data(), two.node_coordinates().data(),
                          one.node_coordinates().size_bytes()),
              0);
}

// Deformed tets that overlap (every vertex jittered by up to 0.8 cells, many tets inverted): a
// node inside several takes the map of the highest tet index, whatever order the tasks visit
// them in, so 1, 2 and 3 threads build the same bits.
TEST(InverseMap, OverlappingTetsGiveTheSameMapOnAnyThreadCount) {
    const Volume source = shepp_logan_3d({36, 40, 32});
    const pbd::TetGrid g = full_grid(source, 4);
    std::vector<Vec3f> deformed = g.mesh.positions;
    std::uint32_t state = 12345u;
    const auto jitter = [&] {
        state = state * 1664525u + 1013904223u;
        return (static_cast<float>(state >> 8) / 16777216.0f - 0.5f) * 1.6f * 4.0f;
    };
    for (Vec3f& p : deformed) {
        p.x += jitter() * static_cast<float>(source.spacing().x);
        p.y += jitter() * static_cast<float>(source.spacing().y);
        p.z += jitter() * static_cast<float>(source.spacing().z);
    }
    InverseMap maps[3];
    InverseMapStats stats[3];
    for (int threads = 1; threads <= 3; ++threads) {
        set_num_threads(threads);
        stats[threads - 1] =
            maps[threads - 1].build(source, source, g.mesh.tets, g.mesh.positions, deformed);
    }
    set_num_threads(0);
    EXPECT_GT(stats[0].num_inside, 0);
    for (int i = 1; i < 3; ++i) {
        EXPECT_EQ(stats[i].num_inside, stats[0].num_inside);
        EXPECT_EQ(stats[i].num_extrapolated, stats[0].num_extrapolated);
        ASSERT_EQ(maps[i].node_coordinates().size(), maps[0].node_coordinates().size());
        EXPECT_EQ(std::memcmp(maps[i].node_coordinates().data(), maps[0].node_coordinates().data(),
                              maps[0].node_coordinates().size_bytes()),
                  0)
            << i + 1 << " threads";
    }
}

TEST(InverseMap, PointsFarFromTheBodyAndOutsideTheNodesHaveNoSource) {
    const Volume source = shepp_logan_3d({32, 32, 32});
    const pbd::TetGrid g = full_grid(source, 4);
    std::vector<Vec3f> shrunk(g.mesh.positions);
    const Vec3d c = box_center(source);
    for (Vec3f& p : shrunk) {
        p = vec3_cast<float>(c + (vec3_cast<double>(p) - c) * 0.25);  // 8 voxels across
    }
    InverseMap map;
    map.build(source, source, g.mesh.tets, g.mesh.positions, shrunk);
    double s[3];
    const double corner[3] = {1.0, 1.0, 1.0};
    EXPECT_FALSE(map.source_coordinate(corner, s));
    const double centre[3] = {15.5, 15.5, 15.5};
    ASSERT_TRUE(map.source_coordinate(centre, s));
    EXPECT_NEAR(s[0], 15.5, 1e-3);
    const double outside[3] = {-1.0, 3.0, 3.0};
    EXPECT_FALSE(map.source_coordinate(outside, s));
    const double nan[3] = {std::numeric_limits<double>::quiet_NaN(), 3.0, 3.0};
    EXPECT_FALSE(map.source_coordinate(nan, s));
}

TEST(InverseMap, BadInputsAreInvalidInputNamingTheArgument) {
    const Volume source = shepp_logan_3d({8, 8, 8});
    const pbd::TetGrid g = full_grid(source, 4);
    InverseMap map;
    auto message = [&](auto&& call) {
        try {
            call();
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("no exception");
    };
    EXPECT_NE(message([&] {
                  map.build(source, source, g.mesh.tets, g.mesh.positions, g.mesh.positions,
                            {.node_voxels = 0});
              }).find("node_voxels (0)"),
              std::string::npos);
    const std::vector<Vec3f> fewer(g.mesh.positions.begin(), g.mesh.positions.end() - 1);
    EXPECT_NE(message([&] {
                  map.build(source, source, g.mesh.tets, g.mesh.positions, fewer);
              }).find("deformed_positions.size()"),
              std::string::npos);
    std::vector<Vec3f> bad(g.mesh.positions);
    bad[3].y = std::numeric_limits<float>::infinity();
    EXPECT_NE(message([&] {
                  map.build(source, source, g.mesh.tets, g.mesh.positions, bad);
              }).find("deformed_positions[3]"),
              std::string::npos);
    std::vector<geometry::Tet> tets(g.mesh.tets);
    tets[1][2] = 100000;
    EXPECT_NE(message([&] {
                  map.build(source, source, tets, g.mesh.positions, g.mesh.positions);
              }).find("tet 1"),
              std::string::npos);
    Volume target = like(source);
    EXPECT_NE(message([&] { resample_through(InverseMap{}, source, target); }).find("not built"),
              std::string::npos);
}

}  // namespace
}  // namespace pliant::volume
