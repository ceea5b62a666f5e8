// AABB: an axis-aligned box [lo, hi] (closed). The empty box has lo = +inf, hi = -inf so that
// merging with it is the identity; min/max are exact, so merged boxes are bitwise independent of
// the order of merging (the BVH relies on this for deterministic refits).
#pragma once

#include <limits>
#include <type_traits>

#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant {

struct AABB {
    Vec3f lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
             std::numeric_limits<float>::infinity()};
    Vec3f hi{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
             -std::numeric_limits<float>::infinity()};

    PLIANT_HOST_DEVICE static constexpr AABB of_point(Vec3f p) { return {p, p}; }
    PLIANT_HOST_DEVICE constexpr bool is_empty() const {
        return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z;
    }
    PLIANT_HOST_DEVICE constexpr void extend(Vec3f p) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    PLIANT_HOST_DEVICE constexpr void extend(const AABB& b) {
        lo = min(lo, b.lo);
        hi = max(hi, b.hi);
    }
    // Grows the box by `h` on every side (h ≥ 0, world units).
    PLIANT_HOST_DEVICE constexpr AABB inflated(float h) const {
        return {lo - Vec3f{h, h, h}, hi + Vec3f{h, h, h}};
    }
    PLIANT_HOST_DEVICE constexpr Vec3f center() const { return (lo + hi) * 0.5f; }
    PLIANT_HOST_DEVICE constexpr Vec3f extent() const { return hi - lo; }
    friend constexpr bool operator==(const AABB&, const AABB&) = default;
};
static_assert(std::is_trivially_copyable_v<AABB> && sizeof(AABB) == 24);

PLIANT_HOST_DEVICE constexpr AABB merge(const AABB& a, const AABB& b) {
    return {min(a.lo, b.lo), max(a.hi, b.hi)};
}

// Closed-interval overlap: boxes that touch at a face, edge or corner overlap.
PLIANT_HOST_DEVICE constexpr bool overlaps(const AABB& a, const AABB& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
           a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}

PLIANT_HOST_DEVICE constexpr bool contains(const AABB& outer, const AABB& inner) {
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

}  // namespace pliant
