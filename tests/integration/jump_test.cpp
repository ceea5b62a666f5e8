// Violent input (docs/reliability.md): a ribbon whose pinned row jumps 1.6 m in the first substep
// and whose lower end starts inside a sphere. Loading warns about the jump (naming the pin group,
// its distance per substep and the frame); the pins chase their target at half the thickness per
// substep (2.5 mm: 1.6 m takes 640 substeps, 16 frames of 40), which stats.json reports per frame
// (pins_lagging, pins_max_lag) and a warning reports once; the self-collision fail-safe stays
// within its budget of pair tests (cloth/ccd_fail_safe.hpp) and every frame stays
// intersection-free by the exact check of the written frame.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "integration/run_cli.hpp"

namespace pliant::test {
namespace {

// scenes/stress/jump_ribbon.json at a quarter of its triangles (40 x 20 quads).
constexpr const char* JUMP_RIBBON = R"({
  "cloth": {"grid": {"size": [0.5, 2.0], "quads": [20, 40]}, "rotate_degrees": [90, 0, 0],
            "translate": [0, 0, 1.5]},
  "pins": {"regions": [{"min": [-1, -1, 2.49], "max": [1, 1, 2.51]}],
           "motion": {"keyframes": [{"time": 0}, {"time": 0.001, "translate": [0, 1.6, 0]}]}},
  "obstacles": [{"sphere": {"center": [0, 0, 0.55], "radius": 0.2}}],
  "material": {"thickness": 0.005},
  "fps": 24, "frames": 18, "substeps": 40
})";

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
        ++n;
    }
    return n;
}

TEST(JumpingPins, ChaseTheirTargetWithinTheBudgetAndIntersectionFree) {
    ScratchDir scratch;
    std::ofstream(scratch / "jump.json") << JUMP_RIBBON;
    const CliResult r = run_cli("cloth " + quoted(scratch / "jump.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // The jump, at load time: the group, how far per substep, when, and what follows.
    EXPECT_NE(r.err.find("pliant: warning: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("pins: its motion covers up to 1.6 m in one substep (1.54e+03 m/s) "
                         "from t = 0 s (frame 1), more than the thickness (0.005 m) per substep: "
                         "the pins chase their keyframed target at half the thickness per substep"),
              std::string::npos)
        << r.err;
    // The lag, once.
    EXPECT_EQ(count(r.err, "pinned vertices lag behind their keyframed target"), 1u) << r.err;
    EXPECT_NE(r.err.find("frame 1: 21 pinned vertices lag behind their keyframed target, up to "
                         "1.5 m"),
              std::string::npos)
        << r.err;

    std::ifstream in(scratch / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
    const nlohmann::json& frames = stats.at("frames");
    ASSERT_EQ(frames.size(), 18u);
    // 2.5 mm per substep, 40 substeps per frame: 0.1 m per frame, independent of the cloth.
    const double step = 0.5 * 0.005;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const nlohmann::json& frame = frames[k];
        EXPECT_EQ(frame.at("intersecting_pairs"), 0) << k;
        // Within the budget: 10,000 pairs per window here (861 vertices), 10 windows.
        EXPECT_EQ(frame.at("fail_safe_budget_exceeded"), 0) << k;
        EXPECT_EQ(frame.at("fail_safe_frozen_vertices"), 0) << k;
        EXPECT_LE(frame.at("ccd_pairs").get<std::int64_t>(), 10 * 10'000) << k;
        // The row's lag shrinks by 40 steps per frame until it is on its target (frame 16).
        const double expected = std::max(0.0, 1.6 - step * 40.0 * static_cast<double>(k + 1));
        EXPECT_NEAR(frame.at("pins_max_lag").get<double>(), expected, 1e-9) << k;
        EXPECT_EQ(frame.at("pins_lagging"), expected > 1e-9 ? 21 : 0) << k;
    }
    // The pinned row (z = 2.5 at rest) on its target, 1.6 m along y, in the last frame written.
    std::ifstream last(scratch / "out" / "frames" / "frame_0018.obj");
    std::string line;
    int row = 0;
    while (std::getline(last, line)) {
        double x = 0.0;
        double y = 0.0;
        double z = 0.0;
        if (std::sscanf(line.c_str(), "v %lf %lf %lf", &x, &y, &z) == 3 &&
            std::fabs(z - 2.5) < 1e-6) {
            ++row;
            EXPECT_NEAR(y, 1.6, 1e-6) << line;  // written as float
        }
    }
    EXPECT_EQ(row, 21);
}

TEST(JumpingPins, SmoothMotionIsNotWarnedAbout) {
    // The same ribbon lowered by 0.2 m over 2 s (0.1 mm per substep), without the sphere its end
    // started in (pushing 71 vertices 0.2 m out in a substep is violent too).
    ScratchDir scratch;
    std::string scene = JUMP_RIBBON;
    const std::string sphere = R"({"sphere": {"center": [0, 0, 0.55], "radius": 0.2}})";
    scene.erase(scene.find(sphere), sphere.size());
    scene.replace(scene.find(R"({"time": 0.001, "translate": [0, 1.6, 0]})"),
                  std::string(R"({"time": 0.001, "translate": [0, 1.6, 0]})").size(),
                  R"({"time": 2, "translate": [0, 0, -0.2]})");
    std::ofstream(scratch / "smooth.json") << scene;
    const CliResult r = run_cli("cloth " + quoted(scratch / "smooth.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview --frames 1",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("in one substep"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("budget"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pliant::test
