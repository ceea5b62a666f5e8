#include "pliant/collision/self_broad_phase.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <random>

#include "pliant/collision/incidence.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"
#include "support/random_meshes.hpp"

namespace pliant::collision {
namespace {

using geometry::TriangleMesh;

// Independent reference: every (vertex, face) with v ∉ face and every edge pair sharing no vertex,
// with boxes computed directly from the positions (not from merged vertex boxes).
FeaturePairs brute_force(const TriangleMesh& mesh, std::span<const Vec3f> p0,
                         std::span<const Vec3f> p1, float inflation) {
    const auto topo = geometry::build_topology(mesh.triangles, mesh.num_vertices());
    const auto box_of = [&](std::initializer_list<std::int32_t> vertices) {
        AABB box;
        for (const std::int32_t v : vertices) {
            box.extend(p0[static_cast<std::size_t>(v)]);
            box.extend(p1[static_cast<std::size_t>(v)]);
        }
        return box.inflated(inflation);
    };
    FeaturePairs pairs;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.num_vertices()); ++v) {
        if (topo.triangles_of_vertex(v).empty()) {
            continue;
        }
        for (std::int32_t f = 0; f < static_cast<std::int32_t>(mesh.num_triangles()); ++f) {
            const auto& t = mesh.triangles[static_cast<std::size_t>(f)];
            if (!contains_vertex(t, v) && overlaps(box_of({v}), box_of({t[0], t[1], t[2]}))) {
                pairs.vertex_face.push_back({v, f});
            }
        }
    }
    for (std::int32_t a = 0; a < static_cast<std::int32_t>(topo.num_edges()); ++a) {
        for (std::int32_t b = a + 1; b < static_cast<std::int32_t>(topo.num_edges()); ++b) {
            const auto& ea = topo.edges[static_cast<std::size_t>(a)];
            const auto& eb = topo.edges[static_cast<std::size_t>(b)];
            if (!share_vertex(ea, eb) && overlaps(box_of({ea[0], ea[1]}), box_of({eb[0], eb[1]}))) {
                pairs.edge_edge.push_back({a, b});
            }
        }
    }
    return pairs;
}

template <typename T>
std::vector<T> sorted(std::vector<T> v) {
    std::sort(v.begin(), v.end());
    return v;
}

// got holds every pair of expected (sorted, as brute_force returns them) exactly once, in any
// order, and no other.
void expect_same_pairs(const FeaturePairs& got, const FeaturePairs& expected) {
    const auto vf = sorted(got.vertex_face);
    const auto ee = sorted(got.edge_edge);
    EXPECT_EQ(std::adjacent_find(vf.begin(), vf.end()), vf.end()) << "duplicate VF pair";
    EXPECT_EQ(std::adjacent_find(ee.begin(), ee.end()), ee.end()) << "duplicate EE pair";
    EXPECT_EQ(vf, expected.vertex_face);
    EXPECT_EQ(ee, expected.edge_edge);
}

void expect_matches_brute_force(const TriangleMesh& mesh, const std::vector<Vec3f>& p1,
                                float inflation) {
    SelfCollisionBroadPhase<float> broad(mesh.triangles, mesh.num_vertices());
    const FeaturePairs& got = broad.update(mesh.positions, p1, inflation);
    const FeaturePairs expected = brute_force(mesh, mesh.positions, p1, inflation);
    expect_same_pairs(got, expected);
    EXPECT_GT(expected.vertex_face.size() + expected.edge_edge.size(), 0u) << "vacuous case";
}

TEST(SelfBroadPhase, FoldedSheetStaticMatchesBruteForce) {
    // Tight accordion: layers 1.5 edges apart, inflation a quarter edge — the benchmark workload.
    TriangleMesh mesh = geometry::make_grid_sheet(40, 8, 1.0f, 0.2f);
    const float edge = 1.0f / 40.0f;
    geometry::fold_accordion(mesh.positions, 0.2f, 1.5f * edge);
    expect_matches_brute_force(mesh, mesh.positions, 0.25f * edge);
}

TEST(SelfBroadPhase, CrumpledSweptSheetMatchesBruteForce) {
    const TriangleMesh mesh = test::jittered_sheet(18, 14, 0.4f, 0.08f, 17);
    std::vector<Vec3f> p1 = mesh.positions;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.03f, 0.03f);
    for (Vec3f& p : p1) {
        p += Vec3f{u(rng), u(rng), 3.0f * u(rng)};
    }
    expect_matches_brute_force(mesh, p1, 0.0f);
    expect_matches_brute_force(mesh, p1, 0.01f);
}

TEST(SelfBroadPhase, RandomSoupMatchesBruteForce) {
    const TriangleMesh mesh = test::random_triangle_soup(300, 0.15f, 8);
    expect_matches_brute_force(mesh, mesh.positions, 0.0f);
}

// The trap of R-triangles: triangles sharing a vertex are skipped by the traversal, yet a vertex
// owned by one can touch the other's face. A fan folded flat onto itself makes every such pair
// overlap; the orphan set must deliver them.
TEST(SelfBroadPhase, FoldedFanNeedsTheOrphanSet) {
    TriangleMesh fan;
    fan.positions = {{0, 0, 0},        {1, 0, 0},  {0.5f, 0.8f, 0},
                     {-0.5f, 0.8f, 0}, {-1, 0, 0}, {0.9f, 0.1f, 0.01f}};
    fan.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}};
    // Fold the last blade back over the first.
    SelfCollisionBroadPhase<float> broad(fan.triangles, fan.num_vertices());
    EXPECT_GT(broad.orphans().vertex_face.size(), 0u);
    expect_matches_brute_force(fan, fan.positions, 0.05f);
}

TEST(SelfBroadPhase, RepresentativeTrianglesOwnEveryFeatureOnce) {
    const TriangleMesh mesh = test::jittered_sheet(30, 20, 0.2f, 0.0f, 2);
    SelfCollisionBroadPhase<float> broad(mesh.triangles, mesh.num_vertices());
    const auto& owners = broad.owners();
    const auto& topo = broad.topology();
    std::vector<int> load(mesh.num_triangles(), 0);
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        const std::int32_t t = owners.vertex_owner[v];
        ASSERT_GE(t, 0);
        ASSERT_TRUE(contains_vertex(mesh.triangles[static_cast<std::size_t>(t)],
                                    static_cast<std::int32_t>(v)));
        ++load[static_cast<std::size_t>(t)];
    }
    for (std::size_t e = 0; e < topo.num_edges(); ++e) {
        const std::int32_t t = owners.edge_owner[e];
        const auto& te = topo.triangle_edges[static_cast<std::size_t>(t)];
        ASSERT_NE(std::find(te.begin(), te.end(), static_cast<std::int32_t>(e)), te.end());
        ++load[static_cast<std::size_t>(t)];
    }
    // The per-triangle lists agree with the owner arrays and the load is balanced.
    std::size_t listed = 0;
    for (std::size_t t = 0; t < owners.owned.size(); ++t) {
        const OwnedFeatures& o = owners.owned[t];
        for (int k = 0; k < o.num_vertices; ++k) {
            EXPECT_EQ(owners.vertex_owner[static_cast<std::size_t>(o.vertices[k])],
                      static_cast<std::int32_t>(t));
        }
        for (int k = 0; k < o.num_edges; ++k) {
            EXPECT_EQ(owners.edge_owner[static_cast<std::size_t>(o.edges[k])],
                      static_cast<std::int32_t>(t));
        }
        listed += o.num_vertices + o.num_edges;
    }
    EXPECT_EQ(listed, mesh.num_vertices() + topo.num_edges());
    EXPECT_LE(*std::max_element(load.begin(), load.end()), 3);
}

TEST(SelfBroadPhase, DoubleMatchesFloatAndThreadsDoNotMatter) {
    TriangleMesh mesh = geometry::make_grid_sheet(60, 30, 1.0f, 0.5f);
    geometry::fold_accordion(mesh.positions, 0.25f, 0.025f);
    std::vector<Vec3f> p1 = mesh.positions;
    for (Vec3f& p : p1) {
        p.z += 0.01f * std::sin(20.0f * p.x);
    }
    const auto run = [&](int threads) {
        set_num_threads(threads);
        SelfCollisionBroadPhase<float> broad(mesh.triangles, mesh.num_vertices());
        broad.update(mesh.positions, p1, 0.004f);
        return broad.update(mesh.positions, p1, 0.004f);  // the refit path
    };
    const FeaturePairs one = run(1);
    const FeaturePairs many = run(4);
    set_num_threads(0);
    EXPECT_EQ(one.vertex_face, many.vertex_face);  // identical order, not just sets
    EXPECT_EQ(one.edge_edge, many.edge_edge);
    EXPECT_GT(one.edge_edge.size(), 1000u);
}

// The pairs of `pairs` with a vertex in `changed` (marks by vertex).
FeaturePairs involving(const FeaturePairs& pairs, const TriangleMesh& mesh,
                       const geometry::MeshTopology& topo, const std::vector<bool>& changed) {
    FeaturePairs out;
    for (const VertexFacePair& p : pairs.vertex_face) {
        const auto& t = mesh.triangles[static_cast<std::size_t>(p.face)];
        if (changed[static_cast<std::size_t>(p.vertex)] ||
            changed[static_cast<std::size_t>(t[0])] || changed[static_cast<std::size_t>(t[1])] ||
            changed[static_cast<std::size_t>(t[2])]) {
            out.vertex_face.push_back(p);
        }
    }
    for (const EdgeEdgePair& p : pairs.edge_edge) {
        const auto& a = topo.edges[static_cast<std::size_t>(p.edge_a)];
        const auto& b = topo.edges[static_cast<std::size_t>(p.edge_b)];
        if (changed[static_cast<std::size_t>(a[0])] || changed[static_cast<std::size_t>(a[1])] ||
            changed[static_cast<std::size_t>(b[0])] || changed[static_cast<std::size_t>(b[1])]) {
            out.edge_edge.push_back(p);
        }
    }
    return out;
}

TEST(SelfBroadPhase, PartialUpdateFindsThePairsOfTheChangedVertices) {
    // A crumpled sheet; then some vertices move (their boxes change, a few of them far), and the
    // partial update must return exactly the brute-force pairs that involve them, each once.
    TriangleMesh mesh = test::jittered_sheet(24, 18, 0.4f, 0.08f, 23);
    std::vector<Vec3f> p1 = mesh.positions;
    SelfCollisionBroadPhase<float> broad(mesh.triangles, mesh.num_vertices());
    const float inflation = 0.01f;
    broad.update(mesh.positions, p1, inflation);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-0.05f, 0.05f);
    std::vector<bool> changed(mesh.num_vertices(), false);
    std::vector<std::int32_t> list;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.num_vertices()); v += 7) {
        changed[static_cast<std::size_t>(v)] = true;
        list.push_back(v);
        p1[static_cast<std::size_t>(v)] += Vec3f{u(rng), u(rng), 4.0f * u(rng)};
    }
    // Neighbours changed together (pairs of two changed vertices are reported once).
    for (std::int32_t v = 1; v < static_cast<std::int32_t>(mesh.num_vertices()); v += 7) {
        changed[static_cast<std::size_t>(v)] = true;
        list.push_back(v);
        p1[static_cast<std::size_t>(v)] += Vec3f{0.3f, 0.0f, 0.0f};
    }
    std::sort(list.begin(), list.end());
    const FeaturePairs got = broad.update_vertices(mesh.positions, p1, inflation, list);
    const auto topo = geometry::build_topology(mesh.triangles, mesh.num_vertices());
    const FeaturePairs expected =
        involving(brute_force(mesh, mesh.positions, p1, inflation), mesh, topo, changed);
    expect_same_pairs(got, expected);
    EXPECT_GT(expected.vertex_face.size(), 0u) << "vacuous case";
    EXPECT_GT(expected.edge_edge.size(), 0u) << "vacuous case";
    // A full update on the same boxes agrees with the brute force on all pairs.
    const FeaturePairs& full = broad.update(mesh.positions, p1, inflation);
    EXPECT_EQ(sorted(full.edge_edge), brute_force(mesh, mesh.positions, p1, inflation).edge_edge);
    // Threads do not change the partial result's order.
    const auto run = [&](int threads) {
        set_num_threads(threads);
        SelfCollisionBroadPhase<float> b(mesh.triangles, mesh.num_vertices());
        b.update(mesh.positions, mesh.positions, inflation);
        const FeaturePairs r = b.update_vertices(mesh.positions, p1, inflation, list);
        set_num_threads(0);
        return r;
    };
    const FeaturePairs one = run(1);
    const FeaturePairs many = run(4);
    EXPECT_EQ(one.vertex_face, many.vertex_face);
    EXPECT_EQ(one.edge_edge, many.edge_edge);
    EXPECT_THROW(SelfCollisionBroadPhase<float>(mesh.triangles, mesh.num_vertices())
                     .update_vertices(mesh.positions, p1, inflation, list),
                 InvalidInput);
    const std::vector<std::int32_t> bad{static_cast<std::int32_t>(mesh.num_vertices())};
    EXPECT_THROW(broad.update_vertices(mesh.positions, p1, inflation, bad), InvalidInput);
}

// The memory guard: 40 coincident copies of a sheet (every triangle overlaps hundreds of others).
// Under the limit the pairs are those of an unlimited update; above it the update stops keeping
// pairs, reports it, returns none and allows no partial update on it; the next update within the
// limit clears the flag.
TEST(SelfBroadPhase, PairLimitStopsAnOverlapTooDenseToHold) {
    const TriangleMesh sheet = geometry::make_grid_sheet(4, 4, 1.0f, 1.0f);
    TriangleMesh mesh;
    const int copies = 40;
    for (int c = 0; c < copies; ++c) {
        const auto offset = static_cast<std::int32_t>(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), sheet.positions.begin(), sheet.positions.end());
        for (const geometry::Triangle& t : sheet.triangles) {
            mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
    }
    const float inflation = 0.01f;
    SelfCollisionBroadPhase<float> unlimited(mesh.triangles, mesh.num_vertices());
    const FeaturePairs all = unlimited.update(mesh.positions, mesh.positions, inflation);
    const std::int64_t triangle_pairs = unlimited.stats().triangle_pairs;
    ASSERT_GT(triangle_pairs, 100 * static_cast<std::int64_t>(mesh.num_triangles()));
    EXPECT_FALSE(unlimited.pair_limit_exceeded());

    SelfCollisionBroadPhase<float> roomy(mesh.triangles, mesh.num_vertices());
    roomy.set_pair_limit(1000);
    const FeaturePairs within = roomy.update(mesh.positions, mesh.positions, inflation);
    EXPECT_FALSE(roomy.pair_limit_exceeded());
    EXPECT_EQ(within.vertex_face, all.vertex_face);
    EXPECT_EQ(within.edge_edge, all.edge_edge);

    SelfCollisionBroadPhase<float> tight(mesh.triangles, mesh.num_vertices());
    tight.set_pair_limit(10);
    const FeaturePairs& cut = tight.update(mesh.positions, mesh.positions, inflation);
    EXPECT_TRUE(tight.pair_limit_exceeded());
    EXPECT_TRUE(cut.vertex_face.empty() && cut.edge_edge.empty());
    EXPECT_EQ(tight.stats().triangle_pairs, 0);  // none kept
    // No partial update on an incomplete full one.
    std::vector<std::int32_t> changed(mesh.num_vertices());
    for (std::size_t v = 0; v < changed.size(); ++v) {
        changed[v] = static_cast<std::int32_t>(v);
    }
    EXPECT_THROW(tight.update_vertices(mesh.positions, mesh.positions, inflation, changed),
                 InvalidInput);
    tight.set_pair_limit(0);
    const FeaturePairs& again = tight.update(mesh.positions, mesh.positions, inflation);
    EXPECT_FALSE(tight.pair_limit_exceeded());
    EXPECT_EQ(again.edge_edge, all.edge_edge);
    // Partial updates keep the limit per block of changed triangles.
    tight.set_pair_limit(10);
    tight.update_vertices(mesh.positions, mesh.positions, inflation, changed);
    EXPECT_TRUE(tight.pair_limit_exceeded());
}

TEST(SelfBroadPhase, TrianglePairFilterDropsTheRTrianglePairsItRejects) {
    TriangleMesh mesh = geometry::make_grid_sheet(20, 12, 1.0f, 0.6f);
    geometry::fold_accordion(mesh.positions, 0.2f, 0.04f);
    const float inflation = 0.01f;
    SelfCollisionBroadPhase<float> broad(mesh.triangles, mesh.num_vertices());
    const FeaturePairs expected = brute_force(mesh, mesh.positions, mesh.positions, inflation);
    // Accepting everything changes nothing.
    const auto all = [](std::int32_t, std::int32_t) {
        return true;
    };
    const SelfCollisionBroadPhase<float>::TrianglePairFilter accept(all);
    const FeaturePairs with_all = broad.update(mesh.positions, mesh.positions, inflation, &accept);
    EXPECT_EQ(sorted(with_all.vertex_face), expected.vertex_face);
    EXPECT_EQ(sorted(with_all.edge_edge), expected.edge_edge);
    // Rejecting every pair leaves the orphan pairs (triangles sharing a vertex) alone, in full
    // and partial updates.
    const auto none = [](std::int32_t, std::int32_t) {
        return false;
    };
    const SelfCollisionBroadPhase<float>::TrianglePairFilter reject(none);
    const FeaturePairs only_orphans =
        broad.update(mesh.positions, mesh.positions, inflation, &reject);
    const auto orphans_vf = sorted(broad.orphans().vertex_face);
    const auto orphans_ee = sorted(broad.orphans().edge_edge);
    std::vector<VertexFacePair> vf;
    std::vector<EdgeEdgePair> ee;
    std::set_intersection(expected.vertex_face.begin(), expected.vertex_face.end(),
                          orphans_vf.begin(), orphans_vf.end(), std::back_inserter(vf));
    std::set_intersection(expected.edge_edge.begin(), expected.edge_edge.end(), orphans_ee.begin(),
                          orphans_ee.end(), std::back_inserter(ee));
    EXPECT_EQ(sorted(only_orphans.vertex_face), vf);
    EXPECT_EQ(sorted(only_orphans.edge_edge), ee);
    EXPECT_LT(vf.size() + ee.size(), expected.vertex_face.size() + expected.edge_edge.size());
    const std::vector<std::int32_t> changed{0, 5, 77, 150};
    const FeaturePairs partial =
        broad.update_vertices(mesh.positions, mesh.positions, inflation, changed, &reject);
    const auto partial_vf = sorted(partial.vertex_face);
    const auto partial_ee = sorted(partial.edge_edge);
    EXPECT_TRUE(std::includes(vf.begin(), vf.end(), partial_vf.begin(), partial_vf.end()));
    EXPECT_TRUE(std::includes(ee.begin(), ee.end(), partial_ee.begin(), partial_ee.end()));
    EXPECT_GT(partial_vf.size() + partial_ee.size(), 0u);
}

TEST(SelfBroadPhase, InexactDoubleIsASupersetOfExact) {
    TriangleMesh mesh = geometry::make_grid_sheet(30, 20, 1.0f, 0.6f);
    geometry::fold_accordion(mesh.positions, 0.2f, 0.03f);
    std::vector<Vec3d> p0(mesh.positions.size());
    std::vector<Vec3d> p1(mesh.positions.size());
    for (std::size_t v = 0; v < p0.size(); ++v) {
        p0[v] = vec3_cast<double>(mesh.positions[v]);
        p1[v] = p0[v] + Vec3d{0.0, 0.0, 1e-3 * std::sin(7.0 * p0[v].x)};
    }
    SelfCollisionBroadPhase<double> exact(mesh.triangles, mesh.num_vertices());
    SelfCollisionBroadPhase<double> loose(mesh.triangles, mesh.num_vertices());
    loose.set_exact(false);
    const auto e = exact.update(p0, p1, 0.002);
    const auto l = loose.update(p0, p1, 0.002);
    const auto e_vf = sorted(e.vertex_face);
    const auto l_vf = sorted(l.vertex_face);
    const auto e_ee = sorted(e.edge_edge);
    const auto l_ee = sorted(l.edge_edge);
    EXPECT_TRUE(std::includes(l_vf.begin(), l_vf.end(), e_vf.begin(), e_vf.end()));
    EXPECT_TRUE(std::includes(l_ee.begin(), l_ee.end(), e_ee.begin(), e_ee.end()));
    EXPECT_GT(e_ee.size(), 100u);
    // A float box is at most a few float ulps larger: hardly any extra pair.
    EXPECT_LT(l_ee.size() + l_vf.size(), (e_ee.size() + e_vf.size()) * 101 / 100);
}

TEST(SelfBroadPhase, RejectsBadArguments) {
    const TriangleMesh mesh = geometry::make_grid_sheet(3, 3, 1.0f, 1.0f);
    SelfCollisionBroadPhase<float> broad(mesh.triangles, mesh.num_vertices());
    std::vector<Vec3f> short_positions(mesh.positions.begin(), mesh.positions.end() - 1);
    try {
        broad.update(mesh.positions, short_positions, 0.0f);
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("positions_t1.size() (15)"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(broad.update(mesh.positions, mesh.positions, -1.0f), InvalidInput);
    EXPECT_THROW(broad.update(mesh.positions, mesh.positions, NAN), InvalidInput);
    std::vector<geometry::Triangle> bad = mesh.triangles;
    bad[2][1] = 99;
    EXPECT_THROW(SelfCollisionBroadPhase<float>(bad, mesh.num_vertices()), InvalidInput);
}

TEST(SelfBroadPhase, EmptyAndSingleTriangle) {
    SelfCollisionBroadPhase<float> empty({}, 0);
    EXPECT_TRUE(empty.update({}, {}, 0.0f).vertex_face.empty());
    TriangleMesh one{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}};
    SelfCollisionBroadPhase<float> single(one.triangles, 3);
    const auto& pairs = single.update(one.positions, one.positions, 1.0f);
    EXPECT_TRUE(pairs.vertex_face.empty());
    EXPECT_TRUE(pairs.edge_edge.empty());
}

}  // namespace
}  // namespace pliant::collision
