// External oracle, end to end: `pliant collide 227.ply --to 228.ply --json` on the cloth-funnel
// frames (../shared/data/cloth-funnel, see its README) must report exactly the 7,319 VF and
// 33,770 EE pairs computed independently (swept boxes, no inflation, closed overlap, features
// sharing no vertex). Skips when the shared data is absent, as in a user's own clone.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

#include "integration/run_cli.hpp"

namespace pliant::test {
namespace {

TEST(Funnel, SweptStepMatchesOracle) {
    const std::filesystem::path frames =
        std::filesystem::path(PLIANT_SHARED_DATA_DIR) / "cloth-funnel" / "frames";
    const std::filesystem::path frame_t0 = frames / "227.ply";
    const std::filesystem::path frame_t1 = frames / "228.ply";
    if (!std::filesystem::exists(frame_t0) || !std::filesystem::exists(frame_t1)) {
        GTEST_SKIP() << "external data not found: " << frame_t0.string() << " and "
                     << frame_t1.string()
                     << " (the cloth-funnel frames live in ../shared/data beside the project)";
    }
    ScratchDir scratch;
    const CliResult r =
        run_cli("collide " + quoted(frame_t0) + " --to " + quoted(frame_t1) + " --json", scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json json = nlohmann::json::parse(r.out);
    EXPECT_EQ(json.at("vertices").get<std::int64_t>(), 9450);
    EXPECT_EQ(json.at("triangles").get<std::int64_t>(), 18484);
    EXPECT_TRUE(json.at("swept").get<bool>());
    EXPECT_EQ(json.at("inflation").get<double>(), 0.0);
    EXPECT_EQ(json.at("vf_pairs").get<std::int64_t>(), 7319);
    EXPECT_EQ(json.at("ee_pairs").get<std::int64_t>(), 33770);
}

// The continuous narrow phase on the same step: every pair the Mathematica ground truth marks as
// colliding (27 vertex-face, 107 edge-edge among the queries in cloth-funnel/queries, which are
// broad-phase pairs of this step) must be a hit, so the hit counts cannot be lower.
TEST(Funnel, CcdOnTheBroadPhasePairsMissesNoGroundTruthContact) {
    const std::filesystem::path frames =
        std::filesystem::path(PLIANT_SHARED_DATA_DIR) / "cloth-funnel" / "frames";
    if (!std::filesystem::exists(frames / "227.ply") ||
        !std::filesystem::exists(frames / "228.ply")) {
        GTEST_SKIP() << "external data not found under " << frames.string();
    }
    ScratchDir scratch;
    const CliResult r = run_cli("collide " + quoted(frames / "227.ply") + " --to " +
                                    quoted(frames / "228.ply") + " --ccd --json",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json json = nlohmann::json::parse(r.out);
    EXPECT_GE(json.at("vf_hits").get<std::int64_t>(), 27);
    EXPECT_GE(json.at("ee_hits").get<std::int64_t>(), 107);
    EXPECT_LE(json.at("vf_hits").get<std::int64_t>(), json.at("vf_pairs").get<std::int64_t>());
    const double toi = json.at("earliest_toi").get<double>();
    EXPECT_GE(toi, 0.0);
    EXPECT_LT(toi, 1.0);
    EXPECT_GT(json.at("narrow_ms").get<double>(), 0.0);
}

}  // namespace
}  // namespace pliant::test
