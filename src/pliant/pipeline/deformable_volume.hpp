// The deformable-volume pipeline's state for one source volume (Park & Kye 2022): a tet mesh over
// it — pbd::build_tet_grid over the visible voxels, or a TetGen mesh in the volume's world frame —
// the XPBD soft body on that mesh and the resampler that rasterizes the deformed tets back into a
// grid. Shared by `pliant deform` (deform_run.hpp) and the viewer (`pliant view volume
// --deform`), so that both run the same pipeline.
//
//   DeformableVolume deformable(source, &tf, {.cell_voxels = 4}, {}, {.stiffness = 0.8});
//   deformable.body().add_driver(pbd::TwistDriver{.angle = 90.0});
//   deformable.body().step(1.0 / 24.0);
//   deformable.resample(target);   // target: dims, type, spacing and origin of target_like()
//
// The source volume and the transfer function must outlive the object (the resampler reads them
// every frame). Not copyable or movable (the resampler refers to the mesh it owns).
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/resample.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::pipeline {

// How a deformed frame is shown: `exact` resamples every voxel (volume::Resampler) and ray-casts
// the result (render::RayCaster); `map` builds the frame's inverse map (volume::InverseMap, one
// node every cell_voxels voxels) and ray-casts the source through it (render::MappedRayCaster),
// which interpolates once where the exact route interpolates twice (docs/performance.md compares
// them).
enum class ResampleMode { exact, map };

// "exact" or "map"; InvalidInput naming both otherwise.
ResampleMode parse_resample_mode(const std::string& text);
const char* name(ResampleMode mode);

class DeformableVolume {
public:
    // tf: the transfer function of a scalar source (which voxels are visible), nullptr for RGBA.
    // grid_options.tf is replaced by tf. mesh: a TetGen mesh instead of the grid (empty: the
    // grid). Throws InvalidInput when there is nothing to deform (no visible voxel, a mesh
    // without tets) and IoError for an unreadable mesh.
    DeformableVolume(const volume::Volume& source, const volume::TransferFunction* tf,
                     const pbd::TetGridOptions& grid_options, const std::filesystem::path& mesh,
                     const pbd::SoftBodyOptions& body_options);
    ~DeformableVolume();
    DeformableVolume(const DeformableVolume&) = delete;
    DeformableVolume& operator=(const DeformableVolume&) = delete;

    pbd::SoftBody& body() { return *m_body; }
    const pbd::SoftBody& body() const { return *m_body; }
    const geometry::TetMesh& rest() const { return m_grid ? m_grid->mesh : m_mesh; }
    const pbd::TetGrid* grid() const { return m_grid.get(); }

    // A new soft body at rest, time 0, with the current body's options; drivers and drag are
    // not carried over (the caller adds them).
    void reset_body();

    // An empty volume like the source, for resample(): the same dims, spacing and origin, and
    // the resampler's output type.
    volume::Volume target_like() const;
    // The body's current positions resampled into `target` (volume::Resampler::resample).
    volume::ResampleStats resample(volume::Volume& target) const;
    // The same for positions of the body's vertices saved earlier (#V, world units).
    volume::ResampleStats resample(std::span<const Vec3f> positions, volume::Volume& target) const;
    // The body's current positions as an inverse map over the source's frame (target_like()'s),
    // one node every cell_voxels voxels of the grid (4 for a TetGen mesh): what
    // render::MappedRayCaster(source, tf, source, …) renders.
    volume::InverseMapStats build_map(volume::InverseMap& map) const;
    volume::InverseMapStats build_map(std::span<const Vec3f> positions,
                                      volume::InverseMap& map) const;

private:
    const volume::Volume* m_source;
    std::unique_ptr<pbd::TetGrid> m_grid;  // null: a TetGen mesh (m_mesh)
    geometry::TetMesh m_mesh;
    std::unique_ptr<pbd::SoftBody> m_body;
    std::unique_ptr<volume::Resampler> m_resampler;
};

}  // namespace pliant::pipeline
