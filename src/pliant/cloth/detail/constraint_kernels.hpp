// The cloth solver's constraint projections (solver.hpp), as kernels over the constraints of one
// colour: a scalar kernel per constraint, and AVX2 kernels that project four constraints at a
// time (double precision, four lanes), chosen at run time. The AVX2 kernels do the scalar
// kernel's arithmetic lane by lane, in the same order and without contracting a · b + c into an
// fma (pliant is compiled with -ffp-contract=off; core/simd_dispatch.hpp): the
// results are bitwise those of the scalar kernel, so the choice never changes a result, on any
// machine, for any number of threads.
//
// Vertices are PackedVertex: position and inverse mass in one 32-byte record, so that four
// vertices load and store as four 256-bit rows (transposed in registers) instead of gathers.
//
// Stretch (one edge p-q, rest length L): C = |x_p − x_q| − L, XPBD with one iteration:
//   λ = −C / (w_p + w_q + α̃),  x_p += w_p λ n,  x_q −= w_q λ n,  n = (x_p − x_q) / |x_p − x_q|;
// skipped when w_p + w_q = 0 or the edge has zero length.
//
// Bending (dihedral angle θ of the triangles (x0, x2, x3) and (x1, x3, x2) around the edge
// x2-x3, rest angle θ_0; dihedral.hpp has the angle and gradient): C = θ − θ_0 wrapped into
// (−π, π], λ = −C / (Σ w_k |∇_k θ|² + α̃), x_k += w_k λ ∇_k θ; skipped for a degenerate pair (zero
// area or edge length) or when Σ w_k |∇_k θ|² = 0. The angle is atan2 of unnormalized sine and
// cosine terms (atan2 is invariant to scaling both), evaluated by detail::atan2 below (a rational
// approximation to 1e-16, the same operations in the scalar and vector kernels).
//
// Isometric bending (a hinge flat at rest, stencil K of isometric_bending.hpp): with
// b = K_0 (x0 − x2) + K_1 (x1 − x2) + K_3 (x3 − x2) (= Σ K_k x_k) and the hinge normal
// n = K_0 n_A + K_1 n_B (n_A = (x2 − x0) × (x3 − x0), n_B = (x3 − x1) × (x2 − x1); the weights
// make the two terms as long at rest, so n bisects the wings as b does), C = n̂ · b, XPBD with
// one iteration and n̂ held fixed: Δλ = −C / (Σ w_k K_k² + α̃), x_k += w_k K_k n̂ Δλ, evaluated
// as n · (−(n · b) / (|n|² (Σ w_k K_k² + α̃))); skipped when Σ w_k K_k² = 0 or that denominator
// is not positive (n = 0, or its square underflows). No square root, one division.
//
// Stretch chains (stretch_chains.hpp): the stretch constraints of a chain of edges v_0 … v_m
// solved together, one linearized XPBD step (λ starting at 0) for all of them: with n_k the unit
// direction of edge k (x_{k+1} − x_k) and C_k = |x_{k+1} − x_k| − L_k,
//   A Δλ = −C,   A_kk = (w_k + w_{k+1}) (1 + ε_k) + α̃,   ε_k = ε + κ |C_k| / ℓ_k,
//   A_{k,k+1} = A_{k+1,k} = −w_{k+1} n_k · n_{k+1},   Δx_j = w_j (n_{j−1} Δλ_{j−1} − n_j Δλ_j),
// (ℓ_k the edge's length). A = J W Jᵀ + diag(ε_k (w_k + w_{k+1}) + α̃) is tridiagonal, symmetric
// and positive definite (ε > 0), so the Thomas algorithm solves it in one forward and one
// backward sweep without pivoting. ε_k is a Levenberg-Marquardt damping of the step, larger on
// strained edges (stretch_chains.hpp has ε, κ and why). An edge with w_k + w_{k+1} = 0, zero
// length or a length that overflows, and a padding row, take no part (the row is decoupled,
// Δλ = 0), as the single-edge kernel skips such an edge.
//
// Per-element kernels: no allocation, no exceptions; the constraints of one call must not share
// vertices (a colour), and calls on disjoint ranges of a colour may run in parallel.
#pragma once

#include <cstdint>

namespace pliant::cloth::detail {

struct alignas(32) PackedVertex {
    double x;
    double y;
    double z;
    double inverse_mass;
};

// Constraints of one colour as columns (structure of arrays), in the colour's order.
struct StretchColumns {
    const std::int32_t* p;
    const std::int32_t* q;
    const double* rest_length;
    // The multipliers λ the substep has already given these constraints (a stretch-chain solve
    // before, in the same order), or null for none: the projection is then XPBD's next iteration,
    // Δλ = (−C − α̃ λ) / (w_p + w_q + α̃), so that compliant edges converge to C = −α̃ λ.
    const double* lambda = nullptr;
};
struct BendingColumns {
    const std::int32_t* v0;
    const std::int32_t* v1;
    const std::int32_t* v2;  // the shared edge is v2-v3
    const std::int32_t* v3;
    const double* rest_angle;
};

struct IsometricBendingColumns {
    const std::int32_t* v0;
    const std::int32_t* v1;
    const std::int32_t* v2;  // the shared edge is v2-v3
    const std::int32_t* v3;
    const double* k0;  // the stencil, 1/m
    const double* k1;
    const double* k2;
    const double* k3;
};

// Four chains of one family side by side (lane l = chain l), padded to the longest: rows past a
// chain's end repeat its last vertex and hold no edge (rest length < 0); a lane without a chain
// holds the padding vertex (inverse mass 0, used by no chain), written back unchanged.
struct ChainPacket {
    const std::int32_t* vertices;  // num_rows + 1 rows of four: row k, lane l = vertex k of chain l
    const double* rest_length;     // num_rows rows of four; negative: padding, no edge
    const std::int32_t* edges;  // num_rows rows of four: the edge's index (for λ), −1: padding
    std::int32_t num_rows;      // rows of edges (the longest chain's edge count)
};
// The parameters of a chain solve: alpha = compliance / h², regularization = ε > 0,
// strain_regularization = κ ≥ 0.
struct ChainSolve {
    double alpha;
    double regularization;
    double strain_regularization = 0.0;
};
// Doubles of scratch project_chain_packet needs per row of edges.
inline constexpr std::int32_t CHAIN_SCRATCH_PER_ROW = 24;

// Projects constraints [begin, end) of a colour; alpha = compliance / h². The AVX2 kernels take
// the constraints in groups of four from `begin`; ranges that start at a multiple of four give
// the same grouping for any split of a colour into ranges (not that grouping matters: every
// lane computes the scalar kernel's bits).
void project_stretch(PackedVertex* x, const StretchColumns& c, std::int64_t begin, std::int64_t end,
                     double alpha);
void project_bending(PackedVertex* x, const BendingColumns& c, std::int64_t begin, std::int64_t end,
                     double alpha);
void project_isometric_bending(PackedVertex* x, const IsometricBendingColumns& c,
                               std::int64_t begin, std::int64_t end, double alpha);

// Solves the four chains of a packet, using CHAIN_SCRATCH_PER_ROW × packet.num_rows doubles of
// scratch, and writes each edge's Δλ to lambda[edge] (for the single-edge sweep that follows).
// The chains of a packet share no vertex; packets of one family may run in parallel. The AVX2
// kernel (four lanes) gives the bits of the scalar one.
void project_chain_packet(PackedVertex* x, const ChainPacket& packet, const ChainSolve& solve,
                          double* lambda, double* scratch);

// atan2(y, x) in (−π, π] from +, −, ×, ÷ and comparisons only (the vector kernels evaluate the
// same operations): the octant reduction |y| ≤ |x| → t = |y| / |x| ∈ [0, 1], t > 0.66 → (t − 1) /
// (t + 1) + π/4, then Cephes' rational approximation of atan on [−0.2, 0.66]. Within 2e-16 of
// the correctly rounded value (relative, away from 0); atan2(0, 0) = 0, atan2(0, −x) = π.
double atan2(double y, double x);

}  // namespace pliant::cloth::detail
