// PC2 point caches (.pc2): one file holding every frame's vertex positions of a mesh whose
// topology does not change, the format Blender (Mesh Cache modifier), 3ds Max (Point Cache) and
// Houdini read to animate a mesh imported once (the OBJ frame 0 of a run).
//
// Layout (little-endian): char[12] "POINTCACHE2\0", int32 version 1, int32 #points, float32
// start frame, float32 sample rate (frames per sample: 1), int32 #samples; then for each sample
// #points × (float32 x, y, z). Points in the mesh's vertex order.
//
// write_pc2(path, num_points, num_samples, start_frame, sample) writes the header and asks
// sample(s, out) for the positions of sample s (out has num_points entries), in order, streaming;
// the file is replaced atomically (atomic_file.hpp). InvalidInput (before touching the file) for
// more than 2^31 - 1 points or samples; a non-finite position is InvalidInput and leaves no file;
// IoError when the file cannot be written; whatever sample throws propagates (no file left).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "pliant/core/function_ref.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::io {

void write_pc2(const std::filesystem::path& path, std::int64_t num_points, std::int64_t num_samples,
               double start_frame, FunctionRef<void(std::int64_t, std::span<Vec3f>)> sample);

}  // namespace pliant::io
