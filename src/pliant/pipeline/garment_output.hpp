// What `pliant cloth` writes for a garment beside its frames: the material libraries its OBJ
// names (so the frames show with their materials), and the whole run as one point cache, PC2
// (io/pc2.hpp) or MDD (io/mdd.hpp), for DCC tools that animate a mesh imported once (frame 0).
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "pliant/io/obj_polygons.hpp"

namespace pliant::pipeline {

// Copies each `mtllib` file of the garment (names relative to source_dir, the OBJ's directory;
// several per line allowed) into frames_dir, atomically, unless it is there with the same bytes.
// A library that cannot be read is a warning (the frames keep the `mtllib` line); textures the
// library names are not copied. Returns the number copied. IoError when a copy cannot be written.
int copy_material_libraries(const io::PolygonMesh& garment, const std::filesystem::path& source_dir,
                            const std::filesystem::path& frames_dir, const std::string& scene_name);

// The file name of a point cache kind ("pc2" → "cloth.pc2", "mdd" → "cloth.mdd"); InvalidInput
// for another kind, listing the valid ones.
std::string point_cache_file_name(const std::string& kind);

// Writes `path` as a point cache of `kind` ("pc2" or "mdd") from the frame files frame_0000 …
// frame_<last_frame> (names from frame_file(n)) read back in order: frame 0 is sample 0, at time 0;
// MDD's frame times are n / frames_per_second seconds. Throws what reading or writing throws;
// InvalidInput for an unknown kind or when a frame has another vertex count than frame 0.
void write_point_cache_from_frames(const std::filesystem::path& path, const std::string& kind,
                                   int last_frame, double frames_per_second,
                                   const std::function<std::filesystem::path(int)>& frame_file);

}  // namespace pliant::pipeline
