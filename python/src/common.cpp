#include "common.hpp"

#include <fmt/format.h>

#include <string>

#include "pliant/core/error.hpp"

namespace pliant::python {
namespace {

std::string shape_text(const py::array& array) {
    std::string text = "(";
    for (py::ssize_t d = 0; d < array.ndim(); ++d) {
        text += (d > 0 ? ", " : "") + std::to_string(array.shape(d));
    }
    return text + (array.ndim() == 1 ? ",)" : ")");
}

// What a guarded view's capsule holds: the owner (kept alive by the view) and its guard.
struct GuardedBase {
    py::object owner;
    ViewGuard* guard;
};

}  // namespace

void check_rows_shape(const py::array& array, std::size_t k, const char* what) {
    if (array.ndim() != 2 || array.shape(1) != static_cast<py::ssize_t>(k)) {
        throw InvalidInput(fmt::format("{}: expected an array of shape (N, {}), got shape {}", what,
                                       k, shape_text(array)));
    }
}

std::span<const Vec3d> vec3d_rows(const DoubleArray& array, const char* what) {
    return rows<Vec3d>(array, 3, what);
}

std::span<const Vec3f> vec3f_rows(const FloatArray& array, const char* what) {
    return rows<Vec3f>(array, 3, what);
}

void ViewGuard::check_none_alive(const char* who) const {
    if (live > 0) {
        throw InvalidInput(fmt::format(
            "{}: {} array view(s) of the current state are still alive and would point to freed "
            "memory; delete them (or keep a .copy()) first",
            who, live));
    }
}

py::capsule guard_base(py::handle owner, ViewGuard& guard) {
    auto* held = new GuardedBase{py::reinterpret_borrow<py::object>(owner), &guard};
    py::capsule base(held, [](void* p) {
        auto* h = static_cast<GuardedBase*>(p);
        --h->guard->live;
        delete h;  // releases the owner after the count: the guard lives in it
    });
    ++guard.live;
    return base;
}

py::object to_python(const nlohmann::ordered_json& json) {
    return py::module_::import("json").attr("loads")(json.dump());
}

}  // namespace pliant::python
