#include "pliant/cloth/detail/air_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pliant/core/simd_dispatch.hpp"

// pliant is compiled with -ffp-contract=off (cmake/PliantCodegen.cmake): no a · b + c is contracted
// in the scalar kernel, and the AVX2 kernel uses no fma.
#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

#include "pliant/core/simd_avx2.hpp"
#endif

namespace pliant::cloth::detail {
namespace {

constexpr double TWO_PI = 2.0 * std::numbers::pi;
constexpr double THIRD = 1.0 / 3.0;

// The triangle's drag, air.hpp's formula in Air::wind_at's order of operations.
Vec3d triangle_force(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& va,
                     const Vec3d& vb, const Vec3d& vc, const AirTerms& terms) {
    const Vec3d area_normal = cross(b - a, c - a) * 0.5;  // |.| = area
    const double area = norm(area_normal);
    if (!(area > 0.0)) {
        return {0.0, 0.0, 0.0};
    }
    const Vec3d velocity = (va + vb + vc) * THIRD;
    const Vec3d normal = area_normal * (1.0 / area);
    Vec3d wind = terms.wind;
    if (terms.has_gusts) {
        const Vec3d centre = (a + b + c) * THIRD;
        const double along = dot(centre, terms.wind) / terms.wind_speed;
        const double phase = TWO_PI * (terms.time_phase - along / terms.gust_wavelength);
        wind = terms.wind * (1.0 + terms.gust_amplitude * std::sin(phase));
    }
    const double u_n = dot(velocity - wind, normal);
    // Drag can at most stop the relative motion within the substep: the impulse is capped at the
    // triangle's momentum normal to it (explicit quadratic drag would overshoot and blow up once
    // h ρ C_d |u·n| / areal_density > 2).
    const double drag = 0.5 * terms.density * terms.drag_coefficient * area * u_n * u_n;
    const double stopping = terms.areal_density * area * std::abs(u_n) / terms.h;
    return normal * (-std::copysign(std::min(drag, stopping), u_n));
}

#if defined(PLIANT_HAS_AVX2_TARGET)

using simd::add;
using simd::div;
using simd::mul;
using simd::select;
using simd::set1;
using simd::sub;
using V = __m256d;

struct Vec4 {
    V x, y, z;
};

PLIANT_AVX2_INLINE Vec4 sub(const Vec4& a, const Vec4& b) {
    return {sub(a.x, b.x), sub(a.y, b.y), sub(a.z, b.z)};
}
PLIANT_AVX2_INLINE Vec4 add(const Vec4& a, const Vec4& b) {
    return {add(a.x, b.x), add(a.y, b.y), add(a.z, b.z)};
}
PLIANT_AVX2_INLINE Vec4 scale(const Vec4& a, V s) {
    return {mul(a.x, s), mul(a.y, s), mul(a.z, s)};
}
PLIANT_AVX2_INLINE V dot(const Vec4& a, const Vec4& b) {
    return add(add(mul(a.x, b.x), mul(a.y, b.y)), mul(a.z, b.z));
}
PLIANT_AVX2_INLINE Vec4 cross(const Vec4& a, const Vec4& b) {
    return {sub(mul(a.y, b.z), mul(a.z, b.y)), sub(mul(a.z, b.x), mul(a.x, b.z)),
            sub(mul(a.x, b.y), mul(a.y, b.x))};
}
PLIANT_AVX2_INLINE Vec4 broadcast(const Vec3d& a) {
    return {set1(a.x), set1(a.y), set1(a.z)};
}

// Corner `corner` of triangles t[0..3], lane l = triangle l.
PLIANT_AVX2_INLINE Vec4 gather(const Vec3d* p, const std::array<std::int32_t, 3>* t, int corner) {
    const Vec3d& p0 = p[t[0][static_cast<std::size_t>(corner)]];
    const Vec3d& p1 = p[t[1][static_cast<std::size_t>(corner)]];
    const Vec3d& p2 = p[t[2][static_cast<std::size_t>(corner)]];
    const Vec3d& p3 = p[t[3][static_cast<std::size_t>(corner)]];
    return {_mm256_set_pd(p3.x, p2.x, p1.x, p0.x), _mm256_set_pd(p3.y, p2.y, p1.y, p0.y),
            _mm256_set_pd(p3.z, p2.z, p1.z, p0.z)};
}

// Four triangles from t: triangle_force lane by lane (std::sin per lane).
PLIANT_AVX2_FN void four_forces(const Vec3d* positions, const Vec3d* velocities,
                                const std::array<std::int32_t, 3>* t, const AirTerms& terms,
                                Vec3d* forces) {
    const Vec4 a = gather(positions, t, 0);
    const Vec4 b = gather(positions, t, 1);
    const Vec4 c = gather(positions, t, 2);
    const V zero = _mm256_setzero_pd();
    const Vec4 area_normal = scale(cross(sub(b, a), sub(c, a)), set1(0.5));
    const V area = _mm256_sqrt_pd(dot(area_normal, area_normal));
    const V has_area = _mm256_cmp_pd(area, zero, _CMP_GT_OQ);
    const V third = set1(THIRD);
    const Vec4 velocity = scale(
        add(add(gather(velocities, t, 0), gather(velocities, t, 1)), gather(velocities, t, 2)),
        third);
    const Vec4 normal = scale(area_normal, div(set1(1.0), area));
    Vec4 wind = broadcast(terms.wind);
    if (terms.has_gusts) {
        const Vec4 centre = scale(add(add(a, b), c), third);
        const V along = div(dot(centre, wind), set1(terms.wind_speed));
        const V phase =
            mul(set1(TWO_PI), sub(set1(terms.time_phase), div(along, set1(terms.gust_wavelength))));
        alignas(32) double lanes[4];
        _mm256_store_pd(lanes, phase);
        for (double& lane : lanes) {
            lane = std::sin(lane);
        }
        const V gust = add(set1(1.0), mul(set1(terms.gust_amplitude), _mm256_load_pd(lanes)));
        wind = scale(wind, gust);
    }
    const V u_n = dot(sub(velocity, wind), normal);
    const V sign_bit = set1(-0.0);
    const V abs_u_n = _mm256_andnot_pd(sign_bit, u_n);
    const V drag =
        mul(mul(mul(mul(set1(0.5 * terms.density), set1(terms.drag_coefficient)), area), u_n), u_n);
    const V stopping = div(mul(mul(set1(terms.areal_density), area), abs_u_n), set1(terms.h));
    // std::min(drag, stopping) = stopping < drag ? stopping : drag.
    const V smaller = _mm256_min_pd(stopping, drag);
    // −copysign(smaller, u_n): smaller's magnitude with the opposite of u_n's sign.
    const V magnitude = _mm256_xor_pd(
        _mm256_or_pd(_mm256_andnot_pd(sign_bit, smaller), _mm256_and_pd(sign_bit, u_n)), sign_bit);
    const V s = select(has_area, magnitude, zero);
    // normal · s; a lane without area gets exact zeros (its normal may be NaN).
    const Vec4 force = {select(has_area, mul(normal.x, s), zero),
                        select(has_area, mul(normal.y, s), zero),
                        select(has_area, mul(normal.z, s), zero)};
    alignas(32) double fx[4];
    alignas(32) double fy[4];
    alignas(32) double fz[4];
    _mm256_store_pd(fx, force.x);
    _mm256_store_pd(fy, force.y);
    _mm256_store_pd(fz, force.z);
    for (int l = 0; l < 4; ++l) {
        forces[l] = {fx[l], fy[l], fz[l]};
    }
}

PLIANT_AVX2_FN std::int64_t triangle_air_forces_avx2(const Vec3d* positions,
                                                     const Vec3d* velocities,
                                                     const std::array<std::int32_t, 3>* triangles,
                                                     std::int64_t begin, std::int64_t end,
                                                     const AirTerms& terms, Vec3d* forces) {
    std::int64_t i = begin;
    for (; i + 4 <= end; i += 4) {
        four_forces(positions, velocities, triangles + i, terms, forces + i);
    }
    return i;
}

#endif  // PLIANT_HAS_AVX2_TARGET

}  // namespace

AirTerms air_terms(const Air& air, double areal_density, double h, double t) {
    AirTerms terms;
    terms.density = air.density;
    terms.drag_coefficient = air.drag_coefficient;
    terms.wind = air.wind;
    terms.wind_speed = norm(air.wind);
    terms.has_gusts = air.gust_amplitude > 0.0 && terms.wind_speed > 0.0;
    terms.gust_amplitude = air.gust_amplitude;
    terms.time_phase = t / air.gust_period;
    terms.gust_wavelength = air.gust_wavelength;
    terms.areal_density = areal_density;
    terms.h = h;
    return terms;
}

void triangle_air_forces(const Vec3d* positions, const Vec3d* velocities,
                         const std::array<std::int32_t, 3>* triangles, std::int64_t begin,
                         std::int64_t end, const AirTerms& terms, Vec3d* forces) {
    std::int64_t i = begin;
#if defined(PLIANT_HAS_AVX2_TARGET)
    if (has_avx2()) {
        i = triangle_air_forces_avx2(positions, velocities, triangles, begin, end, terms, forces);
    }
#endif
    for (; i < end; ++i) {
        const std::array<std::int32_t, 3>& t = triangles[i];
        const auto at = [](const Vec3d* p, std::int32_t v) {
            return p[static_cast<std::size_t>(v)];
        };
        forces[i] =
            triangle_force(at(positions, t[0]), at(positions, t[1]), at(positions, t[2]),
                           at(velocities, t[0]), at(velocities, t[1]), at(velocities, t[2]), terms);
    }
}

}  // namespace pliant::cloth::detail
