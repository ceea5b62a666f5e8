// Shared by the binding files: conversions between the library's small types and Python, numpy
// views of the library's arrays, and the per-area registration functions module.cpp calls.
//
// Arrays (docs in README.md, "From Python"):
//   - Output arrays are views of the C++ object's own memory (no copy) whose numpy base keeps
//     that object alive: points as (N, 3) float64 (Vec3d) or float32 (Vec3f), index tuples as
//     (N, K) int32, volumes as (nz, ny, nx[, 4]), images as (H, W, 3) uint8.
//   - Input arrays are read in place when they already are C-contiguous with the expected dtype
//     (numpy converts anything else once, on the way in); a C++ object that owns its data (a mesh,
//     a volume) copies them into its own vectors.
//   - Views of a buffer that a later call may free (a simulation's solver, which reset()
//     rebuilds) hang on a ViewGuard: the call refuses to free the buffer while a view is alive.
#pragma once

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"

namespace py = pybind11;

static_assert(sizeof(pliant::Vec3d) == 24 && alignof(pliant::Vec3d) == alignof(double));
static_assert(sizeof(pliant::Vec3f) == 12 && alignof(pliant::Vec3f) == alignof(float));
static_assert(sizeof(std::array<std::int32_t, 3>) == 12);
static_assert(sizeof(std::array<std::int32_t, 4>) == 16);
static_assert(sizeof(std::array<std::int32_t, 2>) == 8);

// Vec3<T> ↔ any sequence of 3 numbers (tuple, list, numpy array); returned as a tuple.
// BasicAABB<double> ↔ ((xmin, ymin, zmin), (xmax, ymax, zmax)).
namespace pybind11::detail {

template <typename T>
struct type_caster<pliant::Vec3<T>> {
    PYBIND11_TYPE_CASTER(pliant::Vec3<T>, const_name("tuple[float, float, float]"));

    bool load(handle src, bool convert) {
        if (!src || PyUnicode_Check(src.ptr()) || PyBytes_Check(src.ptr()) ||
            PySequence_Check(src.ptr()) == 0) {
            return false;
        }
        const auto seq = reinterpret_borrow<sequence>(src);
        if (seq.size() != 3) {
            return false;
        }
        for (int i = 0; i < 3; ++i) {
            make_caster<double> c;
            if (!c.load(seq[static_cast<std::size_t>(i)], convert)) {
                return false;
            }
            value[i] = static_cast<T>(cast_op<double>(c));
        }
        return true;
    }
    static handle cast(const pliant::Vec3<T>& v, return_value_policy, handle) {
        return make_tuple(static_cast<double>(v.x), static_cast<double>(v.y),
                          static_cast<double>(v.z))
            .release();
    }
};

template <>
struct type_caster<pliant::AABBd> {
    PYBIND11_TYPE_CASTER(
        pliant::AABBd, const_name("tuple[tuple[float, float, float], tuple[float, float, float]]"));

    bool load(handle src, bool convert) {
        if (!src || PyUnicode_Check(src.ptr()) || PySequence_Check(src.ptr()) == 0) {
            return false;
        }
        const auto seq = reinterpret_borrow<sequence>(src);
        if (seq.size() != 2) {
            return false;
        }
        make_caster<pliant::Vec3d> lo;
        make_caster<pliant::Vec3d> hi;
        if (!lo.load(seq[0], convert) || !hi.load(seq[1], convert)) {
            return false;
        }
        value.lo = cast_op<pliant::Vec3d>(lo);
        value.hi = cast_op<pliant::Vec3d>(hi);
        return true;
    }
    static handle cast(const pliant::AABBd& box, return_value_policy policy, handle parent) {
        return make_tuple(reinterpret_steal<object>(
                              make_caster<pliant::Vec3d>::cast(box.lo, policy, parent)),
                          reinterpret_steal<object>(
                              make_caster<pliant::Vec3d>::cast(box.hi, policy, parent)))
            .release();
    }
};

}  // namespace pybind11::detail

namespace pliant::python {

// Input arrays, read in place when C-contiguous and of this dtype (numpy converts others once).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using IndexArray = py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>;

// InvalidInput "<what>: expected an array of shape (N, <k>), got shape (…)" unless `array` is
// (N, k).
void check_rows_shape(const py::array& array, std::size_t k, const char* what);

// The rows of an (N, K) array as a span of K-element records (a view of the array's memory,
// valid while `array` lives). InvalidInput naming `what` for another shape.
template <typename Record, typename Array>
std::span<const Record> rows(const Array& array, std::size_t k, const char* what) {
    check_rows_shape(array, k, what);
    return {reinterpret_cast<const Record*>(array.data()),
            static_cast<std::size_t>(array.shape(0))};
}

std::span<const Vec3d> vec3d_rows(const DoubleArray& array, const char* what);
std::span<const Vec3f> vec3f_rows(const FloatArray& array, const char* what);
template <std::size_t K>
std::span<const std::array<std::int32_t, K>> index_rows(const IndexArray& array, const char* what) {
    return rows<std::array<std::int32_t, K>>(array, K, what);
}

// A numpy view of `count` records of `k` scalars starting at `data`, shape (count, k) (or (count,)
// for k = 0), whose base is `base` (kept alive by the view). Read-only unless `writeable`.
template <typename Scalar>
py::array records_view(const Scalar* data, std::size_t count, std::size_t k, py::handle base,
                       bool writeable) {
    const auto n = static_cast<py::ssize_t>(count);
    const auto item = static_cast<py::ssize_t>(sizeof(Scalar));
    py::array view = k == 0 ? py::array(py::dtype::of<Scalar>(), {n}, {item}, data, base)
                            : py::array(py::dtype::of<Scalar>(), {n, static_cast<py::ssize_t>(k)},
                                        {static_cast<py::ssize_t>(k) * item, item}, data, base);
    if (!writeable) {
        view.attr("setflags")(py::arg("write") = false);
    }
    return view;
}

inline py::array vec3_view(std::span<const Vec3d> points, py::handle base, bool writeable) {
    return records_view(points.empty() ? nullptr : &points[0].x, points.size(), 3, base, writeable);
}
inline py::array vec3_view(std::span<const Vec3f> points, py::handle base, bool writeable) {
    return records_view(points.empty() ? nullptr : &points[0].x, points.size(), 3, base, writeable);
}
template <std::size_t K>
py::array index_view(std::span<const std::array<std::int32_t, K>> records, py::handle base,
                     bool writeable) {
    return records_view(records.empty() ? nullptr : records.data()->data(), records.size(), K, base,
                        writeable);
}

// An array that owns `values` (moved into a capsule): no copy.
template <typename T>
py::array owning_array(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
    auto* owned = new std::vector<T>(std::move(values));
    const py::capsule base(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    return py::array(py::dtype::of<T>(), std::move(shape), owned->data(), base);
}

// Counts the live views of a buffer that its owner may free and rebuild (ClothSimulation::reset,
// DeformableVolume::reset_body). Views made by guarded_view hang on a capsule that holds the owner
// and decrements `live` when numpy frees the last view derived from it.
struct ViewGuard {
    std::int64_t live = 0;
    // InvalidInput "<who>: …" when a view is alive.
    void check_none_alive(const char* who) const;
};
// The base of a guarded view: holds `owner` (the Python object that owns `guard`) and counts
// itself in guard.live until numpy frees it.
py::capsule guard_base(py::handle owner, ViewGuard& guard);

// records_view (read-only) hung on a guard_base.
template <typename Scalar>
py::array guarded_view(const Scalar* data, std::size_t count, std::size_t k, py::handle owner,
                       ViewGuard& guard) {
    return records_view(data, count, k, guard_base(owner, guard), false);
}
template <typename T>
py::array guarded_vec3_view(std::span<const Vec3<T>> points, py::handle owner, ViewGuard& guard) {
    return guarded_view(points.empty() ? nullptr : &points[0].x, points.size(), 3, owner, guard);
}

// JSON results of the pipeline runs as Python dicts and lists.
py::object to_python(const nlohmann::ordered_json& json);

// Registration, one function per area (module.cpp calls them in this order).
void bind_errors(py::module_& m);
void bind_mesh(py::module_& m);
void bind_collision(py::module_& m);
void bind_cloth(py::module_& m);
void bind_volume(py::module_& m);
void bind_render(py::module_& m);
void bind_pbd(py::module_& m);
void bind_nerf(py::module_& m);

}  // namespace pliant::python
