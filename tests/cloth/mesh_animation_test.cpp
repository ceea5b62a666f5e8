#include "pliant/cloth/mesh_animation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::cloth {
namespace {

// Three frames of two vertices: vertex 0 moves along x, vertex 1 along z.
std::vector<std::vector<Vec3d>> three_frames() {
    return {{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}},
            {{0.3, 0.0, 0.0}, {1.0, 0.0, 0.5}},
            {{0.9, 0.0, 0.0}, {1.0, 0.0, 0.0}}};
}

std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "no exception";
}

TEST(MeshAnimation, FrameTimesGiveTheFramesExactly) {
    const MeshAnimation animation(three_frames(), 24.0, false);
    std::vector<Vec3d> out(2);
    for (std::size_t k = 0; k < 3; ++k) {
        animation.positions_at(static_cast<double>(k) / 24.0, out);
        EXPECT_EQ(out[0], animation.frame(k)[0]) << k;
        EXPECT_EQ(out[1], animation.frame(k)[1]) << k;
        EXPECT_EQ(animation.position_at(1, static_cast<double>(k) / 24.0), animation.frame(k)[1]);
    }
}

TEST(MeshAnimation, InterpolatesLinearlyBetweenFrames) {
    const MeshAnimation animation(three_frames(), 10.0, false);
    std::vector<Vec3d> out(2);
    // A quarter of the way from frame 1 (t = 0.1 s) to frame 2 (t = 0.2 s).
    animation.positions_at(0.125, out);
    EXPECT_NEAR(out[0].x, 0.3 + 0.25 * 0.6, 1e-15);
    EXPECT_NEAR(out[1].z, 0.5 - 0.25 * 0.5, 1e-15);
    EXPECT_EQ(animation.position_at(0, 0.125), out[0]);
    // Held before the start and after the end without loop.
    animation.positions_at(-1.0, out);
    EXPECT_EQ(out[0], animation.frame(0)[0]);
    animation.positions_at(5.0, out);
    EXPECT_EQ(out[1], animation.frame(2)[1]);
}

TEST(MeshAnimation, LoopBlendsTheLastFrameBackIntoTheFirst) {
    const MeshAnimation animation(three_frames(), 10.0, true);
    std::vector<Vec3d> out(2);
    // Period 0.3 s: t = 0.25 s is halfway from frame 2 back to frame 0.
    animation.positions_at(0.25, out);
    EXPECT_NEAR(out[0].x, 0.45, 1e-12);
    EXPECT_NEAR(out[1].z, 0.0, 1e-12);
    // One period later, the same.
    std::vector<Vec3d> later(2);
    animation.positions_at(0.25 + 0.3 * 7, later);
    EXPECT_NEAR(later[0].x, 0.45, 1e-9);
    // Frame 0 again at whole periods.
    animation.positions_at(0.0, out);
    EXPECT_EQ(out[0], animation.frame(0)[0]);
    // The wrap counts in the fastest step: frame 2 → 0 moves vertex 0 by 0.9 m per 0.1 s.
    EXPECT_NEAR(animation.max_vertex_step(0.01), 0.09, 1e-12);
    EXPECT_NEAR(MeshAnimation(three_frames(), 10.0, false).max_vertex_step(0.01), 0.06, 1e-12);
}

TEST(MeshAnimation, RejectsFramesOfAnotherTopologyAndBadValues) {
    auto frames = three_frames();
    frames[2].push_back({0.0, 0.0, 0.0});
    EXPECT_EQ(message_of([&] { MeshAnimation(frames, 24.0, false); }),
              "cloth::MeshAnimation: frame 2 has 3 vertices, frame 0 has 2: expected the same "
              "topology in every frame");
    frames = three_frames();
    frames[1][1].y = std::numeric_limits<double>::quiet_NaN();
    EXPECT_NE(message_of([&] { MeshAnimation(frames, 24.0, false); }).find("frame 1, vertex 1"),
              std::string::npos);
    EXPECT_NE(message_of([&] { MeshAnimation({}, 24.0, false); }).find("no frames"),
              std::string::npos);
    EXPECT_NE(message_of([&] { MeshAnimation(three_frames(), 0.0, false); }).find("fps 0"),
              std::string::npos);
    EXPECT_NE(message_of([&] {
                  MeshAnimation(three_frames(), std::numeric_limits<double>::quiet_NaN(), true);
              }).find("fps"),
              std::string::npos);
    const MeshAnimation animation(three_frames(), 24.0, false);
    std::vector<Vec3d> wrong(3);
    EXPECT_THROW(animation.positions_at(0.0, wrong), InvalidInput);
}

}  // namespace
}  // namespace pliant::cloth
