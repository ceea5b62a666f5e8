// Inclusion-based CCD; the method, its error bound and the contract are in ccd.hpp.
//
// Invariants of the search
//   - A box is (lo[d], lo[d] + width[d]) for d = 0 (t), 1 (u), 2 (v); every lo and width is a
//     dyadic rational k / 2^level. A dimension is split only while its width exceeds the tolerance
//     (>= 2^-40), so level <= 40 and lo + width is exact.
//   - The open boxes cover every part of [0, 1]³ not yet excluded, and children start no earlier
//     in t than their parent; so the smallest t_lo in the heap never decreases and is a lower
//     bound on the time of any contact not yet excluded.
#include "pliant/collision/ccd.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace pliant::collision {
namespace {

constexpr double MIN_TOLERANCE = 0x1p-40;
// Coordinates beyond this are not searched (the corner evaluation must not overflow).
constexpr double MAX_COORDINATE = 1e300;
// Error bound on one corner value per unit of M_axis: 256 u = 2^-45 > γ_7 · 18 (see ccd.hpp).
constexpr double RELATIVE_ERROR = 0x1p-45;
// Absolute error from underflow: 64 of the smallest subnormal (each rounding adds at most half).
constexpr double UNDERFLOW_ERROR = 0x1p-1068;

enum class Kind { VERTEX_FACE, EDGE_EDGE };

struct Box {
    double lo[3];
    double width[3];
    int depth;  // number of splits from the root box
};

// Heap order: a is explored after b when it starts later in t, or at the same t_lo is shallower.
bool is_later(const Box& a, const Box& b) {
    return a.lo[0] > b.lo[0] || (a.lo[0] == b.lo[0] && a.depth < b.depth);
}

// The open boxes, reused across the queries of a thread so that a query allocates only when its
// search grows beyond every earlier one on that thread.
std::vector<Box>& thread_heap() {
    thread_local std::vector<Box> heap;
    return heap;
}

// One query: the 4 points at t = 0, their displacements to t = 1 and the per-axis error bounds.
// VERTEX_FACE points are (v, f0, f1, f2); EDGE_EDGE points are (ea0, ea1, eb0, eb1).
struct Query {
    Kind kind;
    double start[4][3];
    double displacement[4][3];
    double error[3];
    double min_separation;
};

// F at the 8 corners of box; corner index = it + 2 iu + 4 iv, each bit selecting lo or lo + width.
// The operation order is the one the error bound in ccd.hpp counts: lerp (3 roundings), three
// differences (1), u- and v-products (1), two sums (2).
void evaluate_corners(const Query& query, const Box& box, double values[8][3]) {
    for (int it = 0; it < 2; ++it) {
        const double t = box.lo[0] + (it == 0 ? 0.0 : box.width[0]);
        for (int axis = 0; axis < 3; ++axis) {
            double p[4];
            for (int k = 0; k < 4; ++k) {
                p[k] = query.start[k][axis] + t * query.displacement[k][axis];
            }
            double base;
            double along_u;
            double along_v;
            if (query.kind == Kind::VERTEX_FACE) {
                // v - f0 - u (f1 - f0) - v (f2 - f0)
                base = p[0] - p[1];
                along_u = -(p[2] - p[1]);
                along_v = -(p[3] - p[1]);
            } else {
                // ea0 - eb0 + u (ea1 - ea0) - v (eb1 - eb0)
                base = p[0] - p[2];
                along_u = p[1] - p[0];
                along_v = -(p[3] - p[2]);
            }
            for (int iu = 0; iu < 2; ++iu) {
                const double u = box.lo[1] + (iu == 0 ? 0.0 : box.width[1]);
                for (int iv = 0; iv < 2; ++iv) {
                    const double v = box.lo[2] + (iv == 0 ? 0.0 : box.width[2]);
                    values[it + 2 * iu + 4 * iv][axis] = (base + u * along_u) + v * along_v;
                }
            }
        }
    }
}

// True when, in some axis, every point of the box is provably farther than δ from 0.
bool is_excluded(const Query& query, const double values[8][3]) {
    for (int axis = 0; axis < 3; ++axis) {
        double lo = values[0][axis];
        double hi = values[0][axis];
        for (int corner = 1; corner < 8; ++corner) {
            lo = std::min(lo, values[corner][axis]);
            hi = std::max(hi, values[corner][axis]);
        }
        // Rounding is monotone and min_separation is a double, so a rounded comparison that holds
        // implies the exact one.
        if (lo - query.error[axis] > query.min_separation ||
            hi + query.error[axis] < -query.min_separation) {
            return true;
        }
    }
    return false;
}

// The dimension to split: among those wider than tolerance, the one along which F varies most
// (largest |F(corner) - F(neighbour)| over the box's 4 edges in that dimension and the 3 axes);
// -1 when every width is within tolerance. Ties go to the lower dimension (t first).
int split_dimension(const Box& box, const double values[8][3], double tolerance) {
    int chosen = -1;
    double chosen_variation = -1.0;
    for (int dim = 0; dim < 3; ++dim) {
        if (!(box.width[dim] > tolerance)) {
            continue;
        }
        const int bit = 1 << dim;
        double variation = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
            if ((corner & bit) != 0) {
                continue;
            }
            for (int axis = 0; axis < 3; ++axis) {
                variation = std::max(variation,
                                     std::fabs(values[corner | bit][axis] - values[corner][axis]));
            }
        }
        if (variation > chosen_variation) {
            chosen = dim;
            chosen_variation = variation;
        }
    }
    return chosen;
}

// True when box provably holds no contact: a vertex-face box with u_lo + v_lo > 1 (exact: dyadic)
// holds no point of the triangle; otherwise the corner test. Leaves the corner values in values.
bool is_box_excluded(const Query& query, const Box& box, double values[8][3]) {
    if (query.kind == Kind::VERTEX_FACE && box.lo[1] + box.lo[2] > 1.0) {
        return true;
    }
    evaluate_corners(query, box, values);
    return is_excluded(query, values);
}

// The two halves of box along dim (lower first), one level deeper.
std::pair<Box, Box> split(const Box& box, int dim) {
    const double half = box.width[dim] * 0.5;
    Box lower = box;
    lower.width[dim] = half;
    lower.depth = box.depth + 1;
    Box upper = lower;
    upper.lo[dim] = box.lo[dim] + half;
    return {lower, upper};
}

void push(std::vector<Box>& heap, const Box& box) {
    heap.push_back(box);
    std::push_heap(heap.begin(), heap.end(), is_later);
}

CcdResult run_ccd(Kind kind, const Vec3d (&t0)[4], const Vec3d (&t1)[4],
                  const CcdOptions& options) {
    // Step 1: sanitise the options (see ccd.hpp) and reject inputs out of range.
    const double tolerance = std::isnan(options.tolerance)
                                 ? CcdOptions{}.tolerance
                                 : std::clamp(options.tolerance, MIN_TOLERANCE, 1.0);
    const int max_iterations = std::max(options.max_iterations, 1);
    Query query{};
    query.kind = kind;
    query.min_separation = options.min_separation > 0.0 ? options.min_separation : 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        double magnitude = 0.0;
        bool is_finite_input = true;
        for (int k = 0; k < 4; ++k) {
            for (const double x : {t0[k][axis], t1[k][axis]}) {
                is_finite_input = is_finite_input && std::isfinite(x);
                magnitude = std::max(magnitude, std::fabs(x));
            }
            query.start[k][axis] = t0[k][axis];
            query.displacement[k][axis] = t1[k][axis] - t0[k][axis];
        }
        if (!is_finite_input || !(magnitude < MAX_COORDINATE) ||
            !std::isfinite(query.min_separation)) {
            return {.hit = true, .toi = 0.0, .iterations = 0, .hit_iteration_limit = false};
        }
        query.error[axis] = magnitude * RELATIVE_ERROR + UNDERFLOW_ERROR;
    }

    // Step 2: best-first bisection: always refine the open box with the smallest t_lo (ties: the
    // deepest, which drills towards a terminal box instead of widening the front).
    std::vector<Box>& heap = thread_heap();
    heap.clear();
    heap.push_back(Box{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, 0});
    int iterations = 0;
    double values[8][3];
    double child_values[8][3];
    while (!heap.empty()) {
        std::pop_heap(heap.begin(), heap.end(), is_later);
        const Box box = heap.back();
        heap.pop_back();
        if (iterations >= max_iterations) {
            // box.lo[0] is the smallest t_lo of every unexplored box.
            return {.hit = true,
                    .toi = box.lo[0],
                    .iterations = iterations,
                    .hit_iteration_limit = true};
        }
        ++iterations;
        if (is_box_excluded(query, box, values)) {
            continue;
        }
        // Step 3: when splitting t excludes one half, keep only the other. Without this, a
        // contact along a curve at one instant (parallel edges, a zero-area face) would be
        // refined in u and v along the whole curve before t, costing O(1 / tolerance) boxes.
        if (box.width[0] > tolerance) {
            const auto [lower, upper] = split(box, 0);
            iterations += 2;
            const bool is_lower_excluded = is_box_excluded(query, lower, child_values);
            const bool is_upper_excluded = is_box_excluded(query, upper, child_values);
            if (is_lower_excluded || is_upper_excluded) {
                if (!is_lower_excluded) {
                    push(heap, lower);
                }
                if (!is_upper_excluded) {
                    push(heap, upper);
                }
                continue;
            }
        }
        const int dim = split_dimension(box, values, tolerance);
        if (dim < 0) {
            // Every open box starts at or after box.lo[0], so no contact precedes it.
            return {.hit = true,
                    .toi = box.lo[0],
                    .iterations = iterations,
                    .hit_iteration_limit = false};
        }
        const auto [lower, upper] = split(box, dim);
        push(heap, lower);
        push(heap, upper);
    }
    return {.hit = false, .toi = 1.0, .iterations = iterations, .hit_iteration_limit = false};
}

}  // namespace

CcdResult vertex_face_ccd(const Vec3d& v_t0, const Vec3d& f0_t0, const Vec3d& f1_t0,
                          const Vec3d& f2_t0, const Vec3d& v_t1, const Vec3d& f0_t1,
                          const Vec3d& f1_t1, const Vec3d& f2_t1, const CcdOptions& options) {
    const Vec3d t0[4] = {v_t0, f0_t0, f1_t0, f2_t0};
    const Vec3d t1[4] = {v_t1, f0_t1, f1_t1, f2_t1};
    return run_ccd(Kind::VERTEX_FACE, t0, t1, options);
}

CcdResult edge_edge_ccd(const Vec3d& ea0_t0, const Vec3d& ea1_t0, const Vec3d& eb0_t0,
                        const Vec3d& eb1_t0, const Vec3d& ea0_t1, const Vec3d& ea1_t1,
                        const Vec3d& eb0_t1, const Vec3d& eb1_t1, const CcdOptions& options) {
    const Vec3d t0[4] = {ea0_t0, ea1_t0, eb0_t0, eb1_t0};
    const Vec3d t1[4] = {ea0_t1, ea1_t1, eb0_t1, eb1_t1};
    return run_ccd(Kind::EDGE_EDGE, t0, t1, options);
}

}  // namespace pliant::collision
