// Continuous collision detection (CCD) for the two narrow-phase primitives over one time step:
// does a vertex touch a triangle, or an edge touch an edge, while every endpoint moves on a
// straight line from its position at t = 0 to its position at t = 1? Conservative: a contact is
// never missed; the earliest time of impact is returned as a lower bound.
//
//   const CcdResult r = vertex_face_ccd(v0, a0, b0, c0, v1, a1, b1, c1);
//   if (r.hit) { /* no contact before r.toi: advance the step to at most r.toi */ }
//
// Method: inclusion-based root finding in the spirit of Tight-Inclusion. Every point moves as
// x(t) = (1 - t) x_t0 + t x_t1, and a contact is a zero (or, with a minimum separation δ, a point
// inside [-δ, δ]³) of the co-domain function over the parameter box B = [0, 1]³:
//   vertex-face  F = v(t) - [(1 - u - v) f0(t) + u f1(t) + v f2(t)],  u, v >= 0, u + v <= 1
//   edge-edge    F = [ea0(t) + u (ea1(t) - ea0(t))] - [eb0(t) + v (eb1(t) - eb0(t))]
// F is affine in each of t, u, v separately (multilinear), so on any sub-box its range lies in the
// convex hull of its values at the box's 8 corners; so does the range of any projection n · F
// (a linear combination of multilinear functions is multilinear). A box is discarded when, along
// some axis or along one of two separating directions n and m, all 8 corner values, widened by a
// rigorous bound on their floating-point error, lie above the separation or all lie below minus
// it; a vertex-face box is also discarded when u_lo + v_lo > 1 (it holds no point of the
// triangle).
//
// The separating directions come from the positions at mid-step: with a and b the two direction
// vectors of the pair (the two edges, or the face's f1 - f0 and f2 - f0; a the longer), n is the
// unit normal of both (a × b), or any unit normal of a when they are within 1e-6 rad of parallel,
// and m = â × n. n · F is then nearly independent of u and v (for a face: the vertex's distance
// to the plane), and m · F nearly independent of u. They matter when the axes cannot separate a
// box because F is nearly zero along a whole curve of (u, v): edges lying along each other (a
// folded or stacked cloth), a zero-area face; the axes would then need O(1 / tolerance) boxes
// along the curve. The whole-step and slab tests below also use the in-plane normals e × n of
// the pair's other edges (b; for a face also f2 - f1), which separate coplanar neighbours in a
// flat cloth.
//
// The search:
//   1. The whole step at once, along the axes and then along n and m: F is bilinear in t and the
//      feature parameters, so over a slab of time and all of the features its range lies between
//      its values at the slab's two ends at the features' corners (for a face its 3 vertices,
//      tighter than the (u, v) square); most pairs from a broad phase end here.
//   2. t alone: the same slab test, first at the instant t = 0 (when it survives, the search
//      starts at 0), then bisecting t, earlier slabs first, dropping excluded slabs, until a
//      surviving slab is within tolerance wide; no contact precedes its start.
//   3. best-first over [start, 1] × [0, 1]²: always refine the open box with the smallest t_lo
//      (ties: the deepest). Refining a box first tries its two t-halves and goes on with the
//      survivor when one is discarded; otherwise it bisects the dimension along which the corner
//      values vary most.
//   A surviving slab or box is terminal, ending the search with a hit at toi = its t_lo, when its
//   three widths are all at most `tolerance`, or when its values span at most
//   tolerance × (F's range over the step) on every axis: then at toi the features are within
//   δ + that span (+ rounding) of each other, and refining further would only sharpen a contact
//   that is certain up to that span.
//
// Why it is conservative
//   - The hull argument is exact for multilinear F: a box discarded in exact arithmetic holds no
//     contact. Corner parameters are dyadic (k / 2^level) and hence exact doubles.
//   - Each corner value is computed as lerps p0 + t (p1 - p0) followed by the differences and
//     u-, v-products above: at most 7 roundings deep, with an absolute-value evaluation of at most
//     18 M_axis, where M_axis is the largest |coordinate| of the 8 inputs on that axis. By the
//     standard bound (Higham, Accuracy and Stability of Numerical Algorithms, §3.1) the error is at
//     most γ_7 · 18 M_axis < 126.1 u M_axis (u = 2^-53); the code uses err_axis = 2^-45 M_axis =
//     256 u M_axis, plus 64 · 2^-1074 for underflow. The comparisons lo - err > δ and
//     hi + err < -δ are made on rounded results, which is safe because rounding is monotone and δ
//     is a double.
//   - A projection (n0 F0 + n1 F1) + n2 F2 of computed corner values F~ is within
//     Σ |n_i| (err_i + γ_3 max|F~_i|) of the exact n · F (γ_3 < 2^-50 is used), plus the same
//     underflow term; the bound is rounded up by a factor 1 + 2^-40. Inside the contact box [-δ,
//     δ]³, |n · F| <= δ ‖n‖₁, so the separation along n is δ ‖n‖₁ (rounded up). Any direction n is
//     sound; the choice above only decides how fast boxes are discarded.
//   - Discarded boxes hold no contact and the open boxes cover the rest of [0, 1]³. Step 2 only
//     drops discarded slabs before `start`. A slab's end points are lerps start + t displacement
//     (the inputs themselves at t = 0 and 1), within 5.1 u M_axis of exact; a difference of two
//     is within 12.2 u M_axis < err_axis, and along n within 18.4 u Σ |n_i| M_i < 2^-48 Σ |n_i|
//     M_i, the bound used there. Children start no earlier in t than their parent, so when a box is
//     popped no unexplored contact precedes its t_lo: the returned toi is at most the true earliest
//     contact time.
//   - When the iteration limit is hit the query reports a hit with toi = the smallest t_lo of any
//     box still unexplored, which is also a lower bound.
//
// What a false positive can be
//   - A near miss closer than the floating-point error bound (~2.8e-14 of the largest coordinate)
//     or than F's range over a tolerance-sized box. On the Sample-Queries erleben-* sets all
//     of them are pairs within ~1e-11 of touching, and their number does not change from
//     tolerance 1e-6 to 1e-10.
//   - With δ > 0 the test is the box [-δ, δ]³ around the contact (L∞), so a pair at Euclidean
//     distance up to √3 δ can be reported.
//   - A vertex-face box straddling the triangle's hypotenuse also covers points just beyond it
//     (u + v > 1), i.e. within about tolerance of the edge f1-f2.
//   - The iteration limit.
//
// Parameters and units
//   - Positions in any length unit; min_separation (δ) in the same unit, >= 0 (a negative or NaN
//     value is treated as 0). tolerance is a width in the unitless parameter space [0, 1]³,
//     clamped to [2^-40, 1] (NaN → the default). max_iterations bounds the evaluated boxes (values
//     below 1 act as 1); iterations counts evaluated boxes, the look-ahead halves included, so it
//     can exceed max_iterations by 2.
//   - toi ∈ [0, 1]: 1 when hit is false. With hit, no contact (within δ) happens before toi, and
//     at toi the features are within δ + tolerance × (F's range over the step) of each other or
//     within a tolerance-sized parameter box of such a point.
//   - Range: finite coordinates of magnitude below 1e300. Non-finite or larger inputs report a
//     conservative hit at toi = 0 without searching.
//   - Per-element kernel: no exceptions; thread safe. The open boxes live in a thread-local
//     vector reused across queries, so a query allocates only when its search outgrows every
//     earlier one on that thread. Cost: one or two slab tests (~0.1 µs) for most pairs a broad
//     phase reports; otherwise up to 2 log2(1 / tolerance) slabs for step 2 and about
//     3 log2(1 / tolerance) boxes along the path to a hit, plus the boxes of near misses: 0.1-12 µs
//     per query on average over the Sample-Queries and cloth-funnel sets (docs/performance.md);
//     bounded by max_iterations.
//
// Reference: B. Wang, Z. Ferguson, T. Schneider, X. Jiang, M. Attene, D. Panozzo, "A Large-scale
// Benchmark and an Inclusion-based Algorithm for Continuous Collision Detection", ACM TOG 40(5),
// 2021 (Tight-Inclusion). Differences: the error bound is a fixed a-priori γ-bound per axis rather
// than the paper's filters; boxes are also tested along the two separating directions; the
// co-domain tolerance is relative to F's range over the step rather than an absolute length, so
// results do not depend on the length unit; the search starts with slab tests in t alone; the
// split dimension is the one along which the corner values vary most, after a t-half look-ahead;
// the search is best-first by t_lo instead of breadth-first.
#pragma once

#include "pliant/core/vec3.hpp"

namespace pliant::collision {

struct CcdOptions {
    double min_separation = 0.0;  // δ, world units: a contact is a pair closer than δ (L∞ box)
    double tolerance = 1e-6;      // parameter-space width of a terminal box, unitless
    int max_iterations = 1'000'000;  // evaluated boxes before a conservative hit is reported
};

struct CcdResult {
    bool hit;                  // a contact within δ cannot be excluded in t ∈ [0, 1]
    double toi;                // earliest time in [0, 1] a contact cannot be excluded; 1 if !hit
    int iterations;            // boxes evaluated
    bool hit_iteration_limit;  // the search stopped at max_iterations (hit is then true)
};

// Vertex v against triangle (f0, f1, f2); _t0 / _t1 are the positions at the start / end of the
// step. See the header comment for the contract.
CcdResult vertex_face_ccd(const Vec3d& v_t0, const Vec3d& f0_t0, const Vec3d& f1_t0,
                          const Vec3d& f2_t0, const Vec3d& v_t1, const Vec3d& f0_t1,
                          const Vec3d& f1_t1, const Vec3d& f2_t1, const CcdOptions& options = {});

// Edge (ea0, ea1) against edge (eb0, eb1); _t0 / _t1 as above.
CcdResult edge_edge_ccd(const Vec3d& ea0_t0, const Vec3d& ea1_t0, const Vec3d& eb0_t0,
                        const Vec3d& eb1_t0, const Vec3d& ea0_t1, const Vec3d& ea1_t1,
                        const Vec3d& eb0_t1, const Vec3d& eb1_t1, const CcdOptions& options = {});

}  // namespace pliant::collision
