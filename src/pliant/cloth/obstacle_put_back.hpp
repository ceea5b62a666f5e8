// Cloth triangles that meet an obstacle after a pass that moved them go to a fallback that is
// clear of it: after a substep's obstacle passes, and after the self-contact pushes.
//
//   ObstaclePutBack put_back;  // scratch, reused substep after substep
//   // After the obstacle passes: what they left in an obstacle goes back to the substep's start,
//   // carried with the obstacles.
//   put_back.seed(positions, before_passes);
//   put_back.run(model, start, ObstaclePutBack::Fallback::carried);
//   // After a pass that must not move cloth into an obstacle (self-contact pushes): undone.
//   put_back.seed(positions, before_pushes);
//   put_back.run(model, before_pushes, ObstaclePutBack::Fallback::reference);
//
// Why: the obstacle passes (push_out, mesh_contact.hpp) each resolve what entered in the substep,
// one after the other, with bounded and averaged corrections. They can leave a triangle in an
// obstacle (a push bounded by max_push, a vertex whose features' corrections average out, a pass
// that moves a vertex the previous pass placed), and every pass acts only on motion that enters,
// so such a crossing stays. This pass is checked against the exact predicate instead.
//
// Contract:
//   - seed(positions, changed_from) marks the vertices whose position differs from
//     changed_from[v] (a pass moved them); the marks add up until run(), which clears them. A
//     later pass may move the marked vertices again before run() (OGC's truncation pulls part of
//     an obstacle pass's corrections back: seed before it, run after it).
//   - run(model, reference, fallback, max_carry): the triangles with a marked vertex are the
//     first round's seeds. Rounds: each seed triangle that meets an obstacle (obstacle_met_by,
//     exact; a triangle a vertex moved earlier in the round is tested again) has its free
//     vertices (inverse mass > 0) moved to their fallback, unless the fallback cannot clear it:
//     the triangle there meets an obstacle as well, a vertex's fallback is inside a closed mesh
//     obstacle (meets_triangle sees only triangles through the surface) or farther than
//     max_carry (m) from reference[v] (an obstacle that jumps: the passes bound their pushes so
//     that cloth is not swept through cloth). Such a triangle stays, counted in stuck(). The
//     triangles of the vertices moved are the next round's seeds. A vertex moves at most once
//     per run, so the rounds end.
//   - Fallback::reference: the vertex goes to reference[v].
//   - Fallback::carried: reference[v] is where the vertex was at the obstacles' previous
//     placement (ClothModel::move_obstacles keeps it: the substep's start); the vertex goes where
//     the met obstacle's motion since then carries that point: rigid motion exactly (a triangle
//     clear of a rigidly moving obstacle at the start is clear of it carried along, when all its
//     vertices move), a deforming mesh's deformation by the displacement of the current
//     surface's point nearest to the start (within the mesh's largest vertex step and
//     `thickness`; approximate, and checked like every fallback). The vertex then moves with the
//     obstacle's surface for the substep (it does not slide).
//   - Fallback::carried with `since` (an ObstaclePlacements captured earlier): reference[v] is
//     where the vertex was when the placements were captured, and the vertex goes where the met
//     obstacle's motion since then carries that point (the same rules; for a deforming mesh the
//     radius is its largest vertex move since then). For positions older than one substep: the
//     self-collision fail-safe puts vertices back where its window of several substeps began,
//     which a moving obstacle may have taken since.
// run() returns the vertices moved (moved() lists them, in the order they moved). Deterministic:
// the tests run in parallel into one entry per seed triangle, the moves in triangle order, so any
// number of threads gives the same positions. Cost: one obstacle query per seed triangle per
// round (MeshObstacle::meets_triangle, an LBVH query) and O(moved vertices) besides; seed() and
// finding the seeds are O(V).
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/motion.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

// Where a model's obstacles are at one time (capture()): their rigid placements and a deforming
// mesh's vertices (world units), for Fallback::carried from then.
struct ObstaclePlacements {
    std::vector<Pose> mesh_poses;                    // per mesh obstacle
    std::vector<std::vector<Vec3d>> mesh_positions;  // per mesh obstacle; empty when rigid
    std::vector<Pose> poses;                         // per analytic obstacle

    void capture(const ClothModel& model);
};

class ObstaclePutBack {
public:
    enum class Fallback { reference, carried };

    void seed(std::span<const Vec3d> positions, std::span<const Vec3d> changed_from);
    std::int64_t run(ClothModel& model, std::span<const Vec3d> reference, Fallback fallback,
                     double max_carry = std::numeric_limits<double>::infinity(),
                     const ObstaclePlacements* since = nullptr);

    std::span<const std::int32_t> moved() const { return m_moved; }
    // Triangles of the last run that met an obstacle at their fallback too (left as they were).
    std::int64_t stuck() const { return static_cast<std::int64_t>(m_stuck.size()); }
    // Those triangles, in the order they were found.
    std::span<const std::int32_t> stuck_triangles() const { return m_stuck; }

private:
    std::vector<std::uint8_t> m_seeded;          // per vertex: seed() marked it
    std::vector<std::uint8_t> m_triangle_marks;  // all clear between runs
    std::vector<std::int32_t> m_vertex_moved;  // the round it moved in (0: not); clear between runs
    std::vector<std::int32_t> m_seeds;
    std::vector<std::int32_t> m_met;  // per seed: the obstacle it meets (obstacle_met_by), or -1
    std::vector<std::int32_t> m_moved;
    std::vector<std::int32_t> m_marked;  // the vertices whose m_vertex_moved is set
    std::vector<std::int32_t> m_stuck;
};

}  // namespace pliant::cloth
