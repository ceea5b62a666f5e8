#include "pliant/cloth/detail/air_kernels.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "pliant/core/simd_dispatch.hpp"

namespace pliant::cloth::detail {
namespace {

struct Triangles {
    std::vector<Vec3d> positions;
    std::vector<Vec3d> velocities;
    std::vector<std::array<std::int32_t, 3>> triangles;
};

// Random triangles over shared vertices, one of zero area, one with all velocities zero.
Triangles random_triangles(int count, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Triangles t;
    const int num_vertices = count + 2;
    for (int v = 0; v < num_vertices; ++v) {
        t.positions.push_back({uniform(random), uniform(random), uniform(random)});
        t.velocities.push_back({3.0 * uniform(random), 3.0 * uniform(random), uniform(random)});
    }
    std::uniform_int_distribution<std::int32_t> vertex(0, num_vertices - 1);
    for (int i = 0; i < count; ++i) {
        t.triangles.push_back({vertex(random), vertex(random), vertex(random)});
    }
    if (count > 5) {
        t.triangles[5] = {1, 1, 2};  // zero area
    }
    return t;
}

// air.hpp's formula, term by term through Air::wind_at: the reference.
Vec3d reference_force(const Triangles& t, std::size_t i, const Air& air, double areal_density,
                      double h, double time) {
    const auto& tri = t.triangles[i];
    const Vec3d& a = t.positions[static_cast<std::size_t>(tri[0])];
    const Vec3d& b = t.positions[static_cast<std::size_t>(tri[1])];
    const Vec3d& c = t.positions[static_cast<std::size_t>(tri[2])];
    const Vec3d area_normal = cross(b - a, c - a) * 0.5;
    const double area = norm(area_normal);
    if (!(area > 0.0)) {
        return {0.0, 0.0, 0.0};
    }
    const Vec3d velocity = (t.velocities[static_cast<std::size_t>(tri[0])] +
                            t.velocities[static_cast<std::size_t>(tri[1])] +
                            t.velocities[static_cast<std::size_t>(tri[2])]) *
                           (1.0 / 3.0);
    const Vec3d centre = (a + b + c) * (1.0 / 3.0);
    const Vec3d normal = area_normal * (1.0 / area);
    const double u_n = dot(velocity - air.wind_at(centre, time), normal);
    const double drag = 0.5 * air.density * air.drag_coefficient * area * u_n * u_n;
    const double stopping = areal_density * area * std::abs(u_n) / h;
    return normal * (-std::copysign(std::min(drag, stopping), u_n));
}

bool same_bits(const Vec3d& a, const Vec3d& b) {
    return std::memcmp(&a, &b, sizeof(Vec3d)) == 0;
}

Air gusty_air() {
    Air air;
    air.density = 1.2;
    air.drag_coefficient = 1.1;
    air.wind = {8.0, 1.5, -0.5};
    air.gust_amplitude = 0.5;
    air.gust_period = 0.8;
    air.gust_wavelength = 1.5;
    return air;
}

TEST(AirKernels, ForcesAreTheFormulaOfAirHppBitForBit) {
    const Triangles t = random_triangles(203, 3);
    Air still = gusty_air();
    still.gust_amplitude = 0.0;
    Air calm = gusty_air();
    calm.wind = {0.0, 0.0, 0.0};
    for (const Air& air : {gusty_air(), still, calm}) {
        // A small areal density makes the stopping cap bind for the fast triangles.
        for (const double areal_density : {0.1, 0.001}) {
            const double h = 1.0 / 960.0;
            const double time = 2.37;
            const AirTerms terms = air_terms(air, areal_density, h, time);
            std::vector<Vec3d> forces(t.triangles.size(), Vec3d{7.0, 7.0, 7.0});
            triangle_air_forces(t.positions.data(), t.velocities.data(), t.triangles.data(), 0,
                                static_cast<std::int64_t>(t.triangles.size()), terms,
                                forces.data());
            for (std::size_t i = 0; i < forces.size(); ++i) {
                const Vec3d expected = reference_force(t, i, air, areal_density, h, time);
                ASSERT_TRUE(same_bits(forces[i], expected))
                    << "triangle " << i << ": " << forces[i].x << " against " << expected.x;
            }
            EXPECT_TRUE(same_bits(forces[5], {0.0, 0.0, 0.0}));
        }
    }
}

TEST(AirKernels, VectorAndScalarKernelsGiveTheSameBits) {
    if (!has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this CPU";
    }
    const Triangles t = random_triangles(131, 9);
    const AirTerms terms = air_terms(gusty_air(), 0.1, 1.0 / 960.0, 0.41);
    // Ranges with every remainder of four and starts off a multiple of four.
    for (const auto& [begin, end] :
         {std::array<std::int64_t, 2>{0, 131}, {3, 130}, {1, 4}, {6, 6}}) {
        std::vector<Vec3d> vector(t.triangles.size(), Vec3d{7.0, 7.0, 7.0});
        std::vector<Vec3d> scalar = vector;
        triangle_air_forces(t.positions.data(), t.velocities.data(), t.triangles.data(), begin, end,
                            terms, vector.data());
        allow_avx2(false);
        triangle_air_forces(t.positions.data(), t.velocities.data(), t.triangles.data(), begin, end,
                            terms, scalar.data());
        allow_avx2(true);
        for (std::size_t i = 0; i < vector.size(); ++i) {
            ASSERT_TRUE(same_bits(vector[i], scalar[i])) << "triangle " << i;
        }
    }
}

}  // namespace
}  // namespace pliant::cloth::detail
