#include "pliant/geometry/validate.hpp"

#include <fmt/format.h>

#include "pliant/core/error.hpp"

namespace pliant::geometry {

namespace {

template <typename Real>
void validate_positions_impl(std::span<const Vec3<Real>> positions, std::string_view what) {
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (!is_finite(positions[i])) {
            throw InvalidInput(fmt::format("{}: vertex {} has a non-finite coordinate ({}, {}, {})",
                                           what, i, positions[i].x, positions[i].y,
                                           positions[i].z));
        }
    }
}

}  // namespace

void validate_positions(std::span<const Vec3f> positions, std::string_view what) {
    validate_positions_impl(positions, what);
}
void validate_positions(std::span<const Vec3d> positions, std::string_view what) {
    validate_positions_impl(positions, what);
}

void validate_triangles(std::span<const Triangle> triangles, std::size_t num_vertices,
                        std::string_view what) {
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        const Triangle& tri = triangles[t];
        for (int k = 0; k < 3; ++k) {
            if (tri[k] < 0 || static_cast<std::size_t>(tri[k]) >= num_vertices) {
                throw InvalidInput(fmt::format(
                    "{}: triangle {} corner {} has vertex index {}, expected 0 <= index < {}", what,
                    t, k, tri[k], num_vertices));
            }
        }
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
            throw InvalidInput(fmt::format(
                "{}: triangle {} repeats a vertex ({}, {}, {}); expected three distinct indices",
                what, t, tri[0], tri[1], tri[2]));
        }
    }
}

}  // namespace pliant::geometry
