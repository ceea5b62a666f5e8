// The rest lengths and volumes of wave-displaced rest positions (driver_apply.hpp, the waves'
// rest state), in float: a vertex's rest position r and its displacement u (the sum of the
// waves, rounded to float once per vertex) enter every difference as (r_a − r_b) + (u_a − u_b)
// (along the axes the waves displace; r_a − r_b along the others, where u is 0),
// so that the displacement's rounding never swamps an edge of the lattice. Scalar formulas, and
// their AVX2 versions over the lattice sweep's runs (lattice_sweep.hpp), 8 constraints at a time
// with the same arithmetic lane by lane, in the same order and without FMA contraction: the two
// give the same bits, so the choice (pliant::has_avx2(), a grid or not) never changes a result.
// World units.
#pragma once

#include <cmath>
#include <cstdint>

#include "pliant/core/vec3.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"

namespace pliant::pbd::detail {

// The axes some wave displaces along: bit a set for axis a (0 x, 1 y, 2 z). Along the others u
// is 0 and the formulas below leave it out (r_a − r_b alone).

// The difference of two displaced points: per component (r_a − r_b) + (u_a − u_b) along the
// displaced axes, r_a − r_b along the others.
inline Vec3f displaced_difference(const Vec3f& ra, const Vec3f& ua, const Vec3f& rb,
                                  const Vec3f& ub, int axes) {
    Vec3f d{};
    for (int c = 0; c < 3; ++c) {
        d[c] = (axes >> c & 1) != 0 ? (ra[c] - rb[c]) + (ua[c] - ub[c]) : ra[c] - rb[c];
    }
    return d;
}

// |d| of an edge's displaced difference d: sqrt((dx² + dy²) + dz²).
inline float displaced_length(const Vec3f& ra, const Vec3f& ua, const Vec3f& rb, const Vec3f& ub,
                              int axes) {
    const Vec3f d = displaced_difference(ra, ua, rb, ub, axes);
    return std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
}

// The signed volume e1 · (e2 × e3) / 6 of a tet's displaced vertices, e_i the displaced
// difference of vertex i and vertex 0, the dot product summed x, y, z.
inline float displaced_volume(const Vec3f* r, const Vec3f* u, int axes) {
    const Vec3f e1 = displaced_difference(r[1], u[1], r[0], u[0], axes);
    const Vec3f e2 = displaced_difference(r[2], u[2], r[0], u[0], axes);
    const Vec3f e3 = displaced_difference(r[3], u[3], r[0], u[0], axes);
    const float cx = e2.y * e3.z - e2.z * e3.y;
    const float cy = e2.z * e3.x - e2.x * e3.z;
    const float cz = e2.x * e3.y - e2.y * e3.x;
    return (e1.x * cx + e1.y * cy + e1.z * cz) / 6.0f;
}

// Rest positions r and displacements u as six arrays, indexed by the lattice sweep's solver index,
// each with 8 floats after the last vertex (read, never used: the kernels load 8 lanes at a time).
struct SoaDisplaced {
    const float* rx = nullptr;
    const float* ry = nullptr;
    const float* rz = nullptr;
    const float* ux = nullptr;
    const float* uy = nullptr;
    const float* uz = nullptr;
};

// The constraints of runs [r0, r1) of `runs` (all colours' runs in order, num_runs of them, the
// last ending at constraint `total`): displaced_length of each edge with `axes` into
// rest_lengths, indexed by the constraints' colour-order index (u read only along `axes`).
void displaced_lengths_runs_avx2(const SoaDisplaced& p, int axes, const LatticeRun* runs,
                                 std::int64_t r0, std::int64_t r1, std::int64_t num_runs,
                                 std::int64_t total, float* rest_lengths);
// The same for tets: displaced_volume into rest_volumes.
void displaced_volumes_runs_avx2(const SoaDisplaced& p, int axes, const LatticeRun* runs,
                                 std::int64_t r0, std::int64_t r1, std::int64_t num_runs,
                                 std::int64_t total, float* rest_volumes);

}  // namespace pliant::pbd::detail
