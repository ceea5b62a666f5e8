#include "pliant/volume/inverse_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
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

// Every vertex moved by up to ±amplitude/2 cells along each axis (a fixed pseudo-random
// sequence); amplitude 1.6 overlaps and inverts many tets.
std::vector<Vec3f> jittered(const std::vector<Vec3f>& rest, const Volume& v, int cell_voxels,
                            float amplitude, std::uint32_t seed) {
    std::vector<Vec3f> out = rest;
    const auto jitter = [&] {
        seed = seed * 1664525u + 1013904223u;
        return (static_cast<float>(seed >> 8) / 16777216.0f - 0.5f) * amplitude *
               static_cast<float>(cell_voxels);
    };
    for (Vec3f& p : out) {
        p.x += jitter() * static_cast<float>(v.spacing().x);
        p.y += jitter() * static_cast<float>(v.spacing().y);
        p.z += jitter() * static_cast<float>(v.spacing().z);
    }
    return out;
}

// The map as InverseMap's contract states it, node by node over every tet (O(#nodes · #T)):
// the tets' affine maps computed with the same double operations in the same order as
// InverseMap::build (barycentric rows cross(e1, e2) / det …, λ3 = 1 − λ0 − λ1 − λ2, the node
// inside where the smallest λ ≥ −1e-9 and the node within the box of the tet's vertices), the
// highest tet index holding a node wins; a node not held, next to held ones, takes the
// extrapolated map of the neighbour (z, y, x order) whose tet gives it the largest smallest λ.
std::vector<float> reference_map(const Volume& source, const Volume& target,
                                 std::span<const geometry::Tet> tets, std::span<const Vec3f> rest,
                                 std::span<const Vec3f> deformed, int b,
                                 std::array<std::int64_t, 3>& nodes) {
    const auto grid = [](const Volume& v, const Vec3f& x) {
        return Vec3d{(x.x - v.origin().x) * (1.0 / v.spacing().x) - 0.5,
                     (x.y - v.origin().y) * (1.0 / v.spacing().y) - 0.5,
                     (x.z - v.origin().z) * (1.0 / v.spacing().z) - 0.5};
    };
    for (int a = 0; a < 3; ++a) {
        nodes[static_cast<std::size_t>(a)] = (target.dims()[a] - 1) / b + 2;
    }
    const std::int64_t nx = nodes[0], ny = nodes[1], nz = nodes[2];
    struct Map {
        Vec3d p[4], p3, r3, rows[3], dr[3];
        bool ok = false;
        double lambda(const Vec3d& x, double l[3]) const {
            const Vec3d d = x - p3;
            l[0] = dot(rows[0], d);
            l[1] = dot(rows[1], d);
            l[2] = dot(rows[2], d);
            return std::min({l[0], l[1], l[2], 1.0 - l[0] - l[1] - l[2]});
        }
        Vec3d at(const double l[3]) const {
            return r3 + dr[0] * l[0] + dr[1] * l[1] + dr[2] * l[2];
        }
    };
    std::vector<Map> maps(tets.size());
    for (std::size_t t = 0; t < tets.size(); ++t) {
        Map& m = maps[t];
        Vec3d r[4];
        for (int v = 0; v < 4; ++v) {
            const auto i = static_cast<std::size_t>(tets[t][static_cast<std::size_t>(v)]);
            m.p[v] = grid(target, deformed[i]);
            r[v] = grid(source, rest[i]);
        }
        const Vec3d e0 = m.p[0] - m.p[3], e1 = m.p[1] - m.p[3], e2 = m.p[2] - m.p[3];
        const double det = dot(e0, cross(e1, e2));
        m.ok = std::abs(det) > 0.0 && std::isfinite(det);
        const double inv = 1.0 / det;
        m.rows[0] = cross(e1, e2) * inv;
        m.rows[1] = cross(e2, e0) * inv;
        m.rows[2] = cross(e0, e1) * inv;
        m.p3 = m.p[3];
        m.r3 = r[3];
        for (int k = 0; k < 3; ++k) {
            m.dr[k] = r[k] - r[3];
        }
    }
    const auto node = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
        return Vec3d{static_cast<double>(x * b), static_cast<double>(y * b),
                     static_cast<double>(z * b)};
    };
    const auto in_box = [&](const Map& m, const Vec3d& x) {
        for (int a = 0; a < 3; ++a) {
            const double lo = std::min({m.p[0][a], m.p[1][a], m.p[2][a], m.p[3][a]});
            const double hi = std::max({m.p[0][a], m.p[1][a], m.p[2][a], m.p[3][a]});
            if (x[a] < std::ceil(lo / b) * b || x[a] > std::floor(hi / b) * b) {
                return false;
            }
        }
        return true;
    };
    std::vector<std::int64_t> holder(static_cast<std::size_t>(nx * ny * nz), -1);
    std::vector<float> g(3 * holder.size(), std::numeric_limits<float>::quiet_NaN());
    const auto put = [&](std::int64_t q, const Vec3d& r) {
        g[3 * q] = static_cast<float>(r.x);
        g[3 * q + 1] = static_cast<float>(r.y);
        g[3 * q + 2] = static_cast<float>(r.z);
    };
    for (std::int64_t z = 0; z < nz; ++z) {
        for (std::int64_t y = 0; y < ny; ++y) {
            for (std::int64_t x = 0; x < nx; ++x) {
                const std::int64_t q = x + nx * (y + ny * z);
                for (auto t = static_cast<std::int64_t>(tets.size()) - 1; t >= 0; --t) {
                    const Map& m = maps[static_cast<std::size_t>(t)];
                    double l[3];
                    if (m.ok && m.lambda(node(x, y, z), l) >= -1e-9 && in_box(m, node(x, y, z))) {
                        holder[static_cast<std::size_t>(q)] = t;
                        put(q, m.at(l));
                        break;
                    }
                }
            }
        }
    }
    for (std::int64_t z = 0; z < nz; ++z) {
        for (std::int64_t y = 0; y < ny; ++y) {
            for (std::int64_t x = 0; x < nx; ++x) {
                const std::int64_t q = x + nx * (y + ny * z);
                if (holder[static_cast<std::size_t>(q)] >= 0) {
                    continue;
                }
                double best = -std::numeric_limits<double>::infinity();
                for (std::int64_t cz = std::max<std::int64_t>(0, z - 1);
                     cz <= std::min(nz - 1, z + 1); ++cz) {
                    for (std::int64_t cy = std::max<std::int64_t>(0, y - 1);
                         cy <= std::min(ny - 1, y + 1); ++cy) {
                        for (std::int64_t cx = std::max<std::int64_t>(0, x - 1);
                             cx <= std::min(nx - 1, x + 1); ++cx) {
                            const std::int64_t t =
                                holder[static_cast<std::size_t>(cx + nx * (cy + ny * cz))];
                            if (t < 0) {
                                continue;
                            }
                            const Map& m = maps[static_cast<std::size_t>(t)];
                            double l[3];
                            const double score = m.lambda(node(x, y, z), l);
                            if (score > best) {
                                best = score;
                                put(q, m.at(l));
                            }
                        }
                    }
                }
            }
        }
    }
    return g;
}

void expect_reference_map(const Volume& source, const Volume& target,
                          std::span<const geometry::Tet> tets, std::span<const Vec3f> rest,
                          std::span<const Vec3f> deformed, int b, const std::string& what) {
    std::array<std::int64_t, 3> nodes{};
    const std::vector<float> expected =
        reference_map(source, target, tets, rest, deformed, b, nodes);
    // The AVX2 pass over the tets (where the CPU has AVX2) and the scalar one.
    for (const bool avx2 : {true, false}) {
        allow_avx2(avx2);
        for (const int threads : {1, 2}) {
            set_num_threads(threads);
            InverseMap map;
            const InverseMapStats stats =
                map.build(source, target, tets, rest, deformed, {.node_voxels = b});
            EXPECT_GT(stats.num_inside, 0) << what;
            ASSERT_EQ(map.nodes(), nodes) << what;
            ASSERT_EQ(map.node_coordinates().size(), expected.size()) << what;
            EXPECT_EQ(std::memcmp(map.node_coordinates().data(), expected.data(),
                                  expected.size() * sizeof(float)),
                      0)
                << what << ", " << threads << " threads, AVX2 allowed: " << avx2;
            // Each row's extent: from its first node that is not empty to its last.
            const std::span<const std::int32_t> extents = map.node_row_extents();
            ASSERT_EQ(extents.size(), static_cast<std::size_t>(2 * nodes[1] * nodes[2])) << what;
            for (std::int64_t row = 0; row < nodes[1] * nodes[2]; ++row) {
                std::int64_t first = 0, end = 0;
                for (std::int64_t x = 0; x < nodes[0]; ++x) {
                    if (!std::isnan(expected[static_cast<std::size_t>(3 * (x + nodes[0] * row))])) {
                        first = end == 0 ? x : first;
                        end = x + 1;
                    }
                }
                EXPECT_EQ(extents[static_cast<std::size_t>(2 * row)], first)
                    << what << ", row " << row;
                EXPECT_EQ(extents[static_cast<std::size_t>(2 * row + 1)], end)
                    << what << ", row " << row;
            }
        }
    }
    allow_avx2(true);
    set_num_threads(0);
}

// InverseMap::build against the contract evaluated node by node over every tet, bit for bit:
// smooth and rough deformations, inverted and overlapping tets, nodes exactly on the tets'
// vertices, edges and faces (the target shifted by half a voxel puts every node on a lattice
// vertex, held by up to 20 tets at once), B not a power of two, a mesh that is not a whole
// number of cells and whose cells are out of TetGrid's order.
TEST(InverseMap, BuildsTheMapOfItsContractBitForBit) {
    const Volume source = shepp_logan_3d({30, 26, 34});
    for (const int cell_voxels : {4, 3}) {
        const pbd::TetGrid g = full_grid(source, cell_voxels);
        const std::vector<Vec3f>& rest = g.mesh.positions;
        const std::string b = "B " + std::to_string(cell_voxels) + ": ";
        expect_reference_map(source, source, g.mesh.tets, rest, rest, cell_voxels, b + "identity");
        Volume shifted = like(source);
        shifted.set_origin(source.origin() - source.spacing() * 0.5);
        expect_reference_map(source, shifted, g.mesh.tets, rest, rest, cell_voxels,
                             b + "nodes on the lattice vertices");
        expect_reference_map(source, shifted, g.mesh.tets, rest, twisted(rest, source, 90.0, true),
                             cell_voxels, b + "rigid quarter turn, nodes on the lattice");
        expect_reference_map(source, source, g.mesh.tets, rest, twisted(rest, source, 60.0, false),
                             cell_voxels, b + "twist 60");
        for (const float amplitude : {0.3f, 1.6f}) {
            const std::vector<Vec3f> d = jittered(rest, source, cell_voxels, amplitude, 777u);
            expect_reference_map(source, source, g.mesh.tets, rest, d, cell_voxels,
                                 b + "jitter " + std::to_string(amplitude));
            std::vector<geometry::Tet> tets = g.mesh.tets;
            tets.resize(tets.size() - 3);
            std::swap(tets[5], tets[12]);
            std::swap(tets[15], tets[19]);
            std::reverse(tets.begin() + 40, tets.end());
            expect_reference_map(source, source, tets, rest, d, cell_voxels,
                                 b + "shuffled, jitter " + std::to_string(amplitude));
        }
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
    std::vector<Vec3f> nan_rest(g.mesh.positions);
    nan_rest.back().z = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(message([&] {
                  map.build(source, source, g.mesh.tets, nan_rest, g.mesh.positions);
              }).find("rest_positions[" + std::to_string(nan_rest.size() - 1) + "]"),
              std::string::npos);
    std::vector<geometry::Tet> tets(g.mesh.tets);
    tets[1][2] = 100000;
    EXPECT_NE(message([&] {
                  map.build(source, source, tets, g.mesh.positions, g.mesh.positions);
              }).find("tet 1"),
              std::string::npos);
    tets = g.mesh.tets;
    tets.back()[0] = -1;
    EXPECT_NE(message([&] {
                  map.build(source, source, tets, g.mesh.positions, g.mesh.positions);
              }).find("tet " + std::to_string(tets.size() - 1) + " has vertex index -1"),
              std::string::npos);
    tets.back()[0] = static_cast<std::int32_t>(g.mesh.positions.size());
    EXPECT_NE(message([&] {
                  map.build(source, source, tets, g.mesh.positions, g.mesh.positions);
              }).find("outside [0, " + std::to_string(g.mesh.positions.size()) + ")"),
              std::string::npos);
    Volume target = like(source);
    EXPECT_NE(message([&] { resample_through(InverseMap{}, source, target); }).find("not built"),
              std::string::npos);
}

}  // namespace
}  // namespace pliant::volume
