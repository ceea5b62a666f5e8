// Uses the installed library the way the README shows: the broad phase on a folded sheet and a
// small cloth scene simulated through the pipeline API. Exit 0 when the numbers make sense.
#include <fmt/format.h>

#include <cstdio>

#include "pliant/collision/self_broad_phase.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"
#include "pliant/version.hpp"

int main() {
    using namespace pliant;
    geometry::TriangleMesh sheet = geometry::make_grid_sheet(40, 40, 1.0f, 1.0f);
    const float edge = 1.0f / 40.0f;
    geometry::fold_accordion(sheet.positions, 0.25f, 1.5f * edge);
    collision::SelfCollisionBroadPhase<float> broad_phase(sheet.triangles, sheet.num_vertices());
    const collision::FeaturePairs& pairs =
        broad_phase.update(sheet.positions, sheet.positions, 0.25f * edge);

    pipeline::ClothSimulation sim = pipeline::ClothSimulation::from_scene(
        pipeline::parse_cloth_scene(
            R"({"cloth": {"grid": {"size": [1, 1], "quads": [10, 10]}, "translate": [0, 0, 0.5]},
                "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
                "frames": 4, "fps": 24, "substeps": 10})",
            "consumer scene", "."),
        "consumer scene");
    for (int f = 0; f < 4; ++f) {
        sim.step();
    }
    const pipeline::ClothFrameCheck check = sim.check();
    fmt::print(
        "pliant {}: {} vertex-face, {} edge-edge pairs; cloth at t = {:.3f} s, {} "
        "intersecting pairs\n",
        PLIANT_VERSION, pairs.vertex_face.size(), pairs.edge_edge.size(), sim.time(),
        check.intersecting_pairs);
    const bool ok = !pairs.vertex_face.empty() && !pairs.edge_edge.empty() &&
                    check.intersecting_pairs == 0 && sim.positions()[0].z < 0.5;
    return ok ? 0 : 1;
}
