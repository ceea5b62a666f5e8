// Image comparisons for the ray-casting tests (render and integration): PSNR of 8-bit images, the
// pixel-centre rays of a camera, and the largest 8-bit difference between render_rays()' float
// colours and an image.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <span>
#include <vector>

#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"

namespace pliant::test {

// PSNR of b against a over every 8-bit channel, in dB (peak 255); 200 for equal images. The
// images must have the same size (a test failure otherwise).
inline double psnr(const render::Image& a, const render::Image& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    double sum = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        const double e = static_cast<double>(a.pixels[i]) - static_cast<double>(b.pixels[i]);
        sum += e * e;
    }
    const double mse = sum / static_cast<double>(a.pixels.size());
    return mse == 0.0 ? 200.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

// cam's pixel-centre rays (Camera::pixel_ray), row by row.
inline std::vector<render::Ray> pixel_rays(const render::Camera& cam) {
    std::vector<render::Ray> rays;
    for (int j = 0; j < cam.height(); ++j) {
        for (int i = 0; i < cam.width(); ++i) {
            rays.push_back(cam.pixel_ray(i, j));
        }
    }
    return rays;
}

// The largest difference, in 8-bit levels over every channel, between the colours rgb (3 floats
// per pixel, in the image's pixel order, as to_rgb8() rounds them) and image's pixels.
inline int max_level_difference(std::span<const float> rgb, const render::Image& image) {
    int worst = 0;
    for (std::size_t p = 0; 3 * p + 2 < rgb.size(); ++p) {
        const render::Rgb8 c = render::to_rgb8({rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2]});
        worst = std::max({worst, std::abs(c.r - image.pixels[3 * p]),
                          std::abs(c.g - image.pixels[3 * p + 1]),
                          std::abs(c.b - image.pixels[3 * p + 2])});
    }
    return worst;
}

}  // namespace pliant::test
