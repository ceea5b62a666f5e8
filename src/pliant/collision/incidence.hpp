// Incidence tests between mesh features (shared vertices), for culling adjacent pairs. Written
// without short-circuit so they compile to branch-free code.
#pragma once

#include "pliant/core/host_device.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::collision {

PLIANT_HOST_DEVICE inline bool contains_vertex(const geometry::Triangle& t, std::int32_t v) {
    return (t[0] == v) | (t[1] == v) | (t[2] == v);
}

PLIANT_HOST_DEVICE inline bool share_vertex(const geometry::Triangle& a, const geometry::Triangle& b) {
    return contains_vertex(b, a[0]) | contains_vertex(b, a[1]) | contains_vertex(b, a[2]);
}

PLIANT_HOST_DEVICE inline bool share_vertex(const geometry::Edge& a, const geometry::Edge& b) {
    return (a[0] == b[0]) | (a[0] == b[1]) | (a[1] == b[0]) | (a[1] == b[1]);
}

}  // namespace pliant::collision
