// The cloth-funnel oracle (../shared/data/cloth-funnel, see its README): the swept boxes of the
// step 227 → 228, no inflation, closed overlap, give exactly 7,319 vertex-face and 33,770
// edge-edge pairs that share no vertex. Skips when the shared data is absent (a user's clone).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/io/mesh_io.hpp"

namespace pliant::collision {
namespace {

const std::filesystem::path FRAMES =
    std::filesystem::path(PLIANT_SHARED_DATA_DIR) / "cloth-funnel/frames";

class ClothFunnel : public ::testing::Test {
protected:
    void SetUp() override {
        if (!std::filesystem::exists(FRAMES / "227.ply") ||
            !std::filesystem::exists(FRAMES / "228.ply")) {
            GTEST_SKIP() << "cloth-funnel frames not found at " << FRAMES
                         << " (../shared/data is not part of a user's clone)";
        }
        m_t0 = io::read_mesh(FRAMES / "227.ply");
        m_t1 = io::read_mesh(FRAMES / "228.ply");
        ASSERT_EQ(m_t0.triangles, m_t1.triangles);
    }
    void TearDown() override { set_num_threads(0); }

    geometry::TriangleMeshD m_t0, m_t1;
};

TEST_F(ClothFunnel, SweptStepGivesTheOracleCountsInDoubleAndFloat) {
    SelfCollisionBroadPhase<double> exact(m_t0.triangles, m_t0.num_vertices());
    const FeaturePairs& pairs = exact.update(m_t0.positions, m_t1.positions, 0.0);
    EXPECT_EQ(pairs.vertex_face.size(), 7319u);
    EXPECT_EQ(pairs.edge_edge.size(), 33770u);
    // Refitting the same step gives the same answer.
    EXPECT_EQ(exact.update(m_t0.positions, m_t1.positions, 0.0).edge_edge.size(), 33770u);

    // Rounded to float, the frames happen to give the same counts (no box gap is below float
    // resolution); the float path is what the cloth solver runs.
    const auto t0 = geometry::convert_precision<float>(m_t0);
    const auto t1 = geometry::convert_precision<float>(m_t1);
    SelfCollisionBroadPhase<float> single(t0.triangles, t0.num_vertices());
    const FeaturePairs& fp = single.update(t0.positions, t1.positions, 0.0f);
    EXPECT_EQ(fp.vertex_face.size(), 7319u);
    EXPECT_EQ(fp.edge_edge.size(), 33770u);
}

TEST_F(ClothFunnel, NoDuplicatesAndIdenticalForOneAndTwoThreads) {
    const auto run = [&](int threads) {
        set_num_threads(threads);
        SelfCollisionBroadPhase<double> broad(m_t0.triangles, m_t0.num_vertices());
        return broad.update(m_t0.positions, m_t1.positions, 0.0);
    };
    const FeaturePairs one = run(1);
    const FeaturePairs two = run(2);
    EXPECT_EQ(one.vertex_face, two.vertex_face);
    EXPECT_EQ(one.edge_edge, two.edge_edge);
    auto vf = one.vertex_face;
    auto ee = one.edge_edge;
    std::sort(vf.begin(), vf.end());
    std::sort(ee.begin(), ee.end());
    EXPECT_EQ(std::adjacent_find(vf.begin(), vf.end()), vf.end());
    EXPECT_EQ(std::adjacent_find(ee.begin(), ee.end()), ee.end());
}

}  // namespace
}  // namespace pliant::collision
