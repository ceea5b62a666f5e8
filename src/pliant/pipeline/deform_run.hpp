// Running the deformable-volume pipeline on a volume: shared by `pliant deform` and `pliant demo`.
//
// A tet grid over the volume (or the given TetGen mesh), the XPBD soft body under one driver for
// `frames` steps of 1/fps seconds, the deformed mesh resampled into a grid like the source and
// written to `out`; with `video`, every frame resampled and ray-cast into an MP4; with `still`,
// the last frame ray-cast into a PNG; with `mesh_out`, the deformed tet mesh as .vtu. Returns the
// run's numbers (the JSON of `pliant deform`, docs/formats.md). Throws InvalidInput / IoError /
// Unsupported before simulating when the output cannot be written, there is nothing to deform or
// the grid needs more memory than max_memory_bytes allows.
//
// Checkpoints (io/checkpoint.hpp): every checkpoint_every frames before the last, the soft body's
// state and the run's sums go to checkpoint_path(out) (OUT.checkpoint.bin, atomically); the
// file is removed once the run completes. With resume, the run continues from it: the output
// volume (and the still) are bitwise identical to an uninterrupted run's. resume without the
// file starts from frame 0. A corrupt, truncated or foreign checkpoint (another volume, driver
// or options) is InvalidInput naming the file. A video (`video`) cannot be continued: resume
// with one is Unsupported, and runs that write one save no checkpoints.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <functional>
#include <string>

#include "pliant/pbd/drivers.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/pipeline/deformable_volume.hpp"
#include "pliant/pipeline/progress.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::pipeline {

struct DeformRunOptions {
    std::string driver_name;  // for messages and the JSON
    pbd::Driver driver;
    pbd::TetGridOptions grid;    // its tf is replaced by the run's tf
    std::filesystem::path mesh;  // a TetGen mesh instead of the grid (empty: the grid)
    pbd::SoftBodyOptions body;
    int frames = 48;
    double fps = 24.0;
    std::filesystem::path out;    // the deformed volume of the last frame
    std::filesystem::path video;  // MP4 of every frame (empty: none)
    std::filesystem::path still;  // PNG of the last frame (empty: none)
    // The deformed tet mesh of the last frame as VTK XML (.vtu, io/vtu.hpp: positions, tets,
    // displacement and rest positions per vertex, volume ratio per tet); empty: none.
    std::filesystem::path mesh_out;
    std::array<int, 2> size{512, 512};
    std::array<double, 3> camera{30.0, 20.0, 0.0};  // azimuth, elevation (degrees), distance
    bool shading = false;
    // How rendered frames (video, still) are made: through the inverse map (the default: one
    // interpolation, closer to a converged resample than the exact route, and faster at 256³;
    // deformable_volume.hpp) or resampled (exact). The output volume is always the exact
    // resample.
    ResampleMode resample = ResampleMode::map;
    double step = 0.0;  // ray-casting step, world units (0: half the smallest spacing)
    // Through the map, an rgba8 source: the levels of the ray caster's opacity-adaptive step
    // (render::RayCastOptions::thin_levels; 0: every step sampled).
    int thin_levels = render::RayCastOptions{}.thin_levels;
    ProgressFn progress;  // after every frame (progress.hpp)
    // The most memory the run may need (bytes; memory_budget.hpp's deform_need_bytes, checked
    // before the tet grid is built); 0: the memory available.
    std::uint64_t max_memory_bytes = 0;
    int checkpoint_every = 12;  // frames between checkpoints; 0: none
    bool resume = false;        // continue from checkpoint_path(out)
    // Every frame rendered (as the video gets it; set: every frame is rendered, also without a
    // video). For tests and callers that show frames.
    std::function<void(int frame, const render::Image& image)> frame_sink;
    // When every frame renders and no checkpoint is saved: step and map (or resample) frame f + 1
    // on one thread while frame f renders on the others (frame_pipeline.hpp). Every output is
    // bitwise the sequential loop's; the JSON's ms_per_frame is then the period.
    bool pipelined = true;
};

// Where a run writing the volume `out` keeps its checkpoint: OUT.checkpoint.bin beside it.
std::filesystem::path deform_checkpoint_path(const std::filesystem::path& out);

// tf: the transfer function of a scalar source (rendering and which voxels are visible), nullptr
// for RGBA sources.
nlohmann::ordered_json run_deform(const volume::Volume& source, const volume::TransferFunction* tf,
                                  const DeformRunOptions& options);

}  // namespace pliant::pipeline
