// Independent checks of cloth against a closed body surface, for the tests of cloth on animated
// bodies (body_test.cpp, garment_test.cpp): brute force over the body's triangles, sharing no code
// with the solver's contact.
//   winding_number(body, p): the generalized winding number (A. Jacobson, L. Kavan,
//     O. Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized Winding Numbers",
//     ACM TOG 32(4), 2013): w(p) = Σ Ω_t(p) / 4π over the triangles, Ω the signed solid angle by
//     Van Oosterom and Strackee's formula; w ≥ 1 inside some part of a body of closed, outward
//     parts, 0 outside.
//   edges_crossing(cloth, body): the cloth's edges (of its triangles) that cross a triangle of
//     the body (edges_crossing(body, cloth): the body's edges through the cloth's triangles): the
//     segment's ends strictly on opposite sides of the triangle's plane and the line through them
//     strictly inside its three edges (orientation signs in double; a box test first).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <set>
#include <utility>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::test {

inline double winding_number(const geometry::TriangleMeshD& mesh, const Vec3d& p) {
    double sum = 0.0;
    for (const geometry::Triangle& t : mesh.triangles) {
        const Vec3d a = mesh.positions[static_cast<std::size_t>(t[0])] - p;
        const Vec3d b = mesh.positions[static_cast<std::size_t>(t[1])] - p;
        const Vec3d c = mesh.positions[static_cast<std::size_t>(t[2])] - p;
        const double la = norm(a);
        const double lb = norm(b);
        const double lc = norm(c);
        const double numerator = dot(a, cross(b, c));
        const double denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
        sum += 2.0 * std::atan2(numerator, denominator);
    }
    return sum / (4.0 * std::numbers::pi);
}

// Cloth vertices with winding number > 0.5 (inside the body).
inline int vertices_inside(const geometry::TriangleMeshD& cloth,
                           const geometry::TriangleMeshD& body) {
    int inside = 0;
    for (const Vec3d& p : cloth.positions) {
        inside += winding_number(body, p) > 0.5 ? 1 : 0;
    }
    return inside;
}

inline int edges_crossing(const geometry::TriangleMeshD& cloth,
                          const geometry::TriangleMeshD& body) {
    const auto orient = [](const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
        return dot(b - a, cross(c - a, d - a));
    };
    std::set<std::pair<std::int32_t, std::int32_t>> edges;
    for (const geometry::Triangle& t : cloth.triangles) {
        for (std::size_t k = 0; k < 3; ++k) {
            edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
        }
    }
    struct Box {
        Vec3d lo;
        Vec3d hi;
    };
    const auto box_of = [](std::initializer_list<Vec3d> points) {
        Box box{*points.begin(), *points.begin()};
        for (const Vec3d& p : points) {
            box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
            box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
        }
        return box;
    };
    std::vector<std::array<Vec3d, 3>> triangles;
    std::vector<Box> boxes;
    for (const geometry::Triangle& t : body.triangles) {
        triangles.push_back({body.positions[static_cast<std::size_t>(t[0])],
                             body.positions[static_cast<std::size_t>(t[1])],
                             body.positions[static_cast<std::size_t>(t[2])]});
        boxes.push_back(box_of({triangles.back()[0], triangles.back()[1], triangles.back()[2]}));
    }
    int crossing = 0;
    for (const auto& [i, j] : edges) {
        const Vec3d& p = cloth.positions[static_cast<std::size_t>(i)];
        const Vec3d& q = cloth.positions[static_cast<std::size_t>(j)];
        const Box e = box_of({p, q});
        for (std::size_t k = 0; k < triangles.size(); ++k) {
            const Box& b = boxes[k];
            if (e.hi.x < b.lo.x || b.hi.x < e.lo.x || e.hi.y < b.lo.y || b.hi.y < e.lo.y ||
                e.hi.z < b.lo.z || b.hi.z < e.lo.z) {
                continue;
            }
            const auto& [a, bb, c] = triangles[k];
            const double sp = orient(a, bb, c, p);
            const double sq = orient(a, bb, c, q);
            if (!(sp * sq < 0.0)) {
                continue;
            }
            const double e0 = orient(p, q, a, bb);
            const double e1 = orient(p, q, bb, c);
            const double e2 = orient(p, q, c, a);
            if ((e0 > 0.0 && e1 > 0.0 && e2 > 0.0) || (e0 < 0.0 && e1 < 0.0 && e2 < 0.0)) {
                ++crossing;
                break;
            }
        }
    }
    return crossing;
}

}  // namespace pliant::test
