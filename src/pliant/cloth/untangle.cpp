#include "pliant/cloth/untangle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/group_by_key.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/geometry/exact_predicates.hpp"
#include "pliant/geometry/fit_plane.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::cloth {
namespace {

// |n · d| is clamped below at this fraction of |d| (see the header).
constexpr double MIN_CROSSING_COSINE = 0.1;
// Iterations without a new fewest count of pairs after which a region move is tried.
constexpr int STALL_ITERATIONS = 40;
// The least |Σ n_t| / Σ |n_t| of the triangles a region move takes a plane from.
constexpr double MIN_PLANE_AGREEMENT = 0.5;

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

// Connected components of triangles over shared edges, skipping triangles with skip[t] != 0
// (component -1); components are numbered in order of their lowest triangle. Returns the count.
std::int32_t edge_components(const geometry::MeshTopology& topology,
                             std::span<const std::uint8_t> skip,
                             std::vector<std::int32_t>& component,
                             std::vector<std::int32_t>& stack) {
    const std::size_t num_triangles = topology.triangle_edges.size();
    component.assign(num_triangles, -1);
    std::int32_t count = 0;
    for (std::size_t seed = 0; seed < num_triangles; ++seed) {
        if (component[seed] >= 0 || skip[seed] != 0) {
            continue;
        }
        component[seed] = count;
        stack.assign(1, static_cast<std::int32_t>(seed));
        while (!stack.empty()) {
            const auto t = static_cast<std::size_t>(stack.back());
            stack.pop_back();
            for (const std::int32_t e : topology.triangle_edges[t]) {
                for (const std::int32_t u : topology.triangles_of_edge(e)) {
                    const auto k = static_cast<std::size_t>(u);
                    if (component[k] < 0 && skip[k] == 0) {
                        component[k] = count;
                        stack.push_back(u);
                    }
                }
            }
        }
        ++count;
    }
    return count;
}

// The connected pieces of cloth: components of triangles that share a vertex (so that moving a
// piece rigidly tears nothing), numbered in order of their lowest triangle.
struct Pieces {
    std::vector<std::int32_t> of_triangle;  // per triangle, its piece
    std::size_t count = 0;
    // The vertices of piece p: vertices[vertex_offsets[p] .. vertex_offsets[p + 1]), ascending
    // (a vertex in no triangle is in no piece).
    std::vector<std::int32_t> vertex_offsets;
    std::vector<std::int32_t> vertices;
    std::vector<std::uint8_t> has_pinned;  // per piece: a vertex with inverse mass 0 (or NaN)
};

Pieces find_pieces(std::span<const geometry::Triangle> triangles,
                   std::span<const double> inverse_masses) {
    const std::size_t num_vertices = inverse_masses.size();
    std::vector<std::int32_t> parent(num_vertices);
    for (std::size_t v = 0; v < num_vertices; ++v) {
        parent[v] = static_cast<std::int32_t>(v);
    }
    const auto root = [&](std::int32_t v) {
        while (parent[static_cast<std::size_t>(v)] != v) {
            parent[static_cast<std::size_t>(v)] =
                parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
            v = parent[static_cast<std::size_t>(v)];
        }
        return v;
    };
    for (const geometry::Triangle& t : triangles) {
        for (int k = 1; k < 3; ++k) {
            const std::int32_t a = root(t[0]);
            const std::int32_t b = root(t[static_cast<std::size_t>(k)]);
            if (a != b) {
                parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
            }
        }
    }
    Pieces pieces;
    std::vector<std::int32_t> label(num_vertices, -1);
    pieces.of_triangle.resize(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        const auto r = static_cast<std::size_t>(root(triangles[t][0]));
        if (label[r] < 0) {
            label[r] = static_cast<std::int32_t>(pieces.count++);
        }
        pieces.of_triangle[t] = label[r];
    }
    std::vector<std::int32_t> vertex_piece(num_vertices, -1);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        for (const std::int32_t v : triangles[t]) {
            vertex_piece[static_cast<std::size_t>(v)] = pieces.of_triangle[t];
        }
    }
    group_by_key(vertex_piece, pieces.count, pieces.vertex_offsets, pieces.vertices);
    pieces.has_pinned.assign(pieces.count, 0);
    for (std::size_t v = 0; v < num_vertices; ++v) {
        if (vertex_piece[v] >= 0 && !(inverse_masses[v] > 0.0)) {
            pieces.has_pinned[static_cast<std::size_t>(vertex_piece[v])] = 1;
        }
    }
    return pieces;
}

// Whether moving vertex x to `target` takes it from outside the obstacles into one.
bool enters_obstacle(const ObstacleDistance& obstacle_distance, const Vec3d& x,
                     const Vec3d& target) {
    return obstacle_distance && obstacle_distance(target) < 0.0 && !(obstacle_distance(x) < 0.0);
}

// The piece move for separate pieces of cloth that pass through each other (see the header):
// of every free piece and every other piece it crosses, the rigid moves along the other's
// intersected plane that put the piece's vertices near it on one side; the shortest of them all
// that takes no vertex into an obstacle is made. Returns whether one was.
bool separate_pieces(std::span<Vec3d> x, std::span<const geometry::Triangle> triangles,
                     const Pieces& pieces, const std::vector<std::array<std::int32_t, 2>>& pairs,
                     double clearance, const ObstacleDistance& obstacle_distance) {
    // (piece, other piece, other piece's triangle) for every intersecting pair across pieces,
    // sorted.
    std::vector<std::array<std::int32_t, 3>> crossing;
    for (const auto& [a, b] : pairs) {
        const std::int32_t pa = pieces.of_triangle[static_cast<std::size_t>(a)];
        const std::int32_t pb = pieces.of_triangle[static_cast<std::size_t>(b)];
        if (pa != pb) {
            crossing.push_back({pa, pb, b});
            crossing.push_back({pb, pa, a});
        }
    }
    std::sort(crossing.begin(), crossing.end());
    crossing.erase(std::unique(crossing.begin(), crossing.end()), crossing.end());
    struct Move {
        double length;
        std::int32_t piece;
        Vec3d shift;
    };
    std::vector<Move> moves;  // per group the shorter direction first
    std::vector<std::int32_t> others;
    for (std::size_t k = 0; k < crossing.size();) {
        // One (piece, other piece) group.
        const std::int32_t piece = crossing[k][0];
        const std::int32_t other = crossing[k][1];
        others.clear();
        for (; k < crossing.size() && crossing[k][0] == piece && crossing[k][1] == other; ++k) {
            others.push_back(crossing[k][2]);
        }
        const auto p = static_cast<std::size_t>(piece);
        if (pieces.has_pinned[p] != 0) {
            continue;
        }
        const std::optional<geometry::FittedPlane> plane =
            geometry::fit_plane(x, triangles, others, MIN_PLANE_AGREEMENT);
        if (!plane) {
            continue;
        }
        const Vec3d& centre = plane->centre;
        const Vec3d& normal = plane->normal;
        // The piece's vertices near the intersected triangles (within their radius of their
        // centre), on either side of their plane: how far the piece must move along the normal
        // for all of them to be on one side, `clearance` beyond it.
        double radius = 0.0;
        for (const std::int32_t o : others) {
            for (const std::int32_t v : triangles[static_cast<std::size_t>(o)]) {
                radius = std::max(radius, norm(x[static_cast<std::size_t>(v)] - centre));
            }
        }
        double depth_above = 0.0;
        double depth_below = 0.0;
        for (std::int32_t i = pieces.vertex_offsets[p]; i < pieces.vertex_offsets[p + 1]; ++i) {
            const Vec3d& point =
                x[static_cast<std::size_t>(pieces.vertices[static_cast<std::size_t>(i)])];
            if (norm(point - centre) > radius) {
                continue;
            }
            const double d = dot(normal, point - centre);
            depth_above = std::max(depth_above, d);
            depth_below = std::max(depth_below, -d);
        }
        if (!(depth_above > 0.0) || !(depth_below > 0.0)) {
            continue;
        }
        const double lift = depth_below + clearance;
        const double sink = depth_above + clearance;
        if (depth_below <= depth_above) {
            moves.push_back({lift, piece, normal * lift});
            moves.push_back({sink, piece, normal * -sink});
        } else {
            moves.push_back({sink, piece, normal * -sink});
            moves.push_back({lift, piece, normal * lift});
        }
    }
    // Shortest first; among equal lengths, in the order found.
    std::stable_sort(moves.begin(), moves.end(),
                     [](const Move& a, const Move& b) { return a.length < b.length; });
    for (const Move& move : moves) {
        const auto p = static_cast<std::size_t>(move.piece);
        const auto vertices = std::span(pieces.vertices)
                                  .subspan(static_cast<std::size_t>(pieces.vertex_offsets[p]),
                                           static_cast<std::size_t>(pieces.vertex_offsets[p + 1] -
                                                                    pieces.vertex_offsets[p]));
        if (std::any_of(vertices.begin(), vertices.end(), [&](std::int32_t v) {
                const Vec3d& point = x[static_cast<std::size_t>(v)];
                return enters_obstacle(obstacle_distance, point, point + move.shift);
            })) {
            continue;
        }
        for (const std::int32_t v : vertices) {
            x[static_cast<std::size_t>(v)] += move.shift;
        }
        return true;
    }
    return false;
}

// The region flip for contours that run from boundary to boundary (see the header). Returns
// whether it moved anything.
bool flip_regions(std::span<Vec3d> x, std::span<const geometry::Triangle> triangles,
                  const geometry::MeshTopology& topology, const Pieces& pieces,
                  std::span<const double> inverse_masses,
                  const std::vector<std::array<std::int32_t, 2>>& pairs, double clearance,
                  const ObstacleDistance& obstacle_distance) {
    const std::size_t num_triangles = triangles.size();
    // Walls: the triangles of intersecting pairs; partners[t]: the triangles t intersects.
    std::vector<std::uint8_t> wall(num_triangles, 0);
    std::vector<std::array<std::int32_t, 2>> directed;
    directed.reserve(2 * pairs.size());
    for (const auto& [a, b] : pairs) {
        wall[static_cast<std::size_t>(a)] = 1;
        wall[static_cast<std::size_t>(b)] = 1;
        directed.push_back({a, b});
        directed.push_back({b, a});
    }
    std::sort(directed.begin(), directed.end());
    std::vector<std::int32_t> region;
    std::vector<std::int32_t> stack;
    const std::int32_t num_regions = edge_components(topology, wall, region, stack);
    // Per region: its triangles (CSR), size and piece; per piece its largest region.
    std::vector<std::int32_t> region_offsets;
    std::vector<std::int32_t> region_triangles;
    group_by_key(region, static_cast<std::size_t>(num_regions), region_offsets, region_triangles);
    const auto size_of = [&](std::int32_t r) {
        return region_offsets[static_cast<std::size_t>(r) + 1] -
               region_offsets[static_cast<std::size_t>(r)];
    };
    std::vector<std::int32_t> region_piece(static_cast<std::size_t>(num_regions));
    std::vector<std::int32_t> largest_of_piece(pieces.count, -1);
    for (std::int32_t r = 0; r < num_regions; ++r) {
        const std::int32_t first =
            region_triangles[static_cast<std::size_t>(region_offsets[static_cast<std::size_t>(r)])];
        region_piece[static_cast<std::size_t>(r)] =
            pieces.of_triangle[static_cast<std::size_t>(first)];
        std::int32_t& largest =
            largest_of_piece[static_cast<std::size_t>(region_piece[static_cast<std::size_t>(r)])];
        if (largest < 0 || size_of(r) > size_of(largest)) {
            largest = r;
        }
    }
    // Candidates: every region but the largest of its piece (cut off from it by walls),
    // smallest first.
    std::vector<std::int32_t> candidates;
    for (std::int32_t r = 0; r < num_regions; ++r) {
        if (largest_of_piece[static_cast<std::size_t>(region_piece[static_cast<std::size_t>(r)])] !=
            r) {
            candidates.push_back(r);
        }
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [&](std::int32_t a, std::int32_t b) { return size_of(a) < size_of(b); });
    std::vector<std::uint8_t> blocked(static_cast<std::size_t>(num_regions), 0);
    std::vector<std::uint8_t> moved(x.size(), 0);
    std::vector<std::int32_t> walls;
    std::vector<std::int32_t> others;
    std::vector<std::int32_t> region_vertices;
    bool flipped = false;
    for (const std::int32_t r : candidates) {
        if (blocked[static_cast<std::size_t>(r)] != 0) {
            continue;
        }
        const auto members =
            std::span(region_triangles)
                .subspan(static_cast<std::size_t>(region_offsets[static_cast<std::size_t>(r)]),
                         static_cast<std::size_t>(size_of(r)));
        // The walls around the region, and what they intersect: the other layer.
        walls.clear();
        bool pinned = false;
        for (const std::int32_t t : members) {
            for (const std::int32_t v : triangles[static_cast<std::size_t>(t)]) {
                pinned = pinned || !(inverse_masses[static_cast<std::size_t>(v)] > 0.0);
            }
            for (const std::int32_t e : topology.triangle_edges[static_cast<std::size_t>(t)]) {
                for (const std::int32_t u : topology.triangles_of_edge(e)) {
                    if (wall[static_cast<std::size_t>(u)] != 0) {
                        walls.push_back(u);
                    }
                }
            }
        }
        std::sort(walls.begin(), walls.end());
        walls.erase(std::unique(walls.begin(), walls.end()), walls.end());
        others.clear();
        for (const std::int32_t w : walls) {
            auto it = std::lower_bound(directed.begin(), directed.end(),
                                       std::array<std::int32_t, 2>{w, INT32_MIN});
            for (; it != directed.end() && (*it)[0] == w; ++it) {
                others.push_back((*it)[1]);
            }
        }
        std::sort(others.begin(), others.end());
        others.erase(std::unique(others.begin(), others.end()), others.end());
        if (pinned || others.empty()) {
            continue;
        }
        // The other layer's plane there (of the triangles the walls intersect).
        const std::optional<geometry::FittedPlane> plane =
            geometry::fit_plane(x, triangles, others, MIN_PLANE_AGREEMENT);
        if (!plane) {
            continue;
        }
        const Vec3d& centre = plane->centre;
        const Vec3d& normal = plane->normal;
        // The region's side of that plane (its vertices' mean signed distance), then every
        // vertex of the region on that side is reflected to the other, `clearance` beyond it.
        double side_sum = 0.0;
        for (const std::int32_t t : members) {
            for (const std::int32_t v : triangles[static_cast<std::size_t>(t)]) {
                side_sum += dot(normal, x[static_cast<std::size_t>(v)] - centre);
            }
        }
        if (!(side_sum != 0.0)) {
            continue;
        }
        const double side = side_sum > 0.0 ? 1.0 : -1.0;
        // The region folds over, reflected through the other layer's plane to `clearance`
        // beyond it, unless that takes a vertex into an obstacle.
        const auto reflected = [&](std::size_t k) {
            return x[k] - normal * (2.0 * dot(normal, x[k] - centre) + side * clearance);
        };
        const auto folds = [&](std::size_t k) {
            return moved[k] == 0 && dot(normal, x[k] - centre) * side > 0.0;
        };
        if (obstacle_distance) {
            region_vertices.clear();
            for (const std::int32_t t : members) {
                const geometry::Triangle& tri = triangles[static_cast<std::size_t>(t)];
                region_vertices.insert(region_vertices.end(), tri.begin(), tri.end());
            }
            std::sort(region_vertices.begin(), region_vertices.end());
            region_vertices.erase(std::unique(region_vertices.begin(), region_vertices.end()),
                                  region_vertices.end());
            if (std::any_of(region_vertices.begin(), region_vertices.end(), [&](std::int32_t v) {
                    const auto k = static_cast<std::size_t>(v);
                    return folds(k) && enters_obstacle(obstacle_distance, x[k], reflected(k));
                })) {
                continue;
            }
        }
        for (const std::int32_t t : members) {
            for (const std::int32_t v : triangles[static_cast<std::size_t>(t)]) {
                const auto k = static_cast<std::size_t>(v);
                if (folds(k)) {
                    x[k] = reflected(k);
                    moved[k] = 1;
                }
            }
        }
        flipped = true;
        // One flip per contour: neither the other layer's regions along it nor this one again.
        blocked[static_cast<std::size_t>(r)] = 1;
        for (const std::int32_t o : others) {
            for (const std::int32_t e : topology.triangle_edges[static_cast<std::size_t>(o)]) {
                for (const std::int32_t u : topology.triangles_of_edge(e)) {
                    if (region[static_cast<std::size_t>(u)] >= 0) {
                        blocked[static_cast<std::size_t>(region[static_cast<std::size_t>(u)])] = 1;
                    }
                }
            }
        }
    }
    return flipped;
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
    // The connected pieces of cloth, for the region moves.
    const Pieces pieces = find_pieces(triangles, inverse_masses);
    int since_best = 0;
    bool move_tried = false;  // the best state has had its region move
    int moves = 0;            // region moves made so far
    int best_moves = 0;       // those that led to the best state
    std::vector<Vec3d> trial;
    for (int iteration = 0; iteration < options.max_iterations && !pairs.empty() && step > 0.0;
         ++iteration) {
        if (since_best >= STALL_ITERATIONS && !move_tried) {
            // Contour minimization stalls on contours that run from boundary to boundary: one
            // region move from the best state (one per best state: when it leads to no better
            // state, minimization goes on from it; when none applies, from where it is).
            since_best = 0;
            move_tried = true;
            trial = best;
            const std::vector<std::array<std::int32_t, 2>> best_state_pairs =
                collision::find_intersecting_pairs(std::span<const Vec3d>(trial), triangles);
            if (separate_pieces(trial, triangles, pieces, best_state_pairs, step,
                                options.obstacle_distance) ||
                flip_regions(trial, triangles, topology, pieces, inverse_masses, best_state_pairs,
                             step, options.obstacle_distance)) {
                std::copy(trial.begin(), trial.end(), positions.begin());
                ++moves;
                ++result.iterations;
                pairs = collision::find_intersecting_pairs(std::span<const Vec3d>(positions),
                                                           triangles);
                if (static_cast<std::int64_t>(pairs.size()) < best_pairs) {
                    best_pairs = static_cast<std::int64_t>(pairs.size());
                    best.assign(positions.begin(), positions.end());
                    best_moves = moves;
                    move_tried = false;
                }
                continue;
            }
        }
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
            best_moves = moves;
            move_tried = false;
            since_best = 0;
        } else {
            ++since_best;
        }
    }
    std::copy(best.begin(), best.end(), positions.begin());
    result.region_moves = best_moves;
    result.final_pairs = best_pairs;
    for (std::size_t v = 0; v < n; ++v) {
        result.max_displacement = std::max(result.max_displacement, norm(positions[v] - start[v]));
    }
    result.ms = watch.elapsed_ms();
    return result;
}

}  // namespace pliant::cloth
