// PSNR and SSIM against hand-computed values.
#include "pliant/nerf/metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::nerf {
namespace {

std::vector<float> noise_image(int w, int h, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> img(3 * static_cast<std::size_t>(w) * h);
    for (float& x : img) {
        x = u(rng);
    }
    return img;
}

TEST(Metrics, PsnrOfAConstantOffset) {
    std::vector<float> a(300, 0.5f), b(300, 0.6f);
    EXPECT_NEAR(psnr(a, b), 20.0, 1e-5);  // MSE 0.01
    EXPECT_TRUE(std::isinf(psnr(a, a)));
}

TEST(Metrics, SsimIsOneForIdenticalImagesAndDropsWithNoise) {
    const std::vector<float> a = noise_image(32, 24, 1);
    EXPECT_NEAR(ssim(a, a, 32, 24), 1.0, 1e-12);
    std::vector<float> b = a;
    std::mt19937 rng(2);
    std::normal_distribution<float> n(0.0f, 0.1f);
    for (float& x : b) {
        x += n(rng);
    }
    const double s = ssim(a, b, 32, 24);
    EXPECT_LT(s, 0.95);
    EXPECT_GT(s, 0.3);
    // Unrelated noise images are nearly uncorrelated.
    EXPECT_LT(std::fabs(ssim(a, noise_image(32, 24, 3), 32, 24)), 0.2);
}

TEST(Metrics, SsimOfAConstantShiftFollowsTheLuminanceTerm) {
    // Flat images x and y = x + d: variances 0, so SSIM = (2 x y + C1) / (x² + y² + C1).
    const std::vector<float> a(3 * 16 * 16, 0.4f), b(3 * 16 * 16, 0.5f);
    const double c1 = 1e-4;
    EXPECT_NEAR(ssim(a, b, 16, 16), (2 * 0.4 * 0.5 + c1) / (0.16 + 0.25 + c1), 1e-6);
}

TEST(Metrics, RejectsMismatchedSizes) {
    const std::vector<float> a(12), b(9);
    EXPECT_THROW(psnr(a, b), InvalidInput);
    EXPECT_THROW(ssim(a, a, 3, 2), InvalidInput);
}

}  // namespace
}  // namespace pliant::nerf
