// How much memory a command needs, against what it may use: work too large for the machine (or
// for --max-memory) is refused before anything is allocated or written, instead of being killed
// by the operating system hours of swapping later.
//
// One rule serves every command: its need is the sum of what it allocates by input size (each
// part estimated from the input's dimensions with the constants below), checked with
// require_memory() against memory_limit_bytes(--max-memory). The constants are measured peak
// resident sizes (GNU time's "Maximum resident set size" of a run, minus the same run on a tiny
// input), rounded down, so a refused run would certainly not have fitted; a run just under the
// limit can still need more (dense contact, a crowded broad phase).
#pragma once

#include <cstdint>
#include <string>

#include "pliant/volume/volume.hpp"

namespace pliant::pipeline {

// The least memory a cloth simulation takes per triangle (bytes), from the peak resident size of
// one frame of falling grid sheets without contact: with self-collision 1.31 KB at 1000 x 1000
// quads (2 million triangles; 1.39 KB at 536 x 536, more on smaller sheets and in contact),
// without 0.53 KB at 2000 x 2000 quads.
inline constexpr std::uint64_t CLOTH_BYTES_PER_TRIANGLE = 500;
inline constexpr std::uint64_t SELF_COLLIDING_CLOTH_BYTES_PER_TRIANGLE = 1300;

// `pliant collide`'s broad phase per triangle of the mesh (bytes): the mesh, topology (edges,
// incidence), feature boxes, the LBVH and its sort buffers. Measured: 542 bytes per triangle
// (peak resident size of `pliant collide` on a flat 400 x 400-quad grid OBJ, 320,000 triangles,
// minus that on a 20 x 20 one); a crumpled mesh has more pairs and needs more.
inline constexpr std::uint64_t BROAD_PHASE_BYTES_PER_TRIANGLE = 500;

// `pliant deform`'s soft body per tetrahedron of the grid (bytes): rest and deformed tet meshes,
// edges and their colouring, XPBD state and the resampler's per-tet data. Measured: 132.6 bytes
// per tet (peak resident size of `pliant deform` on a 128³ sphere, --full-box, --cells 2:
// 1,310,720 tets, minus --cells 16: 2,560 tets). A grid has 5 tets per cell.
inline constexpr std::uint64_t SOFT_BODY_BYTES_PER_TET = 128;

// The memory this process may use, in bytes: the machine's physical memory, or the control
// group's limit when lower (cgroup v2 memory.max, v1 memory.limit_in_bytes); 0 when neither
// can be determined.
std::uint64_t available_memory_bytes();

// The limit a command checks against: `max_memory_mib` MiB (--max-memory) when positive, else
// available_memory_bytes() (0: unknown, no check).
std::uint64_t memory_limit_bytes(double max_memory_mib);

// a · b, or UINT64_MAX when that overflows (a need that large is refused, never wrapped).
std::uint64_t saturating_product(std::uint64_t a, std::uint64_t b);
// a + b, or UINT64_MAX when that overflows.
std::uint64_t saturating_sum(std::uint64_t a, std::uint64_t b);

// "0.262 MB", "1.05 MB", "104 MB", "127.4 GB" (decimal units, 3 significant digits in MB).
std::string format_bytes(double bytes);

// Throws InvalidInput "<what> needs <X>, more than the <Y> allowed by --max-memory (or
// available)" when needed_bytes > limit_bytes (limit 0: unknown, no check).
void require_memory(const std::string& what, std::uint64_t needed_bytes, std::uint64_t limit_bytes);

// Bytes of an 8-bit RGB image of width × height pixels (render::Image).
std::uint64_t image_bytes(std::int64_t width, std::int64_t height);

// Bytes render::RayCaster prepares for a volume of `dims` with `channels` channels (1 or 4): a
// float per voxel and channel (scalar volumes: one lookup coordinate; RGBA: one more for the α
// copy of shaded views, counted whether shaded or not), plus its macro-cell tables (less than a
// byte per voxel).
std::uint64_t ray_cast_bytes(const volume::Dims& dims, int channels);

// Bytes render::MappedRayCaster prepares for a source of `dims` with `channels` channels (1 or
// 4), shaded or not: its float copy (4 bytes per channel; an rgba8 source: its 4 bytes), the
// stored gradient (8 bytes; a shaded rgba8 source: the 16-byte packed records, with the 2 bytes
// of their neighbourhood passes while its bytes are still held), and the occupancy bits (less
// than a byte per voxel): at most 24 bytes per voxel (RGBA) or 12 (scalar), plus one.
std::uint64_t mapped_ray_cast_bytes(const volume::Dims& dims, int channels);

// Bytes of ray-casting `source` into one image of width × height pixels at a time: the volume
// itself, ray_cast_bytes() and the image.
std::uint64_t ray_cast_need_bytes(const volume::Volume& source, std::int64_t width,
                                  std::int64_t height);

// "a 512x512 image of the 256 x 256 x 128 uint8 volume": the what of a ray-casting need.
std::string ray_cast_what(const volume::Volume& source, std::int64_t width, std::int64_t height);

// Bytes of `pliant collide`'s broad phase over a mesh of `triangles` triangles.
std::uint64_t broad_phase_need_bytes(std::uint64_t triangles);

// Bytes of `pliant deform` on a grid of `cells` cells of B³ voxels over `source` (5 tets per
// cell; every cell counted, so an upper bound when cells are empty): the soft body, the
// resampling target (a volume like the source) and, with width × height > 0, the ray caster (the
// larger of RayCaster's and MappedRayCaster's: either route) and one image.
std::uint64_t deform_need_bytes(const volume::Volume& source, std::uint64_t cells,
                                std::int64_t width, std::int64_t height);

// Throws InvalidInput "<what>: <triangles> triangles need at least <X GB or MB> to simulate,
// more than the <Y GB or MB> of memory available" when triangles times the bytes per triangle above
// (with or without self-collision) exceeds memory_bytes (0: unknown, no check).
void require_cloth_fits_in_memory(const std::string& what, std::uint64_t triangles,
                                  bool self_collision, std::uint64_t memory_bytes);

}  // namespace pliant::pipeline
