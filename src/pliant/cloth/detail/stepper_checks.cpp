#include "pliant/cloth/detail/stepper_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::cloth::detail {

void check_step(const ClothModel& model, double dt, int substeps, std::size_t num_vertices,
                std::size_t num_triangles) {
    if (!(dt > 0.0) || !std::isfinite(dt) || substeps < 1) {
        throw InvalidInput(fmt::format(
            "cloth step: expected dt > 0 (finite) and substeps >= 1, got dt {} and substeps {}", dt,
            substeps));
    }
    if (model.num_vertices() != num_vertices || model.triangles().size() != num_triangles) {
        throw InvalidInput(fmt::format(
            "cloth step: the model has {} vertices and {} triangles, the stepper was built for {} "
            "and {}",
            model.num_vertices(), model.triangles().size(), num_vertices, num_triangles));
    }
}

std::unique_ptr<SelfCollision> make_self_collision(const ClothModel& model,
                                                   std::span<const double> rest_lengths) {
    const double thickness = model.material().thickness;
    if (!rest_lengths.empty()) {
        std::vector<double> lengths(rest_lengths.begin(), rest_lengths.end());
        const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
        std::nth_element(lengths.begin(), middle, lengths.end());
        if (thickness > MAX_THICKNESS_IN_EDGES * *middle) {
            throw InvalidInput(fmt::format(
                "cloth: self-collision: material.thickness ({} m) is {:.1f} times the median edge "
                "length ({:.3g} m), expected at most {}: every triangle would be within reach of "
                "hundreds of others; use a smaller thickness or a coarser mesh, or turn "
                "self_collision off",
                thickness, thickness / *middle, *middle, MAX_THICKNESS_IN_EDGES));
        }
    }
    return std::make_unique<SelfCollision>(model.triangles(), model.num_vertices(), thickness);
}

}  // namespace pliant::cloth::detail
