// Vec3f: a 3-vector of floats, plain old data (12 bytes, trivially copyable) so that kernels can
// take spans of it on any backend. Vec3d for sums and exact-ish reference computations.
#pragma once

#include <cmath>
#include <type_traits>

#include "pliant/core/host_device.hpp"

namespace pliant {

template <typename T>
struct Vec3 {
    T x{}, y{}, z{};

    PLIANT_HOST_DEVICE constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    PLIANT_HOST_DEVICE constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }

    PLIANT_HOST_DEVICE constexpr Vec3& operator+=(Vec3 b) {
        x += b.x;
        y += b.y;
        z += b.z;
        return *this;
    }
    PLIANT_HOST_DEVICE constexpr Vec3& operator-=(Vec3 b) {
        x -= b.x;
        y -= b.y;
        z -= b.z;
        return *this;
    }
    PLIANT_HOST_DEVICE constexpr Vec3& operator*=(T s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    friend constexpr bool operator==(const Vec3&, const Vec3&) = default;
};

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;
static_assert(std::is_trivially_copyable_v<Vec3f> && sizeof(Vec3f) == 12);

template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> operator+(Vec3<T> a, Vec3<T> b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> operator-(Vec3<T> a, Vec3<T> b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> operator-(Vec3<T> a) {
    return {-a.x, -a.y, -a.z};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> operator*(Vec3<T> a, T s) {
    return {a.x * s, a.y * s, a.z * s};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> operator*(T s, Vec3<T> a) {
    return {a.x * s, a.y * s, a.z * s};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> operator/(Vec3<T> a, T s) {
    return {a.x / s, a.y / s, a.z / s};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr T dot(Vec3<T> a, Vec3<T> b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> cross(Vec3<T> a, Vec3<T> b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr T squared_norm(Vec3<T> a) {
    return dot(a, a);
}
template <typename T>
PLIANT_HOST_DEVICE inline T norm(Vec3<T> a) {
    return std::sqrt(dot(a, a));
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> min(Vec3<T> a, Vec3<T> b) {
    return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
template <typename T>
PLIANT_HOST_DEVICE constexpr Vec3<T> max(Vec3<T> a, Vec3<T> b) {
    return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}
template <typename T>
PLIANT_HOST_DEVICE inline bool is_finite(Vec3<T> a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
// Whether every coordinate of a lies in [−half_side, half_side] (false for NaN).
template <typename T>
PLIANT_HOST_DEVICE inline bool within_cube(Vec3<T> a, T half_side) {
    return std::abs(a.x) <= half_side && std::abs(a.y) <= half_side && std::abs(a.z) <= half_side;
}
template <typename To, typename From>
PLIANT_HOST_DEVICE constexpr Vec3<To> vec3_cast(Vec3<From> a) {
    return {static_cast<To>(a.x), static_cast<To>(a.y), static_cast<To>(a.z)};
}

}  // namespace pliant
