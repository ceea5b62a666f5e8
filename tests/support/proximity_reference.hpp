// Long-double references and tolerances shared by the proximity tests (point-triangle,
// segment-segment): independent of the code under test, in higher precision.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <type_traits>

#include "pliant/core/vec3.hpp"

namespace pliant::test {

using Long = long double;
using Vec3L = Vec3<Long>;

template <typename Real>
Vec3L to_long(Vec3<Real> v) {
    return vec3_cast<Long>(v);
}

// Distance from p to the segment [start, end] (a point when start == end).
inline Long reference_point_segment_distance(Vec3L p, Vec3L start, Vec3L end) {
    const Vec3L direction = end - start;
    const Long squared_length = squared_norm(direction);
    Long parameter = 0;
    if (squared_length > 0) {
        parameter = std::clamp(dot(p - start, direction) / squared_length, Long(0), Long(1));
    }
    return norm(p - (start + direction * parameter));
}

// A sampled minimum distance and the bound on how much it can exceed the true minimum.
struct SampledDistance {
    Long min_distance;
    Long resolution;
};

// The largest |coordinate| of the points.
template <typename Real>
Long extent_of(std::initializer_list<Vec3<Real>> points) {
    Long extent = 0;
    for (const Vec3<Real> point : points) {
        extent = std::max(
            {extent, std::fabs(Long(point.x)), std::fabs(Long(point.y)), std::fabs(Long(point.z))});
    }
    return extent;
}

// Absolute distance tolerance: a few dozen ulps of the largest coordinate.
template <typename Real>
Long distance_tolerance(Long extent) {
    return 64 * Long(std::numeric_limits<Real>::epsilon()) * extent;
}

// A point of precision Real from double literals.
template <typename Real>
Vec3<Real> vec(double x, double y, double z) {
    return {static_cast<Real>(x), static_cast<Real>(y), static_cast<Real>(z)};
}

// Typed tests over float and double, named "float" / "double".
struct RealNames {
    template <typename T>
    static std::string GetName(int /*index*/) {
        return std::is_same_v<T, float> ? "float" : "double";
    }
};
using RealTypes = ::testing::Types<float, double>;

}  // namespace pliant::test
