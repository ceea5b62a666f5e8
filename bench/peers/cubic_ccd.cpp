#include "peers/cubic_ccd.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace pliant::bench {
namespace {

constexpr double BARYCENTRIC_EPS = 1e-10;  // unitless
constexpr double DISTANCE_EPS = 1e-10;     // relative to the inputs' scale
constexpr double POLY_EPS = 1e-12;         // relative to the coefficients' magnitude
constexpr double ROOT_WIDTH = 1e-15;       // Newton / bisection stop, in t
constexpr int MAX_ROOT_STEPS = 80;

// p(t) = c[0] + c[1] t + c[2] t² + c[3] t³.
using Cubic = std::array<double, 4>;

double eval(const Cubic& c, double t) {
    return ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
}

double eval_derivative(const Cubic& c, double t) {
    return (3.0 * c[3] * t + 2.0 * c[2]) * t + c[1];
}

// det[a(t), b(t), c(t)] with a(t) = a0 + t da etc., as a cubic in t.
Cubic det_cubic(const Vec3d& a0, const Vec3d& da, const Vec3d& b0, const Vec3d& db, const Vec3d& c0,
                const Vec3d& dc) {
    const Vec3d n0 = cross(a0, b0);
    const Vec3d n1 = cross(a0, db) + cross(da, b0);
    const Vec3d n2 = cross(da, db);
    return {dot(n0, c0), dot(n0, dc) + dot(n1, c0), dot(n1, dc) + dot(n2, c0), dot(n2, dc)};
}

// Roots in (0, 1) of p'(t) = 3 c3 t² + 2 c2 t + c1, sorted; returns their number (0..2).
int critical_points(const Cubic& c, std::array<double, 2>& out) {
    const double a = 3.0 * c[3];
    const double b = 2.0 * c[2];
    const double k = c[1];
    int n = 0;
    auto keep = [&](double t) {
        if (t > 0.0 && t < 1.0) {
            out[n++] = t;
        }
    };
    if (a == 0.0) {
        if (b != 0.0) {
            keep(-k / b);
        }
    } else {
        const double disc = b * b - 4.0 * a * k;
        if (disc == 0.0) {
            keep(-b / (2.0 * a));
        } else if (disc > 0.0) {
            const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
            keep(q / a);
            if (q != 0.0) {
                keep(k / q);
            }
        }
    }
    if (n == 2 && out[0] > out[1]) {
        std::swap(out[0], out[1]);
    }
    return n;
}

// The root of p in (lo, hi), given that p(lo) and p(hi) have opposite signs (neither zero):
// safeguarded Newton, bisection whenever a Newton step leaves the bracket.
double bracketed_root(const Cubic& c, double lo, double hi, double p_lo) {
    const bool lo_negative = p_lo < 0.0;
    double x = 0.5 * (lo + hi);
    for (int step = 0; step < MAX_ROOT_STEPS; ++step) {
        const double px = eval(c, x);
        if (px == 0.0) {
            return x;
        }
        if ((px < 0.0) == lo_negative) {
            lo = x;
        } else {
            hi = x;
        }
        if (hi - lo <= ROOT_WIDTH) {
            return 0.5 * (lo + hi);
        }
        const double dpx = eval_derivative(c, x);
        double next = dpx != 0.0 ? x - px / dpx : lo;
        if (!(next > lo && next < hi)) {
            next = 0.5 * (lo + hi);
        }
        if (std::abs(next - x) <= ROOT_WIDTH) {
            return next;
        }
        x = next;
    }
    return x;
}

// Calls accept(t) on the roots of p in [0, 1] in increasing order until it returns true; returns
// whether one did (see the header for what counts as a root).
template <typename Accept>
bool for_each_root(const Cubic& c, Accept&& accept) {
    const double tol =
        POLY_EPS * (std::abs(c[0]) + std::abs(c[1]) + std::abs(c[2]) + std::abs(c[3]));
    std::array<double, 2> crit{};
    const int num_crit = critical_points(c, crit);
    std::array<double, 4> knots{0.0, 1.0, 1.0, 1.0};
    for (int i = 0; i < num_crit; ++i) {
        knots[static_cast<std::size_t>(i) + 1] = crit[static_cast<std::size_t>(i)];
    }
    const int num_pieces = num_crit + 1;
    double lo = knots[0];
    double p_lo = eval(c, lo);
    for (int i = 0; i < num_pieces; ++i) {
        const double hi = knots[static_cast<std::size_t>(i) + 1];
        const double p_hi = eval(c, hi);
        if (std::abs(p_lo) <= tol) {
            if (accept(lo)) {
                return true;
            }
        } else if (std::abs(p_hi) > tol && (p_lo < 0.0) != (p_hi < 0.0)) {
            if (accept(bracketed_root(c, lo, hi, p_lo))) {
                return true;
            }
        }
        lo = hi;
        p_lo = p_hi;
    }
    return std::abs(p_lo) <= tol && accept(lo);  // t = 1
}

Vec3d lerp(const Vec3d& p0, const Vec3d& p1, double t) {
    return p0 + (p1 - p0) * t;
}

double max_abs_coordinate(const std::array<const Vec3d*, 8>& points) {
    double m = 0.0;
    for (const Vec3d* p : points) {
        m = std::max({m, std::abs(p->x), std::abs(p->y), std::abs(p->z)});
    }
    return std::max(m, 1e-300);
}

bool inside_triangle(const Vec3d& p, const Vec3d& f0, const Vec3d& f1, const Vec3d& f2,
                     double scale) {
    const Vec3d n = cross(f1 - f0, f2 - f0);
    const double nn = squared_norm(n);
    const double s2 = scale * scale;
    if (!(nn > 1e-30 * s2 * s2)) {
        return false;
    }
    const double w0 = dot(cross(f1 - p, f2 - p), n) / nn;
    const double w1 = dot(cross(f2 - p, f0 - p), n) / nn;
    const double w2 = 1.0 - w0 - w1;
    return w0 >= -BARYCENTRIC_EPS && w1 >= -BARYCENTRIC_EPS && w2 >= -BARYCENTRIC_EPS;
}

// Squared distance between segments (p1, q1) and (p2, q2): Ericson, Real-Time Collision Detection,
// §5.1.9, with degenerate (point) segments handled.
double segment_segment_distance2(const Vec3d& p1, const Vec3d& q1, const Vec3d& p2, const Vec3d& q2,
                                 double scale) {
    const double eps = 1e-30 * scale * scale;
    const Vec3d d1 = q1 - p1;
    const Vec3d d2 = q2 - p2;
    const Vec3d r = p1 - p2;
    const double a = squared_norm(d1);
    const double e = squared_norm(d2);
    const double f = dot(d2, r);
    double s = 0.0;
    double t = 0.0;
    if (a <= eps && e <= eps) {
        return squared_norm(r);
    }
    if (a <= eps) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = dot(d1, r);
        if (e <= eps) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = dot(d1, d2);
            const double denom = a * e - b * b;
            s = denom != 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1.0) {
                t = 1.0;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    return squared_norm((p1 + d1 * s) - (p2 + d2 * t));
}

}  // namespace

bool cubic_vertex_face_ccd(const Vec3d& v_t0, const Vec3d& f0_t0, const Vec3d& f1_t0,
                           const Vec3d& f2_t0, const Vec3d& v_t1, const Vec3d& f0_t1,
                           const Vec3d& f1_t1, const Vec3d& f2_t1, double& toi) {
    const double scale =
        max_abs_coordinate({&v_t0, &f0_t0, &f1_t0, &f2_t0, &v_t1, &f0_t1, &f1_t1, &f2_t1});
    const Vec3d a0 = f1_t0 - f0_t0;
    const Vec3d b0 = f2_t0 - f0_t0;
    const Vec3d c0 = v_t0 - f0_t0;
    const Cubic poly =
        det_cubic(a0, (f1_t1 - f0_t1) - a0, b0, (f2_t1 - f0_t1) - b0, c0, (v_t1 - f0_t1) - c0);
    toi = 1.0;
    return for_each_root(poly, [&](double t) {
        if (!inside_triangle(lerp(v_t0, v_t1, t), lerp(f0_t0, f0_t1, t), lerp(f1_t0, f1_t1, t),
                             lerp(f2_t0, f2_t1, t), scale)) {
            return false;
        }
        toi = t;
        return true;
    });
}

bool cubic_edge_edge_ccd(const Vec3d& ea0_t0, const Vec3d& ea1_t0, const Vec3d& eb0_t0,
                         const Vec3d& eb1_t0, const Vec3d& ea0_t1, const Vec3d& ea1_t1,
                         const Vec3d& eb0_t1, const Vec3d& eb1_t1, double& toi) {
    const double scale = max_abs_coordinate(
        {&ea0_t0, &ea1_t0, &eb0_t0, &eb1_t0, &ea0_t1, &ea1_t1, &eb0_t1, &eb1_t1});
    const double max_distance = DISTANCE_EPS * scale;
    const Vec3d a0 = ea1_t0 - ea0_t0;
    const Vec3d b0 = eb0_t0 - ea0_t0;
    const Vec3d c0 = eb1_t0 - ea0_t0;
    const Cubic poly = det_cubic(a0, (ea1_t1 - ea0_t1) - a0, b0, (eb0_t1 - ea0_t1) - b0, c0,
                                 (eb1_t1 - ea0_t1) - c0);
    toi = 1.0;
    return for_each_root(poly, [&](double t) {
        const double d2 =
            segment_segment_distance2(lerp(ea0_t0, ea0_t1, t), lerp(ea1_t0, ea1_t1, t),
                                      lerp(eb0_t0, eb0_t1, t), lerp(eb1_t0, eb1_t1, t), scale);
        if (!(d2 <= max_distance * max_distance)) {
            return false;
        }
        toi = t;
        return true;
    });
}

}  // namespace pliant::bench
