#include "pliant/cloth/isometric_bending.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/cloth/dihedral.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {
namespace {

using detail::PackedVertex;

// A random rotation (from a random unit quaternion) and translation.
struct Placement {
    Vec3d columns[3];
    Vec3d offset;
    Vec3d apply(const Vec3d& p) const {
        return columns[0] * p.x + columns[1] * p.y + columns[2] * p.z + offset;
    }
};

Placement random_placement(std::mt19937_64& random) {
    std::normal_distribution<double> normal;
    double q[4];
    double length = 0.0;
    for (double& c : q) {
        c = normal(random);
        length += c * c;
    }
    length = std::sqrt(length);
    const double w = q[0] / length;
    const double x = q[1] / length;
    const double y = q[2] / length;
    const double z = q[3] / length;
    Placement p;
    p.columns[0] = {1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)};
    p.columns[1] = {2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)};
    p.columns[2] = {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)};
    p.offset = {normal(random), normal(random), normal(random)};
    return p;
}

// A flat hinge in the plane z = 0 of its own frame: edge x2 = (0, 0), x3 = (length, 0); x0 at
// distance h0 on one side, x1 at distance h1 on the other (the side that makes the dihedral angle
// 0), then placed.
struct FlatHinge {
    std::array<Vec3d, 4> x;  // placed
    std::array<Vec3d, 4> local;
    double h0, h1;
};

FlatHinge random_flat_hinge(std::mt19937_64& random) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    FlatHinge h;
    const double length = 0.005 + 0.03 * uniform(random);
    h.h0 = 0.003 + 0.03 * uniform(random);
    h.h1 = 0.003 + 0.03 * uniform(random);
    h.local = {Vec3d{length * (2.0 * uniform(random) - 0.5), -h.h0, 0.0},
               Vec3d{length * (2.0 * uniform(random) - 0.5), h.h1, 0.0}, Vec3d{0.0, 0.0, 0.0},
               Vec3d{length, 0.0, 0.0}};
    const Placement place = random_placement(random);
    for (std::size_t k = 0; k < 4; ++k) {
        h.x[k] = place.apply(h.local[k]);
    }
    return h;
}

// x rotated by angle about the line through a with unit direction axis (Rodrigues).
Vec3d rotate_about(const Vec3d& x, const Vec3d& a, const Vec3d& axis, double angle) {
    const Vec3d r = x - a;
    return a + r * std::cos(angle) + cross(axis, r) * std::sin(angle) +
           axis * (dot(axis, r) * (1.0 - std::cos(angle)));
}

TEST(IsometricBending, StencilIsTheAffineDependencyOfAFlatHinge) {
    std::mt19937_64 random(1);
    for (int i = 0; i < 1000; ++i) {
        const FlatHinge h = random_flat_hinge(random);
        ASSERT_NEAR(dihedral_angle_value(h.x[0], h.x[1], h.x[2], h.x[3]), 0.0, 1e-9);
        const auto stencil = isometric_bending_stencil(h.x[0], h.x[1], h.x[2], h.x[3]);
        ASSERT_TRUE(stencil.has_value()) << i;
        const std::array<double, 4>& k = *stencil;
        // The wings' weights: one over their distance from the edge's line.
        EXPECT_NEAR(k[0], 1.0 / h.h0, 1e-9 / h.h0) << i;
        EXPECT_NEAR(k[1], 1.0 / h.h1, 1e-9 / h.h1) << i;
        const double scale = std::abs(k[0]) + std::abs(k[1]) + std::abs(k[2]) + std::abs(k[3]);
        EXPECT_NEAR(k[0] + k[1] + k[2] + k[3], 0.0, 1e-13 * scale);
        // Σ K_k X_k = 0 in the hinge's own plane, and b = 0 at rest.
        Vec3d sum{0.0, 0.0, 0.0};
        for (std::size_t j = 0; j < 4; ++j) {
            sum += h.local[j] * k[j];
        }
        EXPECT_LT(norm(sum), 1e-12 * scale) << i;
        EXPECT_LT(norm(isometric_bending_vector(k, h.x[0], h.x[1], h.x[2], h.x[3])), 1e-11 * scale);
    }
}

TEST(IsometricBending, RejectsBentFoldedAndDegenerateHinges) {
    std::mt19937_64 random(2);
    const FlatHinge h = random_flat_hinge(random);
    const Vec3d axis = (h.x[3] - h.x[2]) * (1.0 / norm(h.x[3] - h.x[2]));
    const auto bent = [&](double angle) {
        return isometric_bending_stencil(h.x[0], rotate_about(h.x[1], h.x[2], axis, angle), h.x[2],
                                         h.x[3]);
    };
    EXPECT_TRUE(bent(0.5 * ISOMETRIC_FLAT_ANGLE).has_value());
    EXPECT_TRUE(bent(-0.5 * ISOMETRIC_FLAT_ANGLE).has_value());
    EXPECT_FALSE(bent(2.0 * ISOMETRIC_FLAT_ANGLE).has_value());
    EXPECT_FALSE(bent(0.3).has_value());
    EXPECT_FALSE(bent(std::numbers::pi).has_value());  // folded flat: both wings on one side
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_FALSE(isometric_bending_stencil(h.x[0], h.x[1], h.x[2], h.x[2]).has_value());
    EXPECT_FALSE(isometric_bending_stencil(h.x[2], h.x[1], h.x[2], h.x[3]).has_value());
    EXPECT_FALSE(isometric_bending_stencil(h.x[0], (h.x[2] + h.x[3]) * 0.5, h.x[2], h.x[3])
                     .has_value());  // zero-area wing
    EXPECT_FALSE(
        isometric_bending_stencil(h.x[0], Vec3d{nan, 0.0, 0.0}, h.x[2], h.x[3]).has_value());
}

TEST(IsometricBending, RigidAndAffineMotionsDoNotBendAndAFoldGivesTwoSinHalfTheAngle) {
    std::mt19937_64 random(3);
    for (int i = 0; i < 200; ++i) {
        const FlatHinge h = random_flat_hinge(random);
        const std::array<double, 4> k = *isometric_bending_stencil(h.x[0], h.x[1], h.x[2], h.x[3]);
        const double scale = std::abs(k[0]) + std::abs(k[1]) + std::abs(k[2]) + std::abs(k[3]);
        // A rigid motion, and an in-plane stretch and shear of the rest hinge: b stays 0.
        const Placement move = random_placement(random);
        std::array<Vec3d, 4> y;
        std::array<Vec3d, 4> z;
        for (std::size_t j = 0; j < 4; ++j) {
            y[j] = move.apply(h.x[j]);
            const Vec3d& l = h.local[j];
            z[j] = move.apply(Vec3d{1.3 * l.x + 0.4 * l.y, 0.8 * l.y, 0.0});
        }
        EXPECT_LT(norm(isometric_bending_vector(k, y[0], y[1], y[2], y[3])), 1e-10 * scale);
        EXPECT_LT(norm(isometric_bending_vector(k, z[0], z[1], z[2], z[3])), 1e-10 * scale);
        // Folding wing B by θ about the edge: |b| = 2 sin(θ/2), along the wings' bisecting normal
        // (n̂_A + n̂_B), and the dihedral angle (an independent measure) is ±θ.
        const Vec3d axis = (h.x[3] - h.x[2]) * (1.0 / norm(h.x[3] - h.x[2]));
        for (const double angle : {1e-4, 0.1, 1.0, 2.0, 3.0}) {
            const Vec3d x1 = rotate_about(h.x[1], h.x[2], axis, angle);
            const Vec3d b = isometric_bending_vector(k, h.x[0], x1, h.x[2], h.x[3]);
            EXPECT_NEAR(norm(b), 2.0 * std::sin(0.5 * angle), 1e-9) << angle;
            EXPECT_NEAR(std::abs(dihedral_angle_value(h.x[0], x1, h.x[2], h.x[3])), angle, 1e-9);
            const Vec3d n_a = cross(h.x[2] - h.x[0], h.x[3] - h.x[0]);
            const Vec3d n_b = cross(h.x[3] - x1, h.x[2] - x1);
            const Vec3d bisector = n_a * (1.0 / norm(n_a)) + n_b * (1.0 / norm(n_b));
            EXPECT_LT(norm(cross(b, bisector)), 1e-9 * norm(b) * norm(bisector)) << angle;
        }
    }
}

// n hinges on disjoint vertices, flat at rest (stencils from there), then deformed: wing B
// folded by up to ±largest_fold rad, every vertex moved by up to `jitter` m on each axis, some
// pinned, some fully pinned.
struct Hinges {
    std::vector<PackedVertex> x;
    std::vector<std::int32_t> v[4];
    std::vector<double> k[4];
    detail::IsometricBendingColumns columns() const {
        return {v[0].data(), v[1].data(), v[2].data(), v[3].data(),
                k[0].data(), k[1].data(), k[2].data(), k[3].data()};
    }
};

Hinges random_hinges(int n, std::uint64_t seed, double largest_fold, double jitter) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Hinges hinges;
    for (int i = 0; i < n; ++i) {
        const FlatHinge h = random_flat_hinge(random);
        const std::array<double, 4> k = *isometric_bending_stencil(h.x[0], h.x[1], h.x[2], h.x[3]);
        const Vec3d axis = (h.x[3] - h.x[2]) * (1.0 / norm(h.x[3] - h.x[2]));
        std::array<Vec3d, 4> x = h.x;
        x[1] = rotate_about(x[1], x[2], axis, largest_fold * uniform(random));
        for (Vec3d& p : x) {
            p += Vec3d{uniform(random), uniform(random), uniform(random)} * jitter;
        }
        for (std::size_t j = 0; j < 4; ++j) {
            double w = 1.0 + uniform(random);
            if ((i % 7 == 3 && j == 0) || i % 13 == 6) {
                w = 0.0;  // pinned
            }
            hinges.v[j].push_back(static_cast<std::int32_t>(hinges.x.size()));
            hinges.x.push_back({x[j].x, x[j].y, x[j].z, w});
            hinges.k[j].push_back(k[j]);
        }
    }
    return hinges;
}

Vec3d at(const PackedVertex& p) {
    return {p.x, p.y, p.z};
}

TEST(IsometricBending, KernelMatchesAReferenceProjection) {
    Hinges h = random_hinges(257, 4, 2.5, 1e-3);
    const std::vector<PackedVertex> start = h.x;
    std::vector<PackedVertex> expected = h.x;
    const double alpha = 3e-3;
    detail::project_isometric_bending(h.x.data(), h.columns(), 0, 257, alpha);
    int moved = 0;
    for (std::size_t i = 0; i < 257; ++i) {
        // C = n̂ · b, n = K_0 n_A + K_1 n_B; x_j += w_j K_j n̂ (−C / (Σ w K² + α)).
        std::array<Vec3d, 4> x;
        std::array<double, 4> k;
        double weight = 0.0;
        for (std::size_t j = 0; j < 4; ++j) {
            const PackedVertex& p = expected[static_cast<std::size_t>(h.v[j][i])];
            x[j] = at(p);
            k[j] = h.k[j][i];
            weight += p.inverse_mass * k[j] * k[j];
        }
        const Vec3d n =
            cross(x[2] - x[0], x[3] - x[0]) * k[0] + cross(x[3] - x[1], x[2] - x[1]) * k[1];
        const Vec3d normal = n * (1.0 / norm(n));
        const double c = dot(normal, isometric_bending_vector(k, x[0], x[1], x[2], x[3]));
        if (!(weight > 0.0)) {
            continue;
        }
        for (std::size_t j = 0; j < 4; ++j) {
            PackedVertex& p = expected[static_cast<std::size_t>(h.v[j][i])];
            const Vec3d dx = normal * (p.inverse_mass * k[j] * (-c / (weight + alpha)));
            p.x += dx.x;
            p.y += dx.y;
            p.z += dx.z;
        }
    }
    for (std::size_t i = 0; i < h.x.size(); ++i) {
        EXPECT_NEAR(h.x[i].x, expected[i].x, 1e-14) << i;
        EXPECT_NEAR(h.x[i].y, expected[i].y, 1e-14) << i;
        EXPECT_NEAR(h.x[i].z, expected[i].z, 1e-14) << i;
        moved += norm(at(h.x[i]) - at(start[i])) > 1e-6 ? 1 : 0;
        if (start[i].inverse_mass == 0.0) {
            // Pinned: not a bit changes.
            ASSERT_EQ(h.x[i].x, start[i].x);
            ASSERT_EQ(h.x[i].y, start[i].y);
            ASSERT_EQ(h.x[i].z, start[i].z);
        }
    }
    EXPECT_GT(moved, 600);  // the projections did something
}

TEST(IsometricBending, SmallBendsMoveAsTheDihedralConstraintDoes) {
    // Bent by up to 1e-3 rad, rest angle 0, rigid: the two kernels' moves agree to first order.
    Hinges iso = random_hinges(64, 5, 1e-3, 0.0);
    Hinges dihedral = iso;
    const std::vector<PackedVertex> start = iso.x;
    const std::vector<double> rest(64, 0.0);
    detail::project_isometric_bending(iso.x.data(), iso.columns(), 0, 64, 0.0);
    const detail::BendingColumns columns{dihedral.v[0].data(), dihedral.v[1].data(),
                                         dihedral.v[2].data(), dihedral.v[3].data(), rest.data()};
    detail::project_bending(dihedral.x.data(), columns, 0, 64, 0.0);
    double largest = 0.0;
    double worst = 0.0;
    for (std::size_t i = 0; i < start.size(); ++i) {
        const Vec3d moved = at(dihedral.x[i]) - at(start[i]);
        largest = std::max(largest, norm(moved));
        worst = std::max(worst, norm(at(iso.x[i]) - at(dihedral.x[i])));
    }
    EXPECT_GT(largest, 1e-7);
    EXPECT_LT(worst, 0.02 * largest);
}

TEST(IsometricBending, RigidProjectionRemovesTheBendToSecondOrder) {
    Hinges h = random_hinges(1, 6, 0.0, 0.0);
    for (PackedVertex& p : h.x) {
        p.inverse_mass = 1.0;
    }
    std::array<double, 4> k{h.k[0][0], h.k[1][0], h.k[2][0], h.k[3][0]};
    const auto bend = [&] {
        return norm(isometric_bending_vector(k, at(h.x[0]), at(h.x[1]), at(h.x[2]), at(h.x[3])));
    };
    const Vec3d axis = (at(h.x[3]) - at(h.x[2])) * (1.0 / norm(at(h.x[3]) - at(h.x[2])));
    const Vec3d x1 = rotate_about(at(h.x[1]), at(h.x[2]), axis, 0.05);
    h.x[1] = {x1.x, x1.y, x1.z, 1.0};
    const double before = bend();
    EXPECT_GT(before, 0.04);
    detail::project_isometric_bending(h.x.data(), h.columns(), 0, 1, 0.0);
    EXPECT_LT(bend(), before * before);
}

TEST(IsometricBending, ARigidProjectionUndoesAFoldOfUnequalWingsAtAnyAngle) {
    // b is linear and, for a fold of one wing, points along the wings' bisecting normal, which
    // n = K_0 n_A + K_1 n_B is for any wing heights: one projection with α = 0 brings b to 0.
    std::mt19937_64 random(8);
    int unequal = 0;
    for (int i = 0; i < 200; ++i) {
        const FlatHinge h = random_flat_hinge(random);
        unequal += std::max(h.h0, h.h1) > 2.0 * std::min(h.h0, h.h1) ? 1 : 0;
        const std::array<double, 4> k = *isometric_bending_stencil(h.x[0], h.x[1], h.x[2], h.x[3]);
        const Vec3d axis = (h.x[3] - h.x[2]) * (1.0 / norm(h.x[3] - h.x[2]));
        for (const double angle : {0.5, 1.5, 2.5, 3.0, 3.1}) {
            std::array<Vec3d, 4> x = h.x;
            x[1] = rotate_about(x[1], x[2], axis, angle);
            std::vector<PackedVertex> packed;
            for (const Vec3d& p : x) {
                packed.push_back({p.x, p.y, p.z, 1.0});
            }
            const std::int32_t v[4] = {0, 1, 2, 3};
            const detail::IsometricBendingColumns columns{&v[0], &v[1], &v[2], &v[3],
                                                          &k[0], &k[1], &k[2], &k[3]};
            detail::project_isometric_bending(packed.data(), columns, 0, 1, 0.0);
            const Vec3d b = isometric_bending_vector(k, at(packed[0]), at(packed[1]), at(packed[2]),
                                                     at(packed[3]));
            ASSERT_LT(norm(b), 1e-9) << i << " " << angle << " " << h.h0 / h.h1;
        }
    }
    EXPECT_GT(unequal, 50);
}

TEST(IsometricBending, VectorAndScalarKernelsGiveTheSameBits) {
    if (!has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this CPU";
    }
    // Every remainder of a range split, ranges that do not start at 0, and lanes the kernel must
    // skip: a hinge with all four vertices on one line (n = 0) and one with a NaN coordinate.
    Hinges hinges = random_hinges(257, 7, 2.5, 1e-3);
    for (std::size_t j = 0; j < 4; ++j) {
        hinges.x[static_cast<std::size_t>(hinges.v[j][9])] = {0.01 * static_cast<double>(j), 0.0,
                                                              0.0, 1.0};
    }
    hinges.x[static_cast<std::size_t>(hinges.v[1][10])].y =
        std::numeric_limits<double>::quiet_NaN();
    for (const auto& [begin, end] : std::vector<std::pair<std::int64_t, std::int64_t>>{{0, 0},
                                                                                       {0, 1},
                                                                                       {0, 3},
                                                                                       {0, 4},
                                                                                       {0, 5},
                                                                                       {0, 8},
                                                                                       {0, 130},
                                                                                       {0, 257},
                                                                                       {1, 6},
                                                                                       {3, 257},
                                                                                       {9, 11}}) {
        Hinges vector = hinges;
        Hinges scalar = hinges;
        detail::project_isometric_bending(vector.x.data(), vector.columns(), begin, end, 2.0);
        allow_avx2(false);
        detail::project_isometric_bending(scalar.x.data(), scalar.columns(), begin, end, 2.0);
        allow_avx2(true);
        const PackedVertex& line = vector.x[static_cast<std::size_t>(vector.v[0][9])];
        ASSERT_EQ(line.x, 0.0);  // the n = 0 hinge is skipped
        ASSERT_EQ(line.y, 0.0);
        for (std::size_t i = 0; i < vector.x.size(); ++i) {
            // Bitwise (NaN compared as NaN: its hinge is skipped, the NaN stays).
            ASSERT_EQ(std::memcmp(&vector.x[i], &scalar.x[i], sizeof(PackedVertex)), 0)
                << begin << " " << end << " " << i;
        }
    }
}

// A sheet of n × n quads of side 1 m, rolled onto a cylinder of radius `radius` along x for
// x > 0 (flat for x ≤ 0): flat and bent hinges.
geometry::TriangleMeshD half_rolled_sheet(int n, double radius) {
    geometry::TriangleMeshD mesh =
        geometry::convert_precision<double>(geometry::make_grid_sheet(n, n, 1.0F, 1.0F));
    for (Vec3d& p : mesh.positions) {
        if (p.x > 0.0) {
            const double angle = p.x / radius;
            p = {radius * std::sin(angle), p.y, radius * (1.0 - std::cos(angle))};
        }
    }
    return mesh;
}

TEST(IsometricBending, SolverUsesItOnFlatHingesAndTheDihedralConstraintOnTheOthers) {
    const geometry::TriangleMeshD mesh = half_rolled_sheet(12, 0.3);
    // Count the flat interior hinges independently.
    const geometry::MeshTopology topology =
        geometry::build_topology(mesh.triangles, mesh.positions.size());
    std::size_t hinges = 0;
    std::size_t flat = 0;
    for (std::int32_t e = 0; e < static_cast<std::int32_t>(topology.num_edges()); ++e) {
        const auto faces = topology.triangles_of_edge(e);
        if (faces.size() != 2) {
            continue;
        }
        ++hinges;
        Vec3d n[2];
        for (std::size_t f = 0; f < 2; ++f) {
            const geometry::Triangle& t = mesh.triangles[static_cast<std::size_t>(faces[f])];
            const Vec3d& a = mesh.positions[static_cast<std::size_t>(t[0])];
            n[f] = cross(mesh.positions[static_cast<std::size_t>(t[1])] - a,
                         mesh.positions[static_cast<std::size_t>(t[2])] - a);
            n[f] = n[f] * (1.0 / norm(n[f]));
        }
        flat += norm(cross(n[0], n[1])) < 1e-6 && dot(n[0], n[1]) > 0.0 ? 1 : 0;
    }
    ASSERT_GT(flat, hinges / 3);
    ASSERT_LT(flat, hinges);
    ClothMaterial material;
    material.bending = BendingModel::isometric;
    const ClothSolver isometric(mesh, material);
    EXPECT_EQ(isometric.num_bending_constraints(), hinges);
    EXPECT_EQ(isometric.num_isometric_bending_constraints(), flat);
    material.bending = BendingModel::dihedral;
    const ClothSolver dihedral(mesh, material);
    EXPECT_EQ(dihedral.num_bending_constraints(), hinges);
    EXPECT_EQ(dihedral.num_isometric_bending_constraints(), 0U);
}

TEST(IsometricBending, AMeshAtRestStaysAtRest) {
    // No gravity: every constraint is satisfied at rest (the isometric ones up to rounding).
    const geometry::TriangleMeshD mesh = half_rolled_sheet(10, 0.4);
    ClothMaterial material;
    material.bending = BendingModel::isometric;
    ClothSolver solver(mesh, material);
    ASSERT_GT(solver.num_isometric_bending_constraints(), 0U);
    solver.set_gravity({0.0, 0.0, 0.0});
    for (int s = 0; s < 5; ++s) {
        solver.step(1.0 / 24.0, 8);
    }
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        ASSERT_LT(norm(solver.positions()[v] - mesh.positions[v]), 1e-12) << v;
    }
}

}  // namespace
}  // namespace pliant::cloth
