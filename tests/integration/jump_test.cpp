// Violent input (docs/reliability.md): a ribbon whose pinned row jumps 1.6 m in the first substep
// and whose lower end starts inside a sphere. Loading warns about the jump (naming the pin group,
// its distance per substep and the frame); the self-collision fail-safe exceeds its budget of
// pair tests (cloth/ccd_fail_safe.hpp), which stats.json reports per frame and a warning reports
// once; every frame stays intersection-free by the exact check of the written frame.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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
  "fps": 24, "frames": 3, "substeps": 40
})";

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
        ++n;
    }
    return n;
}

TEST(JumpingPins, AreWarnedAboutAndTheFailSafeStaysBoundedAndIntersectionFree) {
    ScratchDir scratch;
    std::ofstream(scratch / "jump.json") << JUMP_RIBBON;
    const CliResult r = run_cli("cloth " + quoted(scratch / "jump.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // The jump, at load time: the group, how far per substep, when.
    EXPECT_NE(r.err.find("pliant: warning: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("pins: its motion covers up to 1.6 m in one substep (1.54e+03 m/s) "
                         "from t = 0 s (frame 1), more than the thickness (0.005 m)"),
              std::string::npos)
        << r.err;
    // The budget, once.
    EXPECT_EQ(count(r.err, "the self-collision fail-safe had more pairs to test than its budget"),
              1u)
        << r.err;

    std::ifstream in(scratch / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
    ASSERT_EQ(stats.at("frames").size(), 3u);
    std::int64_t exceeded = 0;
    for (const nlohmann::json& frame : stats.at("frames")) {
        EXPECT_EQ(frame.at("intersecting_pairs"), 0);
        // At most the budget's pairs per window: 10,000 here (861 vertices), 10 windows.
        EXPECT_LE(frame.at("ccd_pairs").get<std::int64_t>(), 10 * 10'000);
        exceeded += frame.at("fail_safe_budget_exceeded").get<std::int64_t>();
        if (frame.at("fail_safe_budget_exceeded").get<std::int64_t>() > 0) {
            EXPECT_GT(frame.at("fail_safe_frozen_vertices").get<std::int64_t>(), 0);
        }
    }
    EXPECT_GT(exceeded, 0);
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
