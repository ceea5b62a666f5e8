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
// Rounding error of a projection n · F per unit of Σ |n_i| max|F_i|: 2^-50 > γ_3 (see ccd.hpp).
constexpr double PROJECTION_ERROR = 0x1p-50;
// Factor that covers the few roundings in computing an error bound or a separation (1 + 10 u).
constexpr double ROUND_UP = 1.0 + 0x1p-40;
// Error of a difference of two projections n · p of lerped points per unit of Σ |n_i| M_i.
constexpr double STEP_PROJECTION_ERROR = 0x1p-48;
// Separating directions: n and m (boxes and slabs), plus up to two in-plane normals (slabs only).
constexpr int BOX_DIRECTIONS = 2;
constexpr int MAX_DIRECTIONS = 4;
// Below this sine of the angle between a and b, n is taken as any normal of a.
constexpr double PARALLEL_SINE = 1e-6;

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
    double end[4][3];     // the inputs at t = 1 (start + displacement is within rounding of it)
    double magnitude[3];  // M_axis: the largest |coordinate| of the 8 inputs on each axis
    double error[3];      // error bound of one corner value per axis (ccd.hpp)
    double min_separation;
    // The separating directions n and m of ccd.hpp (unit vectors), δ ‖n‖₁ rounded up, and the
    // error bound of a slab test along them; used only when num_directions is 2.
    int num_directions;
    double direction[MAX_DIRECTIONS][3];
    double direction_separation[MAX_DIRECTIONS];
    double direction_slab_error[MAX_DIRECTIONS];
    // A surviving box whose corner values span at most this on every axis is terminal.
    double codomain_tolerance;
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

// True when, along some axis, every point of the box is provably farther than δ from 0; then,
// when the query has separating directions, the same test along each of them (ccd.hpp).
bool is_excluded(const Query& query, const double values[8][3]) {
    double magnitude[3];  // largest |corner value| per axis, for the projections' rounding error
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
        magnitude[axis] = std::max(-lo, hi);
    }
    for (int k = 0; k < std::min(query.num_directions, BOX_DIRECTIONS); ++k) {
        const double* n = query.direction[k];
        double lo = 0.0;
        double hi = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
            const double value =
                (n[0] * values[corner][0] + n[1] * values[corner][1]) + n[2] * values[corner][2];
            lo = corner == 0 ? value : std::min(lo, value);
            hi = corner == 0 ? value : std::max(hi, value);
        }
        double error = 0.0;
        for (int axis = 0; axis < 3; ++axis) {
            error += std::fabs(n[axis]) * (query.error[axis] + PROJECTION_ERROR * magnitude[axis]);
        }
        error = (error + UNDERFLOW_ERROR) * ROUND_UP;
        if (lo - error > query.direction_separation[k] ||
            hi + error < -query.direction_separation[k]) {
            return true;
        }
    }
    return false;
}

// The largest spread of the corner values over the three axes.
double codomain_width(const double values[8][3]) {
    double widest = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        double lo = values[0][axis];
        double hi = values[0][axis];
        for (int corner = 1; corner < 8; ++corner) {
            lo = std::min(lo, values[corner][axis]);
            hi = std::max(hi, values[corner][axis]);
        }
        widest = std::max(widest, hi - lo);
    }
    return widest;
}

// The separating directions of ccd.hpp, from the positions at mid-step: n normal to the pair's
// two direction vectors a (the longer) and b (the edges, or the face's edges f1 - f0 and f2 - f0),
// or any normal of a when they are (nearly) parallel; m = â × n; then, for the slab tests only,
// the in-plane normals e × n of the pair's other edges (b, and for a face also f2 - f1), which
// separate coplanar neighbours (a flat cloth). Unit vectors. None when both vectors are zero or
// not finite (the contact set is then a point for each t, or the input is out of range).
struct Directions {
    int count = 0;
    Vec3d direction[MAX_DIRECTIONS];
};

Directions separating_directions(Kind kind, const Vec3d (&t0)[4], const Vec3d (&t1)[4]) {
    Vec3d mid[4];
    for (int k = 0; k < 4; ++k) {
        mid[k] = 0.5 * (t0[k] + t1[k]);
    }
    Vec3d a = kind == Kind::EDGE_EDGE ? mid[1] - mid[0] : mid[2] - mid[1];
    Vec3d b = kind == Kind::EDGE_EDGE ? mid[3] - mid[2] : mid[3] - mid[1];
    if (squared_norm(b) > squared_norm(a)) {
        std::swap(a, b);
    }
    const double length_a = norm(a);
    if (!(length_a > 0.0) || !std::isfinite(length_a)) {
        return {};
    }
    Vec3d n = cross(a, b);
    if (!(norm(n) > PARALLEL_SINE * length_a * norm(b))) {
        // Nearly parallel: any normal of a; the axis least aligned with a keeps it well scaled.
        const Vec3d magnitude{std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)};
        const Vec3d axis = magnitude.x <= magnitude.y && magnitude.x <= magnitude.z
                               ? Vec3d{1.0, 0.0, 0.0}
                           : magnitude.y <= magnitude.z ? Vec3d{0.0, 1.0, 0.0}
                                                        : Vec3d{0.0, 0.0, 1.0};
        n = cross(a, axis);
    }
    const double length_n = norm(n);
    if (!(length_n > 0.0) || !std::isfinite(length_n)) {
        return {};
    }
    n = n * (1.0 / length_n);
    Directions directions{.count = 2, .direction = {n, cross(a * (1.0 / length_a), n)}};
    const Vec3d others[2] = {b, mid[3] - mid[2]};  // for a face: f2 - f0 (or f1 - f0), f2 - f1
    for (int k = 0; k < (kind == Kind::VERTEX_FACE ? 2 : 1); ++k) {
        const Vec3d normal = cross(others[k], n);
        const double length = norm(normal);
        if (length > 0.0 && std::isfinite(length)) {
            directions.direction[directions.count++] = normal * (1.0 / length);
        }
    }
    return directions;
}

// δ ‖n‖₁ rounded up: the largest |n · F| inside the contact box [-δ, δ]³.
double separation_along(const Vec3d& n, double min_separation) {
    return min_separation * ((std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z)) * ROUND_UP);
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

// One projection x of the 4 points at the two ends t_a (x[0]) and t_b (x[1]) of a slab of time,
// over all of the features: true when the two features' projections are more than `separation`
// apart, on the same side, at both ends. F is bilinear in t and the feature parameters, so its
// range over the slab lies between its values at t_a and t_b at the features' corners (for a
// face: its 3 vertices, tighter than the (u, v) box of the search); each is a difference of two
// projections, computed within `error`. Widens [lo, hi] to the range of those differences.
bool is_step_excluded(Kind kind, const double (&x)[2][4], double error, double separation,
                      double& range_lo, double& range_hi) {
    double lo[2];
    double hi[2];
    for (int at = 0; at < 2; ++at) {
        const double(&p)[4] = x[at];
        if (kind == Kind::VERTEX_FACE) {
            lo[at] = p[0] - std::max(std::max(p[1], p[2]), p[3]);
            hi[at] = p[0] - std::min(std::min(p[1], p[2]), p[3]);
        } else {
            lo[at] = std::min(p[0], p[1]) - std::max(p[2], p[3]);
            hi[at] = std::max(p[0], p[1]) - std::min(p[2], p[3]);
        }
    }
    range_lo = std::min(lo[0], lo[1]);
    range_hi = std::max(hi[0], hi[1]);
    return ((lo[0] - error > separation) & (lo[1] - error > separation)) |
           ((hi[0] + error < -separation) & (hi[1] + error < -separation));
}

// The slab [t_a, t_b] × (all of the features), along the axes and the query's separating
// directions: true when it provably holds no contact. The points at t_a and t_b are the lerps
// start + t displacement (exact inputs at t = 0), within about 5 u M_axis of exact, which the
// bounds of ccd.hpp cover; at t = 0 and t = 1 the inputs themselves are used. codomain_width: the
// widest range of F over the axes. With test_axes false only the directions are tested.
bool is_slab_excluded(const Query& query, double t_a, double t_b, double& codomain_width,
                      bool test_axes = true) {
    double x[3][2][4];
    bool is_excluded_slab = false;
    codomain_width = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        for (int k = 0; k < 4; ++k) {
            x[axis][0][k] = t_a == 0.0 ? query.start[k][axis]
                                       : query.start[k][axis] + t_a * query.displacement[k][axis];
            x[axis][1][k] = t_b == 1.0 ? query.end[k][axis]
                                       : query.start[k][axis] + t_b * query.displacement[k][axis];
        }
        if (test_axes) {
            double lo = 0.0;
            double hi = 0.0;
            is_excluded_slab |= is_step_excluded(query.kind, x[axis], query.error[axis],
                                                 query.min_separation, lo, hi);
            codomain_width = std::max(codomain_width, hi - lo);
        }
    }
    for (int d = 0; d < query.num_directions && !is_excluded_slab; ++d) {
        const double* n = query.direction[d];
        double projected[2][4];
        for (int at = 0; at < 2; ++at) {
            for (int k = 0; k < 4; ++k) {
                projected[at][k] = (n[0] * x[0][at][k] + n[1] * x[1][at][k]) + n[2] * x[2][at][k];
            }
        }
        double lo = 0.0;
        double hi = 0.0;
        is_excluded_slab |= is_step_excluded(query.kind, projected, query.direction_slab_error[d],
                                             query.direction_separation[d], lo, hi);
    }
    return is_excluded_slab;
}

CcdResult no_hit(int iterations) {
    return {.hit = false, .toi = 1.0, .iterations = iterations, .hit_iteration_limit = false};
}

CcdResult hit_at(double toi, int iterations, bool is_iteration_limit = false) {
    return {.hit = true,
            .toi = toi,
            .iterations = iterations,
            .hit_iteration_limit = is_iteration_limit};
}

CcdResult run_ccd(Kind kind, const Vec3d (&t0)[4], const Vec3d (&t1)[4],
                  const CcdOptions& options) {
    // Step 1: sanitise the options (see ccd.hpp).
    const double tolerance = std::isnan(options.tolerance)
                                 ? CcdOptions{}.tolerance
                                 : std::clamp(options.tolerance, MIN_TOLERANCE, 1.0);
    const int max_iterations = std::max(options.max_iterations, 1);
    const double min_separation = options.min_separation > 0.0 ? options.min_separation : 0.0;

    // Step 2: the whole step at once along the axes, straight from the inputs; most pairs from a
    // broad phase end here. Inputs out of range report a conservative hit.
    double magnitude[3];
    double codomain = 0.0;  // the widest range of F over the step, over the axes
    bool is_in_range = std::isfinite(min_separation);
    bool is_excluded_step = false;
    for (int axis = 0; axis < 3; ++axis) {
        double x[2][4];
        magnitude[axis] = 0.0;
        for (int k = 0; k < 4; ++k) {
            x[0][k] = t0[k][axis];
            x[1][k] = t1[k][axis];
            const double m0 = std::fabs(x[0][k]);
            const double m1 = std::fabs(x[1][k]);
            is_in_range &= (m0 < MAX_COORDINATE) & (m1 < MAX_COORDINATE);  // false for NaN
            magnitude[axis] = std::max({magnitude[axis], m0, m1});
        }
        double lo = 0.0;
        double hi = 0.0;
        is_excluded_step |= is_step_excluded(
            kind, x, magnitude[axis] * RELATIVE_ERROR + UNDERFLOW_ERROR, min_separation, lo, hi);
        codomain = std::max(codomain, hi - lo);
    }
    if (!is_in_range) {
        return hit_at(0.0, 0);
    }
    if (is_excluded_step) {
        return no_hit(1);
    }

    // Step 3: the query, then the whole step along the separating directions.
    Query query;
    query.kind = kind;
    query.min_separation = min_separation;
    query.num_directions = 0;
    query.codomain_tolerance = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        for (int k = 0; k < 4; ++k) {
            query.start[k][axis] = t0[k][axis];
            query.end[k][axis] = t1[k][axis];
            query.displacement[k][axis] = t1[k][axis] - t0[k][axis];
        }
        query.magnitude[axis] = magnitude[axis];
        query.error[axis] = magnitude[axis] * RELATIVE_ERROR + UNDERFLOW_ERROR;
    }
    const Directions directions = separating_directions(kind, t0, t1);
    query.num_directions = directions.count;
    for (int d = 0; d < directions.count; ++d) {
        const Vec3d& n = directions.direction[d];
        query.direction[d][0] = n.x;
        query.direction[d][1] = n.y;
        query.direction[d][2] = n.z;
        query.direction_separation[d] = separation_along(n, min_separation);
        // A projection of a lerped point is within (5.1 u + γ_3) Σ |n_i| M_i of exact, a
        // difference of two within 18.4 u Σ |n_i| M_i < 2^-48 Σ |n_i| M_i (ccd.hpp).
        const double scale = std::fabs(n.x) * query.magnitude[0] +
                             std::fabs(n.y) * query.magnitude[1] +
                             std::fabs(n.z) * query.magnitude[2];
        query.direction_slab_error[d] =
            (scale * STEP_PROJECTION_ERROR + UNDERFLOW_ERROR) * ROUND_UP;
    }
    double unused = 0.0;  // the axes' range is already in codomain
    if (directions.count > 0 && is_slab_excluded(query, 0.0, 1.0, unused, false)) {
        return no_hit(1);
    }
    // A box whose corner values span at most tolerance × (F's range over the step) is terminal.
    query.codomain_tolerance = tolerance * codomain;
    const Box root{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, 0};

    // Step 4: the earliest time a contact cannot be excluded over all of (u, v): bisect t alone,
    // earlier slabs first, dropping excluded slabs, until a surviving slab is within tolerance.
    // Everything before it holds no contact, so the search of step 5 starts there. Without this,
    // a contact that begins at one instant along a whole curve of (u, v) (parallel edges in
    // contact, a vertex reaching a zero-area face) would be split in u and v along the curve
    // first, and each piece refined in t on its own: O(1 / tolerance) boxes.
    std::vector<Box>& heap = thread_heap();  // used as a stack here, in t order from the back
    heap.clear();
    int iterations = 1;  // the root box above
    double start = 0.0;
    bool is_any_left = false;  // a slab survived
    heap.push_back(root);
    bool is_evaluated = true;
    // When the features' hulls already meet at t = 0 (neighbours in a cloth), the search starts
    // at 0: nothing to bisect.
    if (iterations < max_iterations) {
        ++iterations;
        if (!is_slab_excluded(query, 0.0, 0.0, unused)) {
            is_any_left = true;
            heap.clear();
        }
    }
    while (!heap.empty()) {
        const Box slab = heap.back();
        heap.pop_back();
        if (iterations >= max_iterations) {
            // Every slab before this one is excluded.
            return hit_at(slab.lo[0], iterations, true);
        }
        if (!is_evaluated) {
            ++iterations;
            if (is_slab_excluded(query, slab.lo[0], slab.lo[0] + slab.width[0], codomain)) {
                continue;
            }
        }
        is_evaluated = false;
        if (codomain <= query.codomain_tolerance) {
            return hit_at(slab.lo[0], iterations);
        }
        if (!(slab.width[0] > tolerance)) {
            start = slab.lo[0];
            is_any_left = true;
            break;
        }
        const auto [lower, upper] = split(slab, 0);
        heap.push_back(upper);
        heap.push_back(lower);
    }
    if (!is_any_left) {
        return no_hit(iterations);
    }

    // Step 5: best-first bisection of [start, 1] x [0, 1]^2: always refine the open box with the
    // smallest t_lo (ties: the deepest, which drills towards a terminal box instead of widening
    // the front). `box` is the box being refined; when has_box is true it has survived the test,
    // its corner values are in `values`, and it starts no later than any box in the heap.
    heap.clear();
    Box box = root;
    box.lo[0] = start;
    box.width[0] = 1.0 - start;  // exact: start is dyadic
    bool has_box = false;
    heap.push_back(box);
    double values[8][3];
    double child_values[2][8][3];
    for (;;) {
        if (!has_box) {
            if (heap.empty()) {
                return no_hit(iterations);
            }
            std::pop_heap(heap.begin(), heap.end(), is_later);
            box = heap.back();
            heap.pop_back();
        }
        if (iterations >= max_iterations) {
            // box.lo[0] is the smallest t_lo of every unexplored box.
            return hit_at(box.lo[0], iterations, true);
        }
        if (!has_box) {
            ++iterations;
            if (is_box_excluded(query, box, values)) {
                continue;
            }
        }
        has_box = false;
        if (codomain_width(values) <= query.codomain_tolerance) {
            return hit_at(box.lo[0], iterations);
        }
        // Step 6: when splitting t excludes one half, go on with the other, directly when it
        // starts no later than the heap's first box. Refining t before u and v keeps a contact
        // near one instant from being cut into many pieces along (u, v).
        if (box.width[0] > tolerance) {
            const auto [lower, upper] = split(box, 0);
            iterations += 2;
            const bool is_lower_excluded = is_box_excluded(query, lower, child_values[0]);
            const bool is_upper_excluded = is_box_excluded(query, upper, child_values[1]);
            if (!is_lower_excluded && is_upper_excluded) {
                box = lower;  // same t_lo, deeper: first in heap order
                std::copy_n(&child_values[0][0][0], 24, &values[0][0]);
                has_box = true;
                continue;
            }
            if (is_lower_excluded && !is_upper_excluded) {
                if (heap.empty() || !is_later(upper, heap.front())) {
                    box = upper;
                    std::copy_n(&child_values[1][0][0], 24, &values[0][0]);
                    has_box = true;
                } else {
                    push(heap, upper);
                }
                continue;
            }
            if (is_lower_excluded) {
                continue;  // both halves excluded
            }
        }
        const int dim = split_dimension(box, values, tolerance);
        if (dim < 0) {
            // Every open box starts at or after box.lo[0], so no contact precedes it.
            return hit_at(box.lo[0], iterations);
        }
        const auto [lower, upper] = split(box, dim);
        push(heap, lower);
        push(heap, upper);
    }
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
