// AABB: an axis-aligned box [lo, hi] (closed), float (AABB) or double (AABBd). The empty box has
// lo = +inf, hi = -inf so that merging with it is the identity; min/max are exact, so merged boxes
// are bitwise independent of the order of merging (the BVH relies on this for deterministic
// refits).
#pragma once

#include <cmath>
#include <limits>
#include <type_traits>

#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant {

template <typename T>
struct BasicAABB {
    using Vec = Vec3<T>;
    static constexpr T INF = std::numeric_limits<T>::infinity();

    Vec lo{INF, INF, INF};
    Vec hi{-INF, -INF, -INF};

    PLIANT_HOST_DEVICE static constexpr BasicAABB of_point(Vec p) { return {p, p}; }
    PLIANT_HOST_DEVICE constexpr bool is_empty() const {
        return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z;
    }
    PLIANT_HOST_DEVICE constexpr void extend(Vec p) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    PLIANT_HOST_DEVICE constexpr void extend(const BasicAABB& b) {
        lo = min(lo, b.lo);
        hi = max(hi, b.hi);
    }
    // Grows the box by `h` on every side (h ≥ 0, world units).
    PLIANT_HOST_DEVICE constexpr BasicAABB inflated(T h) const {
        return {lo - Vec{h, h, h}, hi + Vec{h, h, h}};
    }
    PLIANT_HOST_DEVICE constexpr Vec center() const { return (lo + hi) * T(0.5); }
    PLIANT_HOST_DEVICE constexpr Vec extent() const { return hi - lo; }
    friend constexpr bool operator==(const BasicAABB&, const BasicAABB&) = default;
};

using AABB = BasicAABB<float>;
using AABBd = BasicAABB<double>;
static_assert(std::is_trivially_copyable_v<AABB> && sizeof(AABB) == 24);

template <typename T>
PLIANT_HOST_DEVICE constexpr BasicAABB<T> merge(const BasicAABB<T>& a, const BasicAABB<T>& b) {
    return {min(a.lo, b.lo), max(a.hi, b.hi)};
}

// Closed-interval overlap: boxes that touch at a face, edge or corner overlap. The six
// comparisons are combined without short-circuit: one branch at the caller instead of six
// unpredictable ones.
template <typename T>
PLIANT_HOST_DEVICE constexpr bool overlaps(const BasicAABB<T>& a, const BasicAABB<T>& b) {
    return (int{a.lo.x <= b.hi.x} & int{b.lo.x <= a.hi.x} & int{a.lo.y <= b.hi.y} &
            int{b.lo.y <= a.hi.y} & int{a.lo.z <= b.hi.z} & int{b.lo.z <= a.hi.z}) != 0;
}

template <typename T>
PLIANT_HOST_DEVICE constexpr bool contains(const BasicAABB<T>& outer, const BasicAABB<T>& inner) {
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

// The smallest float box containing `box` (each bound rounded outward), so that tests on float
// boxes never miss an overlap of the double boxes.
inline AABB outward_float(const AABBd& box) {
    const auto down = [](double v) {
        const auto f = static_cast<float>(v);
        return static_cast<double>(f) > v
                   ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                   : f;
    };
    const auto up = [](double v) {
        const auto f = static_cast<float>(v);
        return static_cast<double>(f) < v
                   ? std::nextafter(f, std::numeric_limits<float>::infinity())
                   : f;
    };
    return {{down(box.lo.x), down(box.lo.y), down(box.lo.z)},
            {up(box.hi.x), up(box.hi.y), up(box.hi.z)}};
}
inline AABB outward_float(const AABB& box) {
    return box;
}

}  // namespace pliant
