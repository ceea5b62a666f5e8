// The records of volume::InverseMap's construction that its scratch keeps between builds (hence in
// a header): a deformed tet's affine map, a node's value as a tet recorded it.
#pragma once

#include <algorithm>
#include <cstdint>

#include "pliant/core/vec3.hpp"

namespace pliant::volume::detail {

// A deformed tet's affine map in target grid coordinates: λk = rows[k] · (x − p3) for k < 3,
// λ3 = 1 − λ0 − λ1 − λ2, rest r = r3 + Σ λk dr[k] (source grid coordinates).
struct TetMap {
    Vec3d p3, r3;
    Vec3d rows[3];
    Vec3d dr[3];
    bool ok = false;

    // The smallest barycentric coordinate of x (≥ 0: inside); l[0..2] = λ0..2.
    double lambda(const Vec3d& x, double l[3]) const {
        const Vec3d d = x - p3;
        l[0] = dot(rows[0], d);
        l[1] = dot(rows[1], d);
        l[2] = dot(rows[2], d);
        return std::min({l[0], l[1], l[2], 1.0 - l[0] - l[1] - l[2]});
    }
    Vec3d rest(const double l[3]) const { return r3 + dr[0] * l[0] + dr[1] * l[1] + dr[2] * l[2]; }
};

// A tet that raised a node's holder to its index in InverseMap::build's pass over the tets, and
// its map's value at the node (the node's value if the tet is its holder in the end).
struct HeldValue {
    std::int64_t node;
    std::int32_t tet;
    float value[3];
};

}  // namespace pliant::volume::detail
