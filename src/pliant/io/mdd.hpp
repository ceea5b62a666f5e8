// MDD point caches (.mdd): LightWave's format for every frame's vertex positions of a mesh whose
// topology does not change, read by Blender (Mesh Cache modifier; the "Import Lightwave Point
// Cache" add-on), Houdini, Maya, 3ds Max and LightWave to animate a mesh imported once (frame 0 of
// a run).
//
// Layout (big-endian, no padding): int32 #frames, int32 #points; float32 time of each frame in
// seconds (#frames values: frame / fps); then for each frame #points × (float32 x, y, z). Points in
// the mesh's vertex order. The size is therefore exactly 8 + 4 F + 12 F P bytes.
//
// write_mdd(path, num_points, num_frames, frames_per_second, frame) writes the header and asks
// frame(f, out) for the positions of frame f (out has num_points entries), in order, streaming;
// the file is replaced atomically (atomic_file.hpp), so a run killed while writing leaves the
// earlier file or none, never a partial one. InvalidInput (before touching the file) for more
// than 2^31 - 1 points or frames or a frames_per_second that is not finite and positive; a
// non-finite position is InvalidInput and leaves no file; IoError when the file cannot be
// written; whatever frame throws propagates (no file left).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "pliant/core/function_ref.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::io {

void write_mdd(const std::filesystem::path& path, std::int64_t num_points, std::int64_t num_frames,
               double frames_per_second, FunctionRef<void(std::int64_t, std::span<Vec3f>)> frame);

}  // namespace pliant::io
