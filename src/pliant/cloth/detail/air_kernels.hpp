// The air's drag on the cloth's triangles (air.hpp has the model): the force on triangles
// [begin, end), a scalar kernel per triangle and an AVX2 kernel for four triangles at a time
// (double precision, four lanes), chosen at run time. The AVX2 kernel does the scalar kernel's
// arithmetic lane by lane in the same order, without fma (core/simd_dispatch.hpp), and the gust's
// sine is std::sin of each lane's phase: the results are bitwise those of the scalar kernel, which
// are those of Air::wind_at and the formula in air.hpp evaluated term by term.
//
// Per-element kernels: no allocation, no exceptions; calls on disjoint ranges may run in parallel.
#pragma once

#include <array>
#include <cstdint>

#include "pliant/cloth/air.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

// What a substep's air needs per triangle, derived once per substep (bitwise the terms
// Air::wind_at evaluates per call).
struct AirTerms {
    double density = 0.0;           // kg/m³
    double drag_coefficient = 0.0;  // unitless
    Vec3d wind{0.0, 0.0, 0.0};      // m/s
    bool has_gusts = false;         // gust_amplitude > 0 and |wind| > 0
    double wind_speed = 0.0;        // |wind|, m/s
    double gust_amplitude = 0.0;
    double time_phase = 0.0;       // t / gust_period
    double gust_wavelength = 1.0;  // m
    double areal_density = 0.0;    // kg/m²
    double h = 1.0;                // the substep, s
};
AirTerms air_terms(const Air& air, double areal_density, double h, double t);

// forces[i] = the drag on triangle i (N) for i in [begin, end): triangles index positions and
// velocities; a triangle of zero area feels none.
void triangle_air_forces(const Vec3d* positions, const Vec3d* velocities,
                         const std::array<std::int32_t, 3>* triangles, std::int64_t begin,
                         std::int64_t end, const AirTerms& terms, Vec3d* forces);

}  // namespace pliant::cloth::detail
