#include "pliant/cloth/untangle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/exact_predicates.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {
namespace {

// |n · d| is clamped below at this fraction of |d| (see the header).
constexpr double MIN_CROSSING_COSINE = 0.1;

// Where edge (vertices edge[0], edge[1]) crosses triangle `triangle` (vertex indices), with what
// the gradient needs.
struct Crossing {
    Vec3d point;
    std::int32_t edge[2];
    double s;  // edge parameter of the point
    std::int32_t triangle[3];
    double weights[3];  // barycentric weights of the point in the triangle
    Vec3d normal;       // the triangle's unit normal
    Vec3d direction;    // q − p
};

// Appends the crossing of edge (p, q) through the closed triangle (t0, t1, t2) when the edge's
// ends lie strictly on opposite sides of its plane and the line through them meets the triangle
// (exact signs); the point and weights are computed in double and clamped into the triangle.
void add_crossing(std::span<const Vec3d> x, std::int32_t p, std::int32_t q,
                  const geometry::Triangle& t, std::vector<Crossing>& out) {
    const auto at = [&](std::int32_t v) -> const Vec3d& {
        return x[static_cast<std::size_t>(v)];
    };
    const Vec3d& a = at(t[0]);
    const Vec3d& b = at(t[1]);
    const Vec3d& c = at(t[2]);
    const int side_p = geometry::orient3d(a, b, c, at(p));
    const int side_q = geometry::orient3d(a, b, c, at(q));
    if (side_p * side_q >= 0) {
        return;
    }
    const int s0 = geometry::orient3d(at(p), at(q), a, b);
    const int s1 = geometry::orient3d(at(p), at(q), b, c);
    const int s2 = geometry::orient3d(at(p), at(q), c, a);
    if ((s0 < 0 || s1 < 0 || s2 < 0) && (s0 > 0 || s1 > 0 || s2 > 0)) {
        return;
    }
    const Vec3d n = cross(b - a, c - a);
    const double length = norm(n);
    if (!(length > 0.0)) {
        return;
    }
    const Vec3d normal = n * (1.0 / length);
    const double dp = dot(normal, at(p) - a);
    const double dq = dot(normal, at(q) - a);
    // dp and dq have opposite signs (exactly); rounding can leave both 0 for a tiny crossing.
    const double s = dp != dq ? std::clamp(dp / (dp - dq), 0.0, 1.0) : 0.5;
    Crossing crossing{};
    crossing.point = at(p) + (at(q) - at(p)) * s;
    crossing.edge[0] = p;
    crossing.edge[1] = q;
    crossing.s = s;
    // Barycentric weights from the sub-triangles' areas along the normal.
    double w[3] = {dot(cross(b - crossing.point, c - crossing.point), normal),
                   dot(cross(c - crossing.point, a - crossing.point), normal),
                   dot(cross(a - crossing.point, b - crossing.point), normal)};
    double sum = 0.0;
    for (double& wk : w) {
        wk = std::max(wk, 0.0);
        sum += wk;
    }
    for (int k = 0; k < 3; ++k) {
        crossing.triangle[k] = t[static_cast<std::size_t>(k)];
        crossing.weights[k] = sum > 0.0 ? w[k] / sum : 1.0 / 3.0;
    }
    crossing.normal = normal;
    crossing.direction = at(q) - at(p);
    out.push_back(crossing);
}

// Adds ∂L/∂x to gradient for the end `crossing` of a segment, given c = ∂L/∂X.
void add_end_gradient(const Crossing& crossing, const Vec3d& c, std::span<Vec3d> gradient) {
    const Vec3d& n = crossing.normal;
    const Vec3d& d = crossing.direction;
    const double floor = MIN_CROSSING_COSINE * norm(d);
    double nd = dot(n, d);
    if (std::abs(nd) < floor) {
        nd = nd < 0.0 ? -floor : floor;
    }
    if (!(std::abs(nd) > 0.0)) {
        return;
    }
    const double k = dot(c, d) / nd;
    const Vec3d along_edge = c - n * k;
    gradient[static_cast<std::size_t>(crossing.edge[0])] += along_edge * (1.0 - crossing.s);
    gradient[static_cast<std::size_t>(crossing.edge[1])] += along_edge * crossing.s;
    for (int j = 0; j < 3; ++j) {
        gradient[static_cast<std::size_t>(crossing.triangle[j])] += n * (k * crossing.weights[j]);
    }
}

// Adds the gradient of the length of the intersection of triangles a and b (or, when that is
// not a segment with two distinct ends, a push apart) to `gradient`.
void add_pair_gradient(std::span<const Vec3d> x, const geometry::Triangle& a,
                       const geometry::Triangle& b, std::vector<Crossing>& crossings,
                       std::span<Vec3d> gradient) {
    crossings.clear();
    for (int k = 0; k < 3; ++k) {
        add_crossing(x, a[static_cast<std::size_t>(k)], a[static_cast<std::size_t>((k + 1) % 3)], b,
                     crossings);
        add_crossing(x, b[static_cast<std::size_t>(k)], b[static_cast<std::size_t>((k + 1) % 3)], a,
                     crossings);
    }
    // The two crossings farthest apart are the segment's ends (more than two: an edge through
    // the other's edge shows up twice).
    std::size_t first = 0;
    std::size_t second = 0;
    double longest = 0.0;
    for (std::size_t i = 0; i < crossings.size(); ++i) {
        for (std::size_t j = i + 1; j < crossings.size(); ++j) {
            const double length = norm(crossings[j].point - crossings[i].point);
            if (length > longest) {
                longest = length;
                first = i;
                second = j;
            }
        }
    }
    if (longest > 0.0) {
        const Vec3d u = (crossings[second].point - crossings[first].point) * (1.0 / longest);
        add_end_gradient(crossings[first], u * -1.0, gradient);
        add_end_gradient(crossings[second], u, gradient);
        return;
    }
    // Touching or coplanar: push the triangles apart along the line between their centroids.
    const auto at = [&](std::int32_t v) -> const Vec3d& {
        return x[static_cast<std::size_t>(v)];
    };
    const Vec3d centroid_a = (at(a[0]) + at(a[1]) + at(a[2])) * (1.0 / 3.0);
    const Vec3d centroid_b = (at(b[0]) + at(b[1]) + at(b[2])) * (1.0 / 3.0);
    Vec3d away = centroid_a - centroid_b;
    if (!(norm(away) > 0.0)) {
        away = cross(at(b[1]) - at(b[0]), at(b[2]) - at(b[0]));
    }
    const double length = norm(away);
    if (!(length > 0.0)) {
        return;
    }
    away = away * (1.0 / length);
    for (int k = 0; k < 3; ++k) {
        gradient[static_cast<std::size_t>(a[static_cast<std::size_t>(k)])] -= away;
        gradient[static_cast<std::size_t>(b[static_cast<std::size_t>(k)])] += away;
    }
}

}  // namespace

UntangleResult untangle(std::span<Vec3d> positions, std::span<const geometry::Triangle> triangles,
                        std::span<const double> inverse_masses, const UntangleOptions& options) {
    Stopwatch watch;
    const std::size_t n = positions.size();
    if (inverse_masses.size() != n) {
        throw InvalidInput(
            fmt::format("untangle: expected {} inverse masses (one per vertex), got {}", n,
                        inverse_masses.size()));
    }
    if (options.max_iterations < 0 || options.smoothing < 0 || options.shape_iterations < 0 ||
        !(options.step >= 0.0) || !std::isfinite(options.step)) {
        throw InvalidInput(fmt::format(
            "untangle: expected max_iterations, smoothing and shape_iterations >= 0 and a finite "
            "step >= 0, got {}, {}, {} and {}",
            options.max_iterations, options.smoothing, options.shape_iterations, options.step));
    }
    // Validates indices and coordinates (InvalidInput naming the offending element).
    std::vector<std::array<std::int32_t, 2>> pairs =
        collision::find_intersecting_pairs(std::span<const Vec3d>(positions), triangles);
    UntangleResult result;
    result.initial_pairs = static_cast<std::int64_t>(pairs.size());
    result.final_pairs = result.initial_pairs;
    if (pairs.empty()) {
        result.ms = watch.elapsed_ms();
        return result;
    }

    const geometry::MeshTopology topology = geometry::build_topology(triangles, n);
    double step = options.step;
    if (step == 0.0) {
        double total = 0.0;
        for (const geometry::Edge& e : topology.edges) {
            total += norm(positions[static_cast<std::size_t>(e[1])] -
                          positions[static_cast<std::size_t>(e[0])]);
        }
        step =
            topology.edges.empty() ? 0.0 : total / static_cast<double>(topology.edges.size()) / 8.0;
    }
    // Vertex neighbours (CSR) for the smoothing.
    std::vector<std::int32_t> offsets(n + 1, 0);
    for (const geometry::Edge& e : topology.edges) {
        ++offsets[static_cast<std::size_t>(e[0]) + 1];
        ++offsets[static_cast<std::size_t>(e[1]) + 1];
    }
    for (std::size_t v = 0; v < n; ++v) {
        offsets[v + 1] += offsets[v];
    }
    std::vector<std::int32_t> neighbours(static_cast<std::size_t>(offsets[n]));
    {
        std::vector<std::int32_t> next(offsets.begin(), offsets.end() - 1);
        for (const geometry::Edge& e : topology.edges) {
            neighbours[static_cast<std::size_t>(next[static_cast<std::size_t>(e[0])]++)] = e[1];
            neighbours[static_cast<std::size_t>(next[static_cast<std::size_t>(e[1])]++)] = e[0];
        }
    }

    std::vector<double> rest_lengths(topology.edges.size());
    for (std::size_t e = 0; e < topology.edges.size(); ++e) {
        rest_lengths[e] = norm(positions[static_cast<std::size_t>(topology.edges[e][1])] -
                               positions[static_cast<std::size_t>(topology.edges[e][0])]);
    }
    const std::vector<Vec3d> start(positions.begin(), positions.end());
    std::vector<Vec3d> best = start;
    std::int64_t best_pairs = result.initial_pairs;
    std::vector<Vec3d> gradient(n);
    std::vector<Vec3d> spread(n);
    std::vector<Crossing> crossings;
    for (int iteration = 0; iteration < options.max_iterations && !pairs.empty() && step > 0.0;
         ++iteration) {
        std::fill(gradient.begin(), gradient.end(), Vec3d{0.0, 0.0, 0.0});
        for (const auto& [i, j] : pairs) {
            add_pair_gradient(positions, triangles[static_cast<std::size_t>(i)],
                              triangles[static_cast<std::size_t>(j)], crossings, gradient);
        }
        for (std::size_t v = 0; v < n; ++v) {
            if (!(inverse_masses[v] > 0.0)) {
                gradient[v] = {0.0, 0.0, 0.0};
            }
        }
        for (int ring = 0; ring < options.smoothing; ++ring) {
            for (std::size_t v = 0; v < n; ++v) {
                Vec3d sum = gradient[v];
                for (std::int32_t k = offsets[v]; k < offsets[v + 1]; ++k) {
                    sum +=
                        gradient[static_cast<std::size_t>(neighbours[static_cast<std::size_t>(k)])];
                }
                const double count = 1.0 + (offsets[v + 1] - offsets[v]);
                spread[v] = inverse_masses[v] > 0.0 ? sum * (1.0 / count) : Vec3d{0.0, 0.0, 0.0};
            }
            gradient.swap(spread);
        }
        double largest = 0.0;
        for (const Vec3d& g : gradient) {
            largest = std::max(largest, norm(g));
        }
        if (!(largest > 0.0) || !std::isfinite(largest)) {
            break;
        }
        const double scale = step / largest;
        for (std::size_t v = 0; v < n; ++v) {
            positions[v] -= gradient[v] * scale;
        }
        // Keep the cloth's shape: the edges back towards their lengths (Gauss-Seidel over the
        // edges in order, weighted by the inverse masses).
        for (int sweep = 0; sweep < options.shape_iterations; ++sweep) {
            for (std::size_t e = 0; e < topology.edges.size(); ++e) {
                const auto a = static_cast<std::size_t>(topology.edges[e][0]);
                const auto b = static_cast<std::size_t>(topology.edges[e][1]);
                const double w = inverse_masses[a] + inverse_masses[b];
                const Vec3d d = positions[b] - positions[a];
                const double length = norm(d);
                if (!(w > 0.0) || !(length > 0.0)) {
                    continue;
                }
                const Vec3d correction = d * ((length - rest_lengths[e]) / (length * w));
                positions[a] += correction * inverse_masses[a];
                positions[b] -= correction * inverse_masses[b];
            }
        }
        ++result.iterations;
        pairs = collision::find_intersecting_pairs(std::span<const Vec3d>(positions), triangles);
        if (static_cast<std::int64_t>(pairs.size()) < best_pairs) {
            best_pairs = static_cast<std::int64_t>(pairs.size());
            best.assign(positions.begin(), positions.end());
        }
    }
    std::copy(best.begin(), best.end(), positions.begin());
    result.final_pairs = best_pairs;
    for (std::size_t v = 0; v < n; ++v) {
        result.max_displacement = std::max(result.max_displacement, norm(positions[v] - start[v]));
    }
    result.ms = watch.elapsed_ms();
    return result;
}

}  // namespace pliant::cloth
