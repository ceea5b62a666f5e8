// render::Image helpers: side_by_side against a pixel-by-pixel expectation.
#include "pliant/render/image.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace pliant::render {
namespace {

Image numbered(int width, int height, std::uint8_t base) {
    Image image(width, height);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const auto v = static_cast<std::uint8_t>(base + 10 * y + x);
            image.set(x, y,
                      {v, static_cast<std::uint8_t>(v + 1), static_cast<std::uint8_t>(v + 2)});
        }
    }
    return image;
}

TEST(Image, SideBySidePlacesEachImageAndFillsTheRest) {
    const std::vector<Image> images = {numbered(2, 3, 0), numbered(3, 1, 100), numbered(1, 2, 200)};
    const Rgb8 fill{7, 8, 9};
    const Image out = side_by_side(images, 2, fill);
    ASSERT_EQ(out.width, 2 + 2 + 3 + 2 + 1);
    ASSERT_EQ(out.height, 3);
    ASSERT_TRUE(out.is_consistent());
    int x0 = 0;
    for (const Image& image : images) {
        for (int y = 0; y < out.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                const Rgb8 expected = y < image.height ? image.at(x, y) : fill;
                EXPECT_EQ(out.at(x0 + x, y), expected) << x0 + x << "," << y;
            }
        }
        x0 += image.width;
        for (int g = 0; g < 2 && x0 < out.width; ++g, ++x0) {
            for (int y = 0; y < out.height; ++y) {
                EXPECT_EQ(out.at(x0, y), fill) << "gap column " << x0;
            }
        }
    }
}

TEST(Image, SideBySideOfNothingOrEmptyImagesIsEmpty) {
    EXPECT_EQ(side_by_side({}).width, 0);
    const std::vector<Image> empties = {Image(0, 4), Image(0, 0)};
    const Image out = side_by_side(empties, 0);
    EXPECT_EQ(out.width, 0);
    EXPECT_EQ(out.height, 4);
    EXPECT_TRUE(out.is_consistent());
}

}  // namespace
}  // namespace pliant::render
