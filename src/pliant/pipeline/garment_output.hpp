// What `pliant cloth` writes for a garment beside its frames: the material libraries its OBJ
// names (so the frames show with their materials), and the whole run as one PC2 point cache
// (io/pc2.hpp) for DCC tools that animate a mesh imported once.
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

// Writes `path` (PC2) from the frame files frame_0000 … frame_<last_frame> (names from
// frame_file(n)) read back in order: frame 0 is sample 0. Throws what reading or writing throws;
// InvalidInput when a frame has another vertex count than frame 0.
void write_point_cache_from_frames(const std::filesystem::path& path, int last_frame,
                                   const std::function<std::filesystem::path(int)>& frame_file);

}  // namespace pliant::pipeline
