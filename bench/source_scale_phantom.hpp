// The deformable-volume workload at the source system's scale (Park & Kye 2022; issue 29): a
// 256³ rgba8 volume and a tet grid of 64³ cells of 4 voxels over its visible voxels. The volume
// is the 3D Shepp–Logan phantom classified by the `mri-brain` preset (volume::apply), channels
// stored as round(255 · c): an opaque-enough head-sized ellipsoid filling about a third of the
// box, like the radiance field's cleaned reconstruction. Shared by bench_pbd, bench_resample and
// bench_deform_frame; built once per process (a few seconds), nothing random.
// source_scale_workload_of() builds the same workload over another rgba8 volume (bench_deform_frame
// --volume: a radiance field's reconstruction).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>

#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::bench {

struct SourceScaleWorkload {
    volume::Volume source;  // 256³ rgba8
    pbd::TetGrid grid;      // 64³ cells, active cells only
};

// The workload over rgba8 volume `source`: its tet grid of cells of 4 voxels over the visible
// voxels.
inline std::unique_ptr<SourceScaleWorkload> source_scale_workload_of(volume::Volume source) {
    auto out = std::make_unique<SourceScaleWorkload>();
    out->source = std::move(source);
    out->grid = pbd::build_tet_grid(out->source, {.cell_voxels = 4});
    return out;
}

inline const SourceScaleWorkload& source_scale_workload() {
    static const std::unique_ptr<SourceScaleWorkload> w = [] {
        const volume::Volume scalar = volume::shepp_logan_3d({256, 256, 256});
        const volume::Volume rgba = volume::apply(scalar, volume::preset("mri-brain", scalar));
        volume::Volume source = volume::Volume::allocate(rgba.dims(), volume::VoxelType::rgba8,
                                                         rgba.spacing(), rgba.origin());
        const auto* in = reinterpret_cast<const float*>(rgba.bytes().data());
        auto* dst = reinterpret_cast<std::uint8_t*>(source.bytes().data());
        const std::int64_t n = 4 * rgba.num_voxels();
        for (std::int64_t i = 0; i < n; ++i) {
            dst[i] = static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(in[i], 0.0f, 1.0f)));
        }
        return source_scale_workload_of(std::move(source));
    }();
    return *w;
}

}  // namespace pliant::bench
