// The rest lengths and volumes of wave-displaced rest positions (driver_apply.hpp, the waves'
// rest state), in float: a vertex's rest position r and its displacement u (the sum of the
// waves, rounded to float once per vertex) enter every difference as (r_a − r_b) + (u_a − u_b),
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

// The difference of two displaced points, (r_a − r_b) + (u_a − u_b) per component.
inline Vec3f displaced_difference(const Vec3f& ra, const Vec3f& ua, const Vec3f& rb,
                                  const Vec3f& ub) {
    return {(ra.x - rb.x) + (ua.x - ub.x), (ra.y - rb.y) + (ua.y - ub.y),
            (ra.z - rb.z) + (ua.z - ub.z)};
}

// |d| of an edge's displaced difference d: sqrt((dx² + dy²) + dz²).
inline float displaced_length(const Vec3f& ra, const Vec3f& ua, const Vec3f& rb, const Vec3f& ub) {
    const Vec3f d = displaced_difference(ra, ua, rb, ub);
    return std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
}

// The signed volume e1 · (e2 × e3) / 6 of a tet's displaced vertices, e_i the displaced
// difference of vertex i and vertex 0, the dot product summed x, y, z.
inline float displaced_volume(const Vec3f* r, const Vec3f* u) {
    const Vec3f e1 = displaced_difference(r[1], u[1], r[0], u[0]);
    const Vec3f e2 = displaced_difference(r[2], u[2], r[0], u[0]);
    const Vec3f e3 = displaced_difference(r[3], u[3], r[0], u[0]);
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
// last ending at constraint `total`): displaced_length of each edge into rest_lengths, indexed by
// the constraints' colour-order index.
void displaced_lengths_runs_avx2(const SoaDisplaced& p, const LatticeRun* runs, std::int64_t r0,
                                 std::int64_t r1, std::int64_t num_runs, std::int64_t total,
                                 float* rest_lengths);
// The same for tets: displaced_volume into rest_volumes.
void displaced_volumes_runs_avx2(const SoaDisplaced& p, const LatticeRun* runs, std::int64_t r0,
                                 std::int64_t r1, std::int64_t num_runs, std::int64_t total,
                                 float* rest_volumes);

}  // namespace pliant::pbd::detail
