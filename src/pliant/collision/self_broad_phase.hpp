// SelfCollisionBroadPhase: every non-incident vertex-face and edge-edge pair of a deforming
// triangle mesh whose feature boxes overlap — complete and duplicate-free.
//
// Each update (positions at the start and end of a step, or twice the same for a static query):
//   1. feature boxes: vertex boxes span the vertex's two positions, grown by `inflation` (world
//      units) on every side; edge and triangle boxes are exact merges of their vertex boxes;
//   2. bvh: an LBVH over the triangle boxes, built on the first update (or after
//      request_rebuild()) and refitted otherwise;
//   3. traverse: triangle pairs whose boxes overlap and that share no vertex;
//   4. features: for every such pair, R-triangle owned features (representative_triangles.hpp),
//      plus the orphan set for triangles that share a vertex (orphan_set.hpp); a pair is kept when
//      its feature boxes overlap (closed intervals).
//
// update_vertices() redoes stages 1-4 for a few vertices only (after a full update): their boxes,
// a refit, BVH queries for the triangles around them, their orphan pairs; it returns the pairs
// that involve them.
//
// Real is the precision of the positions (float for simulation, double for files with double
// coordinates). All filtering runs on float boxes (half the memory traffic of double); for double
// input they are rounded outward, so no pair is lost, and every pair that passes is confirmed on
// exact double boxes — the result is exactly the Real-precision answer.
//
// Output order is deterministic (identical for 1 and N threads); VF pairs (v, f) and EE pairs
// (e1 < e2) appear once each. Not thread safe; one instance per mesh.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/collision/feature_pairs.hpp"
#include "pliant/collision/representative_triangles.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/function_ref.hpp"
#include "pliant/geometry/topology.hpp"

namespace pliant::collision {

struct BroadPhaseStats {
    double build_ms = 0.0;     // LBVH build (0 when refitted)
    double refit_ms = 0.0;     // LBVH refit (0 when built)
    double traverse_ms = 0.0;  // BVH self traversal to non-adjacent triangle pairs
    double features_ms = 0.0;  // feature boxes, R-triangle and orphan feature tests, gathering
    std::int64_t triangle_pairs = 0;  // non-adjacent triangle pairs with overlapping boxes
};

template <typename Real>
class SelfCollisionBroadPhase {
public:
    using Vec = Vec3<Real>;
    using Box = BasicAABB<Real>;

    // Precomputes topology, R-triangle owners and the orphan set. Throws InvalidInput for indices
    // out of range or triangles that repeat a vertex.
    SelfCollisionBroadPhase(std::span<const geometry::Triangle> triangles,
                            std::size_t num_vertices);

    // Runs the four stages for a step from positions_t0 to positions_t1 (#V each; pass the same
    // span twice for a static query). inflation ≥ 0, world units. Returns the pairs, valid until
    // the next update.
    //
    // keep (optional): a triangle-pair filter called (from several threads) for every
    // non-adjacent pair of triangles whose boxes overlap; pairs it rejects yield no feature pair
    // (a caller's tighter bound, e.g. on relative motion). Orphan pairs are not filtered.
    using TrianglePairFilter = FunctionRef<bool(std::int32_t, std::int32_t)>;
    const FeaturePairs& update(std::span<const Vec> positions_t0, std::span<const Vec> positions_t1,
                               Real inflation, const TrianglePairFilter* keep = nullptr);

    // A partial update after a full one: the vertices in `changed` (ascending, no duplicates)
    // get new boxes from positions_t0 / positions_t1 (#V each; only the changed vertices are
    // read) grown by `inflation` (the last update's), the edge and triangle boxes that contain
    // them are recomputed and the BVH refitted. Returns the VF and EE pairs that involve a changed
    // vertex (as the vertex, or a corner of the face or edge) and whose boxes overlap: exactly the
    // pairs a full update with the same boxes would report that involve a changed vertex, each
    // once, in a deterministic order. Cost: about one BVH query per triangle around the changed
    // vertices. Valid until the next update; pairs() keeps the last full update's pairs. Throws
    // InvalidInput before any full update, for wrong sizes or out-of-range vertices.
    // keep: as for update().
    const FeaturePairs& update_vertices(std::span<const Vec> positions_t0,
                                        std::span<const Vec> positions_t1, Real inflation,
                                        std::span<const std::int32_t> changed,
                                        const TrianglePairFilter* keep = nullptr);

    // With exact = false (double input only), pairs are kept on the float boxes alone (rounded
    // outward): a superset of the exact answer, for callers that filter the pairs further anyway,
    // without the confirmation on double boxes. Default true. Set before an update; the partial
    // updates that follow use the same setting.
    void set_exact(bool exact) { m_confirm_exact = exact; }

    // A memory guard for callers that cannot bound the overlap (a simulation that diverged, or
    // hostile input): with a limit L > 0, update() stops keeping triangle pairs once it has kept
    // about L per triangle of the mesh (L · #T, counted in steps of 256 per block of the
    // traversal), and update_vertices() once it has kept 2 L per changed triangle (counted per
    // block of 64 of them; it reports a pair for both its triangles) or a block 4 L per triangle;
    // pair_limit_exceeded() is then true until the next update (full or partial), and that update's
    // pairs are incomplete and must not be used (update() returns none). 0 (the default): no limit.
    void set_pair_limit(std::int64_t pairs_per_triangle) { m_pair_limit = pairs_per_triangle; }
    bool pair_limit_exceeded() const { return m_pair_limit_exceeded; }

    // The next update builds the BVH from scratch instead of refitting (after large motion).
    void request_rebuild() { m_needs_build = true; }

    const FeaturePairs& pairs() const { return m_pairs; }
    const BroadPhaseStats& stats() const { return m_stats; }
    const geometry::MeshTopology& topology() const { return m_topology; }
    const RepresentativeTriangles& owners() const { return m_owners; }
    const FeaturePairs& orphans() const { return m_orphans; }
    const bvh::LBVH& bvh() const { return m_bvh; }
    // Bytes held by the broad phase and its BVH (topology included).
    std::size_t memory_bytes() const;

    // Everything a later update reads (boxes, the BVH, the last pairs, partial-update state;
    // not the topology, owners and orphans the constructor derives), so that a run resumed from
    // a checkpoint continues bit for bit (core/bytes.hpp). load_state: InvalidInput for a state
    // of another mesh or a truncated one.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    void compute_boxes(std::span<const Vec> positions_t0, std::span<const Vec> positions_t1,
                       Real inflation);
    void set_vertex_box(std::size_t v, const Vec& p0, const Vec& p1, Real inflation);
    // Appends the owned-feature pairs of the non-adjacent triangles a and b whose boxes overlap
    // (with PARTIAL, only those with a vertex marked in m_vertex_marks).
    template <bool PARTIAL>
    void emit_feature_pairs(std::int32_t a, std::int32_t b, AppendBuffer<VertexFacePair>& vf,
                            AppendBuffer<EdgeEdgePair>& ee) const;
    // Orphan pairs by vertex (CSR over the orphan set's VF then EE indices), built on first use.
    void index_orphans();
    void traverse(const TrianglePairFilter* keep);
    void test_features();

    std::vector<geometry::Triangle> m_triangles;
    std::size_t m_num_vertices;
    geometry::MeshTopology m_topology;
    RepresentativeTriangles m_owners;
    FeaturePairs m_orphans;

    bool overlaps_exact_vf(std::int32_t vertex, std::int32_t face) const;
    bool overlaps_exact_ee(std::int32_t edge_a, std::int32_t edge_b) const;
    bool overlaps_exact_tt(std::int32_t triangle_a, std::int32_t triangle_b) const;
    Box exact_edge_box(std::int32_t edge) const;
    Box exact_triangle_box(std::int32_t triangle) const;

    std::vector<Box> m_exact_vertex_boxes;  // #V, Real = double only
    std::vector<AABB> m_vertex_boxes;       // #V, float, outward
    std::vector<AABB> m_edge_boxes;         // #E
    std::vector<AABB> m_triangle_boxes;     // #T, the BVH's boxes
    bvh::LBVH m_bvh;
    bool m_needs_build = true;

    ChunkedBuffer<std::pair<std::int32_t, std::int32_t>> m_triangle_pair_chunks;
    std::vector<std::pair<std::int32_t, std::int32_t>> m_triangle_pairs;
    ChunkedBuffer<VertexFacePair> m_vf_chunks;
    ChunkedBuffer<EdgeEdgePair> m_ee_chunks;
    FeaturePairs m_pairs;
    BroadPhaseStats m_stats;
    bool m_has_boxes = false;
    bool m_confirm_exact = true;
    std::int64_t m_pair_limit = 0;
    bool m_pair_limit_exceeded = false;
    // Partial updates.
    std::vector<std::uint8_t> m_vertex_marks;    // #V: changed in the current partial update
    std::vector<std::uint8_t> m_triangle_marks;  // #T: contains a changed vertex
    std::vector<std::int32_t> m_affected_triangles;
    std::vector<std::int32_t> m_affected_edges;
    std::vector<std::int32_t> m_orphan_offsets;  // #V + 1
    std::vector<std::int32_t> m_orphan_indices;  // VF index, or #VF + EE index
    std::vector<std::int32_t> m_affected_orphans;
    FeaturePairs m_partial_pairs;
};

extern template class SelfCollisionBroadPhase<float>;
extern template class SelfCollisionBroadPhase<double>;

}  // namespace pliant::collision
