#include "pliant/io/png.hpp"

#include <gtest/gtest.h>

#include <string>

#include "pliant/core/error.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using render::Image;
using render::Rgb8;
using test::expect_io_error;
using test::read_bytes;
using test::TempDir;
using test::write_bytes;

// Every byte value in every channel, odd sizes.
Image gradient(int w, int h) {
    Image image(w, h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            image.set(x, y,
                      {static_cast<std::uint8_t>(x * 7 + y), static_cast<std::uint8_t>(y * 13 + x),
                       static_cast<std::uint8_t>((x * y) ^ 0x5a)});
        }
    }
    return image;
}

TEST(Png, RoundTripIsExact) {
    const TempDir dir;
    for (const auto& [w, h] : {std::pair{1, 1}, std::pair{37, 23}, std::pair{256, 3}}) {
        const Image image = gradient(w, h);
        write_png(dir / "a.png", image);
        EXPECT_EQ(read_png(dir / "a.png"), image) << w << " x " << h;
    }
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.png"});  // no temporary left
    // Top-left origin: the first bytes of the decoded image are pixel (0, 0).
    const Image read = read_png(dir / "a.png");
    EXPECT_EQ(read.at(0, 0), (Rgb8{0, 0, 0x5a}));
    EXPECT_EQ(read.at(1, 0), (Rgb8{7, 1, 0x5a}));
}

TEST(Png, ReplacesAnExistingFileAtomically) {
    const TempDir dir;
    write_bytes(dir / "b.png", "old");
    write_png(dir / "b.png", gradient(4, 4));
    EXPECT_EQ(read_png(dir / "b.png"), gradient(4, 4));
}

TEST(Png, UnwritablePathsAndBadImages) {
    const TempDir dir;
    expect_io_error([&] { write_png(dir / "missing" / "c.png", gradient(3, 3)); },
                    {"missing", "c.png"});
    expect_io_error([&] { write_png(dir.path(), gradient(3, 3)); }, {});
    EXPECT_THROW(write_png(dir / "d.png", Image(0, 5)), InvalidInput);
    Image broken = gradient(3, 3);
    broken.pixels.pop_back();
    EXPECT_THROW(write_png(dir / "d.png", broken), InvalidInput);
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Png, BrokenFilesAreIoErrors) {
    const TempDir dir;
    expect_io_error([&] { read_png(dir / "nope.png"); }, {"nope.png"});
    write_bytes(dir / "text.png", "hello, not an image");
    expect_io_error([&] { read_png(dir / "text.png"); },
                    {"text.png", "not a PNG file", "68 65 6C 6C 6F"});
    write_bytes(dir / "empty.png", "");
    expect_io_error([&] { read_png(dir / "empty.png"); }, {"not a PNG file", "an empty file"});
    // A real PNG cut short, at several lengths (inside the header, inside the data).
    write_png(dir / "good.png", gradient(64, 64));
    const std::string bytes = read_bytes(dir / "good.png");
    ASSERT_GT(bytes.size(), 100u);
    for (const std::size_t keep :
         {std::size_t{12}, std::size_t{40}, bytes.size() / 2, bytes.size() - 20}) {
        write_bytes(dir / "cut.png", bytes.substr(0, keep));
        expect_io_error([&] { read_png(dir / "cut.png"); }, {"cut.png", "corrupt or truncated"});
    }
    // A corrupted byte in the compressed data.
    std::string corrupt = bytes;
    corrupt[bytes.size() / 2] = static_cast<char>(corrupt[bytes.size() / 2] ^ 0xff);
    corrupt[bytes.size() / 2 + 1] = static_cast<char>(corrupt[bytes.size() / 2 + 1] ^ 0x55);
    write_bytes(dir / "corrupt.png", corrupt);
    expect_io_error([&] { read_png(dir / "corrupt.png"); }, {"corrupt.png"});
}

}  // namespace
}  // namespace pliant::io
