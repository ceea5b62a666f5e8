#include "pliant/collision/narrow_phase.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::collision {
namespace {

// Two parallel sheets 0.1 apart; the upper one moves down by 0.2 during the step, so it passes
// through the lower one: every vertex of the upper sheet above the lower sheet's interior crosses
// a face at t = 0.5.
struct CrossingSheets {
    geometry::TriangleMesh mesh;
    std::vector<Vec3f> positions_t1;

    CrossingSheets() {
        const geometry::TriangleMesh lower = geometry::make_grid_sheet(6, 6, 1.0f, 1.0f);
        geometry::TriangleMesh upper = geometry::make_grid_sheet(5, 5, 0.7f, 0.7f);
        mesh = lower;
        const auto offset = static_cast<std::int32_t>(lower.positions.size());
        for (const Vec3f& p : upper.positions) {
            mesh.positions.push_back(p + Vec3f{0.01f, 0.02f, 0.1f});
        }
        for (const geometry::Triangle& t : upper.triangles) {
            mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
        positions_t1 = mesh.positions;
        for (std::size_t v = static_cast<std::size_t>(offset); v < positions_t1.size(); ++v) {
            positions_t1[v].z -= 0.2f;
        }
    }
};

// Reference: the same CCD called pair by pair, sequentially.
NarrowPhaseResult sequential(const CrossingSheets& s, const geometry::MeshTopology& topo,
                             const FeaturePairs& pairs) {
    NarrowPhaseResult r;
    const auto at = [](const std::vector<Vec3f>& p, std::int32_t v) {
        return vec3_cast<double>(p[static_cast<std::size_t>(v)]);
    };
    const auto& p0 = s.mesh.positions;
    const auto& p1 = s.positions_t1;
    for (const VertexFacePair& p : pairs.vertex_face) {
        const auto& f = s.mesh.triangles[static_cast<std::size_t>(p.face)];
        const CcdResult c =
            vertex_face_ccd(at(p0, p.vertex), at(p0, f[0]), at(p0, f[1]), at(p0, f[2]),
                            at(p1, p.vertex), at(p1, f[0]), at(p1, f[1]), at(p1, f[2]));
        r.vf_hits += c.hit ? 1 : 0;
        r.earliest_toi = c.hit ? std::min(r.earliest_toi, c.toi) : r.earliest_toi;
    }
    for (const EdgeEdgePair& p : pairs.edge_edge) {
        const auto& a = topo.edges[static_cast<std::size_t>(p.edge_a)];
        const auto& b = topo.edges[static_cast<std::size_t>(p.edge_b)];
        const CcdResult c = edge_edge_ccd(at(p0, a[0]), at(p0, a[1]), at(p0, b[0]), at(p0, b[1]),
                                          at(p1, a[0]), at(p1, a[1]), at(p1, b[0]), at(p1, b[1]));
        r.ee_hits += c.hit ? 1 : 0;
        r.earliest_toi = c.hit ? std::min(r.earliest_toi, c.toi) : r.earliest_toi;
    }
    return r;
}

TEST(NarrowPhase, SheetPassingThroughASheetIsCaughtAtHalfStep) {
    const CrossingSheets s;
    SelfCollisionBroadPhase<float> broad(s.mesh.triangles, s.mesh.num_vertices());
    const FeaturePairs& pairs = broad.update(s.mesh.positions, s.positions_t1, 0.0f);
    const auto run = [&](int threads) {
        set_num_threads(threads);
        return continuous_narrow_phase(
            std::span<const Vec3f>(s.mesh.positions), std::span<const Vec3f>(s.positions_t1),
            std::span<const geometry::Triangle>(s.mesh.triangles),
            std::span<const geometry::Edge>(broad.topology().edges), pairs);
    };
    const NarrowPhaseResult one = run(1);
    const NarrowPhaseResult many = run(4);
    set_num_threads(0);
    const NarrowPhaseResult expected = sequential(s, broad.topology(), pairs);
    EXPECT_EQ(one.vf_hits, expected.vf_hits);
    EXPECT_EQ(one.ee_hits, expected.ee_hits);
    EXPECT_EQ(one.earliest_toi, expected.earliest_toi);
    EXPECT_EQ(many.vf_hits, one.vf_hits);
    EXPECT_EQ(many.ee_hits, one.ee_hits);
    EXPECT_EQ(many.earliest_toi, one.earliest_toi);
    // All 36 upper vertices are above the lower sheet's interior and cross it at t = 0.5.
    EXPECT_GE(one.vf_hits, 36);
    EXPECT_GT(one.ee_hits, 0);
    EXPECT_LE(one.earliest_toi, 0.5);
    EXPECT_GT(one.earliest_toi, 0.49);
}

TEST(NarrowPhase, NoMotionNoHitsAndBadPairsRejected) {
    const CrossingSheets s;
    SelfCollisionBroadPhase<float> broad(s.mesh.triangles, s.mesh.num_vertices());
    const FeaturePairs& pairs = broad.update(s.mesh.positions, s.mesh.positions, 0.02f);
    const NarrowPhaseResult r = continuous_narrow_phase(
        std::span<const Vec3f>(s.mesh.positions), std::span<const Vec3f>(s.mesh.positions),
        std::span<const geometry::Triangle>(s.mesh.triangles),
        std::span<const geometry::Edge>(broad.topology().edges), pairs);
    // The sheets are 0.1 apart and flat: in-plane neighbours touch nothing they don't share.
    EXPECT_EQ(r.vf_hits, 0);
    EXPECT_EQ(r.earliest_toi, 1.0);
    FeaturePairs bad;
    bad.vertex_face.push_back({static_cast<std::int32_t>(s.mesh.num_vertices()), 0});
    EXPECT_THROW(
        continuous_narrow_phase(std::span<const Vec3f>(s.mesh.positions),
                                std::span<const Vec3f>(s.mesh.positions),
                                std::span<const geometry::Triangle>(s.mesh.triangles),
                                std::span<const geometry::Edge>(broad.topology().edges), bad),
        InvalidInput);
}

}  // namespace
}  // namespace pliant::collision
