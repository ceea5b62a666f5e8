#include "pliant/pbd/detail/integration.hpp"

#include <cstddef>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"

namespace pliant::pbd::detail {

void predict(Float4* x, std::span<Vec3f> previous, std::span<const Vec3f> velocities,
             std::span<const float> inv_masses, const SubstepMotion& m) {
    parallel_for(
        static_cast<std::int64_t>(previous.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            Vec3f vel = velocities[v];
            predict_vertex(x[v], previous[v], vel, inv_masses[v], m);
        },
        VERTEX_GRAIN);
}

void update_velocities_and_predict(Float4* x, std::span<Vec3f> previous,
                                   std::span<const float> inv_masses,
                                   std::span<const std::uint8_t> pinned, const SubstepMotion& m) {
    parallel_for(
        static_cast<std::int64_t>(previous.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            Vec3f vel = pinned[v] != 0 ? Vec3f{} : substep_velocity(x[v], previous[v], m);
            predict_vertex(x[v], previous[v], vel, inv_masses[v], m);
        },
        VERTEX_GRAIN);
}

void update_velocities(const Float4* x, std::span<const Vec3f> previous,
                       std::span<const std::uint8_t> pinned, const SubstepMotion& m,
                       std::span<Vec3f> velocities, std::span<Vec3f> positions) {
    parallel_for(
        static_cast<std::int64_t>(previous.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            if (pinned[v] == 0) {
                velocities[v] = substep_velocity(x[v], previous[v], m);
            }
            positions[v] = {x[v].x, x[v].y, x[v].z};
        },
        VERTEX_GRAIN);
}

}  // namespace pliant::pbd::detail
