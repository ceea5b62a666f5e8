#include "pliant/pbd/detail/chebyshev.hpp"

#include <cstddef>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"

namespace pliant::pbd::detail {

double chebyshev_omega(int iteration, double rho) {
    double omega = 1.0;
    const double rho2 = rho * rho;
    for (int k = 1; k <= iteration; ++k) {
        omega = k == 1 ? 2.0 / (2.0 - rho2) : 4.0 / (4.0 - rho2 * omega);
    }
    return omega;
}

void chebyshev_begin(const Float4* x, std::span<Vec3f> current, std::span<Vec3f> previous) {
    parallel_for(
        static_cast<std::int64_t>(current.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            current[v] = {x[v].x, x[v].y, x[v].z};
            previous[v] = current[v];
        },
        VERTEX_GRAIN);
}

void chebyshev_update(Float4* x, std::span<Vec3f> current, std::span<Vec3f> previous, float omega,
                      float gamma) {
    parallel_for(
        static_cast<std::int64_t>(current.size()),
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            const Vec3f q = current[v];
            Float4& p = x[v];
            if (p.w > 0.0f) {
                const Vec3f swept{p.x, p.y, p.z};
                const Vec3f& before = previous[v];
                const Vec3f next = (((swept - q) * gamma + q) - before) * omega + before;
                p = {next.x, next.y, next.z, p.w};
            }
            previous[v] = q;
            current[v] = {p.x, p.y, p.z};
        },
        VERTEX_GRAIN);
}

}  // namespace pliant::pbd::detail
