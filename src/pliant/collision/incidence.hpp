// Incidence tests between mesh features (shared vertices), for culling adjacent pairs. Written
// without short-circuit so they compile to branch-free code.
#pragma once

#include "pliant/core/host_device.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::collision {

PLIANT_HOST_DEVICE inline bool contains_vertex(const geometry::Triangle& t, std::int32_t v) {
    return (int{t[0] == v} | int{t[1] == v} | int{t[2] == v}) != 0;
}

PLIANT_HOST_DEVICE inline bool share_vertex(const geometry::Triangle& a,
                                            const geometry::Triangle& b) {
    return (int{contains_vertex(b, a[0])} | int{contains_vertex(b, a[1])} |
            int{contains_vertex(b, a[2])}) != 0;
}

PLIANT_HOST_DEVICE inline bool share_vertex(const geometry::Edge& a, const geometry::Edge& b) {
    return (int{a[0] == b[0]} | int{a[0] == b[1]} | int{a[1] == b[0]} | int{a[1] == b[1]}) != 0;
}

}  // namespace pliant::collision
