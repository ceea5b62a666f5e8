// The radiance field's forward pass against closed forms and its analytic backward pass against
// central finite differences.
#include "pliant/nerf/render.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::nerf {
namespace {

// A 6 × 5 × 4 grid over a non-cubic box with random raw parameters (densities around σ ≈ a few
// per unit so that rays are partly transparent).
RadianceGrid random_grid(std::uint32_t seed) {
    RadianceGrid grid(AABBd{{-1.0, -0.5, 0.0}, {2.0, 2.0, 2.0}}, 6, 0.0f, 0.0f);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> s(-6.0f, -3.0f), c(-2.0f, 2.0f);
    auto p = grid.params();
    for (std::size_t v = 0; v < p.size(); v += 4) {
        p[v] = s(rng);
        p[v + 1] = c(rng);
        p[v + 2] = c(rng);
        p[v + 3] = c(rng);
    }
    return grid;
}

std::vector<NormalizedRay> random_rays(const RadianceGrid& grid, int n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<NormalizedRay> rays;
    const Vec3d centre = grid.box().center();
    while (static_cast<int>(rays.size()) < n) {
        const Vec3d eye = centre + Vec3d{u(rng), u(rng), u(rng)} * 4.0;
        const Vec3d target = centre + Vec3d{u(rng), u(rng), u(rng)} * 0.8;
        const Vec3d d = target - eye;
        rays.push_back(normalize_ray(grid, {eye, d / norm(d)}));
    }
    return rays;
}

TEST(FieldRender, UniformMediumMatchesBeerLambert) {
    // Uniform σ and colour: a ray through the box along x renders c (1 − exp(−σ L)) + bg · T.
    RadianceGrid grid(AABBd{{0, 0, 0}, {1, 1, 1}}, 8, density_raw_for_sigma(3.0f), 1.0f);
    const NormalizedRay ray{{-1.0f, 0.5f, 0.5f}, {1.0f, 0.0f, 0.0f}};
    const float bg[3] = {0.2f, 0.4f, 0.6f};
    for (const float step : {0.01f, 0.07f, 0.3f}) {
        const detail::RayOutput out = detail::march(grid.view(), ray.origin, ray.direction, step,
                                                    bg, 0.0f, [](const detail::SampleRecord&) {});
        const float T = std::exp(-3.0f);
        const float c = 1.0f / (1.0f + std::exp(-1.0f));
        EXPECT_NEAR(out.transmittance, T, 1e-5f) << step;
        EXPECT_NEAR(out.rgb[0], c * (1 - T) + bg[0] * T, 1e-5f) << step;
        EXPECT_NEAR(out.rgb[2], c * (1 - T) + bg[2] * T, 1e-5f) << step;
    }
}

TEST(FieldRender, GradientMatchesFiniteDifferences) {
    RadianceGrid grid = random_grid(7);
    const std::vector<NormalizedRay> rays = random_rays(grid, 12, 3);
    std::vector<float> targets(3 * rays.size());
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> t(0.0f, 1.0f);
    for (float& x : targets) {
        x = t(rng);
    }
    FieldRenderOptions options;
    options.step_voxels = 0.37f;
    options.min_transmittance = 0.0f;  // the function must be smooth in every parameter
    const render::Color bg{0.1f, 0.5f, 0.9f};
    std::vector<float> grad(grid.params().size(), 0.0f);
    photometric_loss(grid, rays, targets, bg, options, grad);

    // Central differences in double over the float kernel: h = 1e-2 keeps rounding (≈1e-7 / h)
    // below the truncation error (≈ h² · third derivative).
    const auto loss = [&] {
        std::vector<float> ignored(grid.params().size(), 0.0f);
        return photometric_loss(grid, rays, targets, bg, options, ignored);
    };
    double max_grad = 0.0;
    for (float g : grad) {
        max_grad = std::max(max_grad, static_cast<double>(std::fabs(g)));
    }
    ASSERT_GT(max_grad, 0.0);
    int checked = 0;
    for (std::size_t i = 0; i < grad.size(); ++i) {
        if (std::fabs(grad[i]) < 1e-2 * max_grad) {
            // Entries the rays barely touch: the float loss's rounding (about 1e-9 per ray,
            // divided by 2h) is then a sizeable part of the difference quotient.
            continue;
        }
        const float h = 1e-2f;
        const float keep = grid.params()[i];
        grid.params()[i] = keep + h;
        const double plus = loss();
        grid.params()[i] = keep - h;
        const double minus = loss();
        grid.params()[i] = keep;
        const double fd = (plus - minus) / (2.0 * h);
        EXPECT_NEAR(grad[i], fd, 2e-2 * std::fabs(fd))
            << "parameter " << i << " (channel " << i % 4 << ")";
        ++checked;
    }
    EXPECT_GT(checked, 50);  // density and colour parameters of many voxels
}

TEST(FieldRender, RenderViewIsIdenticalForOneAndTwoThreads) {
    const RadianceGrid grid = random_grid(11);
    render::Camera cam = render::frame_box(grid.box(), 30, 20, 32, 24);
    const Intrinsics in = intrinsics_from_camera(cam);
    const Pose pose = pose_from_camera(cam);
    set_num_threads(1);
    const std::vector<float> a = render_view(grid, in, pose, {0.f, 0.f, 0.f});
    set_num_threads(2);
    const std::vector<float> b = render_view(grid, in, pose, {0.f, 0.f, 0.f});
    set_num_threads(0);
    EXPECT_EQ(a, b);
}

TEST(FieldRender, LossRejectsMismatchedSizes) {
    const RadianceGrid grid = random_grid(1);
    const std::vector<NormalizedRay> rays = random_rays(grid, 2, 1);
    std::vector<float> targets(5), grad(grid.params().size());
    EXPECT_THROW(photometric_loss(grid, rays, targets, {}, {}, grad), InvalidInput);
}

}  // namespace
}  // namespace pliant::nerf
