// Image: an 8-bit RGB raster. width × height pixels, row-major, top-left origin (pixel (x, y) is
// column x counted rightwards, row y counted downwards), 3 bytes per pixel in R, G, B order,
// no padding between rows: pixel (x, y) starts at byte 3·(y·width + x). Values are stored as
// computed (no gamma curve; see DESIGN.md conventions).
//
// Color: a linear colour with float components, nominally in [0, 1]; to_rgb8 clamps and rounds.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace pliant::render {

struct Rgb8 {
    std::uint8_t r = 0, g = 0, b = 0;
    friend constexpr bool operator==(const Rgb8&, const Rgb8&) = default;
};

struct Color {
    float r = 0.0f, g = 0.0f, b = 0.0f;
    friend constexpr bool operator==(const Color&, const Color&) = default;
};

// Clamps each component to [0, 1] and rounds c·255 to nearest (NaN → 0).
inline Rgb8 to_rgb8(Color c) {
    const auto channel = [](float v) {
        const float clamped = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // NaN → 0
        return static_cast<std::uint8_t>(clamped * 255.0f +
                                         0.5f);  // non-negative: truncation rounds
    };
    return {channel(c.r), channel(c.g), channel(c.b)};
}

// c / 255 per channel (exact inverse of to_rgb8 on its outputs).
inline Color to_color(Rgb8 c) {
    return {static_cast<float>(c.r) / 255.0f, static_cast<float>(c.g) / 255.0f,
            static_cast<float>(c.b) / 255.0f};
}

struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> pixels;  // 3 · width · height bytes

    Image() = default;
    // A width × height image filled with `fill`. Precondition: width, height ≥ 0 (sizes are
    // validated by the producers: camera, rasterizer, readers).
    Image(int w, int h, Rgb8 fill = {})
        : width(w),
          height(h),
          pixels(3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h)) {
        for (std::size_t i = 0; i < pixels.size(); i += 3) {
            pixels[i] = fill.r;
            pixels[i + 1] = fill.g;
            pixels[i + 2] = fill.b;
        }
    }

    std::size_t num_pixels() const {
        return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    }
    // Byte offset of pixel (x, y). Precondition: 0 ≤ x < width, 0 ≤ y < height.
    std::size_t offset(int x, int y) const {
        return 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                    static_cast<std::size_t>(x));
    }
    Rgb8 at(int x, int y) const {
        const std::size_t o = offset(x, y);
        return {pixels[o], pixels[o + 1], pixels[o + 2]};
    }
    void set(int x, int y, Rgb8 c) {
        const std::size_t o = offset(x, y);
        pixels[o] = c.r;
        pixels[o + 1] = c.g;
        pixels[o + 2] = c.b;
    }
    // True when pixels holds exactly 3 · width · height bytes and both sizes are ≥ 0.
    bool is_consistent() const {
        return width >= 0 && height >= 0 && pixels.size() == 3 * num_pixels();
    }
    friend bool operator==(const Image&, const Image&) = default;
};

// The images side by side, left to right, `gap` pixels of `fill` between them, top-aligned; the
// result is as tall as the tallest and `fill` below the shorter ones. Precondition: every image
// is_consistent(), gap ≥ 0.
inline Image side_by_side(std::span<const Image> images, int gap = 0, Rgb8 fill = {}) {
    int width = 0;
    int height = 0;
    for (const Image& image : images) {
        width += image.width;
        height = std::max(height, image.height);
    }
    width += images.empty() ? 0 : gap * static_cast<int>(images.size() - 1);
    Image out(width, height, fill);
    int x0 = 0;
    for (const Image& image : images) {
        for (int y = 0; image.width > 0 && y < image.height; ++y) {
            std::memcpy(&out.pixels[out.offset(x0, y)], &image.pixels[image.offset(0, y)],
                        3 * static_cast<std::size_t>(image.width));
        }
        x0 += image.width + gap;
    }
    return out;
}

}  // namespace pliant::render
