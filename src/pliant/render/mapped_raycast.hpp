// Ray casting a deformed volume through its inverse map, without resampling it (issue 29): each
// ray sample in the deformed (target) frame takes the source grid coordinate the map gives
// (volume::InverseMap, trilinear in its coarse nodes) and samples the rest (source) volume there.
//
//   render::MappedRayCaster caster(source, tf, target_frame, {.shading = true});  // once
//   volume::InverseMap map;
//   map.build(source, target_frame, tets, rest_positions, deformed_positions);      // per frame
//   caster.set_map(map);
//   caster.render(camera, image);
//
// It renders what RayCaster renders of volume::resample_through(map, source, target) up to the
// interpolation: the exact pipeline (Resampler, then RayCaster) interpolates the resampled voxels
// trilinearly in the target frame; here the map is interpolated in the target frame and the
// source in its own (tests/render/mapped_raycast_test.cpp measures the PSNR against it on the
// four drivers). Everything else is RayCaster's algorithm (render/raycast.hpp): the same rays,
// step, sample positions, RGBA premultiplied interpolation, lookup table, opacity correction,
// front-to-back compositing, early termination, shortened last segment and clipping plane.
// Differences:
//   - Sample: t the target grid coordinate (clamped to [0, n − 1]), g = map(t); g outside the
//     source box [−0.5, n_s − 0.5]³ is transparent (the resampler writes 0 there), else the source
//     is classified at g exactly as RayCaster classifies a voxel-grid sample.
//   - Shading: the gradient in the target frame by the chain rule, component a = ∇_s v(g) ·
//     ∂g/∂t_a (∂g/∂t_a the map's trilinear derivative) scaled by the target spacing, then
//     0.3 + 0.7 |n · d| as RayCaster. ∇_s v(g) is RayCaster's central difference one source
//     voxel apart, read from a gradient stored once (constructor, in parallel over layers): per
//     source voxel the central differences of the shaded value (scalar, or α) along x, y, z,
//     the index clamped to the grid, in int16 (8 bytes per voxel, 134 MB at 256³; floats were
//     slower, docs/journal/2026-11-29-mapped-gradient.md), interpolated trilinearly: the
//     central difference of a trilinear interpolant is the interpolant of the voxels'
//     differences, so a translation's gradient is RayCaster's up to the quantization.
//   - Empty-space skipping on the map's node cells (B³ target voxels, B = node_voxels): a cell
//     whose 8 nodes are not all set is transparent; one whose nodes are set is visible when some
//     source voxel that a sample in it can read has opacity, tested conservatively: trilinear
//     interpolation stays in the convex hull of its 8 nodes, so its samples lie in the box of
//     the node values (widened by 1/32 voxel for rounding), and the voxels their interpolation
//     reads are tested through bricks of 4³ voxels, 64 bits each, the bit of voxel v set when
//     the cell with first corner v (the voxels {v, v + 1}³) may have opacity: RGBA when one of
//     its voxels has α > 0 (the α bits dilated toward −x, −y, −z once), scalars when the
//     lookup entries of its value range widened by detail::LERP_ROUNDING have opacity (as
//     RayCaster tests its cells; once per transfer function, in the constructor). The cells a
//     box's samples interpolate in are exactly bits [v0, v1], so the point at a cell's centre
//     reads one bit of one word (2 MB for 256³; a box reads a word per brick it overlaps).
//     Each visible cell has 8 sub-cells (its halves along each axis, (B/2)³ target voxels),
//     each tested the same way on the box of the map at its 8 corners (the map is
//     trilinear on a half-cell too; the lattice of fractions 0, 1/2, 1): when the voxels the
//     cell's centre reads (a corner of every sub-cell) have opacity all 8 are visible without
//     a test, which settles most cells inside the body; a cell whose sub-cells are all empty
//     is empty. Empty cubes per octant over the cells (detail::empty_cubes) drive the jumps; a
//     sample in an empty sub-cell of a visible cell jumps past that sub-cell; a ray is marched
//     only over its samples within the visible cells' extents along the axes and the 4
//     diagonals (kept by compute_map(), detail::visible_samples()), so a lane does not jump
//     through the empty space before and after them. Skipped samples would contribute nothing, so
//     images are identical with and without skipping (tested). At the source scale (twist) the
//     sub-cells cut the samples classified from 1.62 M to 1.30 M (the exact route: 1.27 M).
//   - An rgba8 source is kept as its bytes (4 per voxel, 67 MB at 256³) instead of RayCaster's
//     premultiplied float copy (16 bytes per voxel, 268 MB, not built): a sample premultiplies
//     each of its 8 corners in integers (α·c and α, exact in float; detail::rgba8_voxel()) and
//     scales the interpolated values once (opacity α / 255, straight colour α·c / (255 α)): the
//     float copy's values up to rounding (tested against the same source as rgba32f: the same
//     pixels and samples). Shaded, each voxel's bytes and its stored gradient share one 16-byte
//     record (detail::PACKED_VOXEL_BYTES; 268 MB at 256³), so a lane's voxel pair of a row is one
//     32-byte load for both. rgba32f and scalar sources are read from the float copy.
//   - An rgba8 source is marched with an opacity-adaptive step (set_thin_alpha(),
//     set_thin_levels(); 0 turns it off): where every voxel a sample reads has an α byte below
//     the threshold (default 32: the haze a radiance field's density leaves), a ray takes one
//     sample per two steps, at their shared end, with the opacity correction of 2Δs, and, shaded,
//     one per four steps where every voxel within a voxel of those it reads is below half the
//     threshold (the packed records hold that neighbourhood's α; default 2 levels); a coarse
//     sample that reads a denser voxel is discarded and its steps are sampled at the level it
//     allows (detail::mapped_march()). Empty space is thin and the jumps keep a ray's runs of
//     the coarsest level; with the first level alone images stay the same with and without
//     skipping, with the second a march without skipping may take finer runs beside visible
//     voxels (PSNR ≥ 65 dB between the two, tested). Against the fixed step: at least 40 dB (tests:
//     a haze, the phantom); the demo's dataset trained 1,500 iterations 46–48 dB with 45–47 % of
//     its samples (docs/journal/2026-11-30-dense.md, 2026-11-30-thin-levels.md).
//   - Composite mode only (MIP through the map: InvalidInput).
// Cost per frame: the map's state (MapOccupancy, compute_map()) is O(map cells) (parallel over
// layers; the cells outside the map's node row extents, InverseMap::node_row_extents(), only
// cleared) plus a copy of the nodes padded to 4 floats, plus the empty cubes (O(map cells) each)
// of the octants asked for; render() computes the empty cubes of the octants its rays can have
// (1–4 for a camera outside the volume: the signs of the ray directions at the image's 4
// corners, both signs of an axis where they are within 1e-5 of 0, octants_of()) that are not
// computed yet; a sample costs one more trilinear interpolation of 3
// floats (the map) than RayCaster's, and shaded samples one trilinear interpolation of the
// stored gradient (3 channels; a 16-byte load per voxel pair and row, or the packed records'
// 32-byte load, shared with an rgba8 source's bytes). A ray's march ends at its
// early termination (no sample past it is classified). RGBA and scalar sources on a CPU with AVX2
// march 8 rays per vector, a lane refilled from the tile's rays as soon as its ray ends
// (detail/mapped_raycast_avx2.hpp), bitwise the scalar kernel (images and sample counts).
// Off the render thread: compute_map() is const and reads only what the constructor prepared,
// so a frame pipeline computes the next map's state on the thread that built the map while the
// caster renders the current one, and install_map() swaps it in (O(1)) before the next render:
//
//   render::MapOccupancy next;                                   // per map buffer
//   caster.compute_map(maps[back], next, caster.octants_of(camera));   // background thread
//   caster.install_map(next);  caster.render(camera, image);    // render thread, in turn
//
// Determinism: 16 × 16 tiles through core/parallel, every pixel the same float operations:
// bitwise identical images for 1 and N threads.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "pliant/render/camera.hpp"
#include "pliant/render/detail/mapped_raycast_kernel.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::render {

class MappedRayCaster;

// The per-map state of a MappedRayCaster: what it derives from one inverse map for its march —
// the map cells' and sub-cells' occupancy (detail::MAP_CELL_* bits), the visible cells' extents,
// the nodes padded to 4 floats and the empty cubes of some octants. Computed by
// MappedRayCaster::compute_map() (for that caster alone: it is tagged with the caster, and
// install_map() refuses another caster's), installed by MappedRayCaster::install_map() in O(1).
// It refers to its map, which must stay alive and unchanged while the state is used. A value:
// movable, and its buffers are reused by the next compute_map() into it. Not thread safe: one
// thread at a time (the one computing it, then the one installing it).
class MapOccupancy {
public:
    bool has_map() const { return m_map != nullptr; }
    const volume::InverseMap* map() const { return m_map; }
    double ms() const { return m_ms; }  // compute_map()'s wall time
    // The octants (bit per octant, detail::octant_of()) whose empty cubes are computed.
    int octants() const { return m_octants_ready; }
    std::int64_t num_cells() const { return static_cast<std::int64_t>(m_occupancy.size()); }
    std::int64_t num_visible_cells() const;
    // Forgets the map (has_map() false; the buffers are kept for the next compute_map()).
    void clear();

private:
    friend class MappedRayCaster;
    std::uint64_t m_caster = 0;  // the id of the caster that computed it (0: none)
    const volume::InverseMap* m_map = nullptr;
    double m_ms = 0.0;
    std::array<int, 3> m_cells{0, 0, 0};
    std::vector<std::uint8_t> m_occupancy;     // per map cell, detail::MAP_CELL_* bits
    std::vector<std::uint8_t> m_sub_occupied;  // per map cell, its visible sub-cells' bits
    std::vector<std::uint8_t> m_visible;       // per map cell, 0 / 1 (empty_cubes' input)
    detail::VisibleCells m_visible_cells;      // their extents (detail::visible_samples())
    std::vector<float> m_nodes4;               // the map's nodes, 4 floats each (x, y, z, 0)
    // 8 octants × map cells, those of m_octants_ready computed (a render of the installed state
    // computes the octants its rays use that are not, under its caster's mutex).
    mutable std::vector<std::uint8_t> m_empty_cube;
    mutable int m_octants_ready = 0;
};

class MappedRayCaster {
public:
    // source: the rest volume, prepared once as RayCaster prepares it (tf for scalar volumes, as
    // RayCaster; an rgba8 source's bytes are copied); target: the frame the maps are built for
    // (dims, spacing, origin; data unused). The step and opacity unit default from the target as
    // RayCaster's would. InvalidInput as RayCaster's constructor, for an empty target, or for
    // options.mode = mip.
    MappedRayCaster(const volume::Volume& source, const volume::TransferFunction* tf,
                    const volume::Volume& target, const RayCastOptions& options = {});
    ~MappedRayCaster();
    MappedRayCaster(const MappedRayCaster&) = delete;
    MappedRayCaster& operator=(const MappedRayCaster&) = delete;

    // The state of `map` (built for this caster's source and target frames) into `state`, its
    // buffers reused, with the empty cubes of `octants` (bit per octant, e.g. octants_of() of
    // the next render's camera; render() computes the others it needs). InvalidInput for a map
    // that was not built or was built for another target frame. Thread safety: it reads only
    // what the constructor prepared, so it may run on any thread concurrently with render(),
    // set_map(), install_map(), set_clip() and other compute_map() calls (into other states);
    // not with the destructor. Deterministic: the same state for any number of threads.
    void compute_map(const volume::InverseMap& map, MapOccupancy& state, int octants = 0) const;
    // Makes `state` (computed by this caster's compute_map()) the map of the next renders, in
    // O(1): `state` gets the state installed before (its buffers reusable). InvalidInput for a
    // state without a map or computed by another caster (e.g. a caster since rebuilt for a new
    // transfer function). Not during a render.
    void install_map(MapOccupancy& state);
    // Whether compute_map() of this caster made `state` (install_map() accepts it).
    bool is_own(const MapOccupancy& state) const {
        return state.m_caster == m_id && state.has_map();
    }
    // compute_map() into the installed state, on the caller: the one-call form. The map must
    // stay alive and unchanged while it is installed. Not during a render.
    void set_map(const volume::InverseMap& map);
    // Renders through the installed map (InvalidInput before the first set_map() or
    // install_map()); resizes image. Computes the empty cubes its rays need first (serialized
    // between concurrent renders).
    RayCastStats render(const Camera& camera, Image& image) const;
    // The octants (bit per octant) the rays of `camera` can have: the empty cubes render()
    // needs.
    int octants_of(const Camera& camera) const;
    // Changes the clipping plane of later renders; InvalidInput as RayCaster::set_clip.
    void set_clip(const std::optional<ClipPlane>& clip);
    // The opacity-adaptive step of later renders of an rgba8 source (ignored for other sources;
    // detail/mapped_raycast_kernel.hpp, mapped_march()): where every voxel a sample reads has an
    // opacity below thin_alpha / 2^(l − 1) (the haze of a radiance field), a ray takes one
    // sample per 2^l steps, l ≤ thin_levels, with the opacity of the longer step; the second
    // level also asks the voxels around those read to be below thin_alpha / 2 and is taken for
    // shaded sources only (their packed records hold that neighbourhood's α). thin_alpha 0 or
    // thin_levels 0: every step sampled (RayCaster's samples). Defaults
    // detail::THIN_ALPHA_BYTES / 255 and RayCastOptions::thin_levels. InvalidInput outside
    // [0, 1] and [0, detail::MAX_THIN_LEVELS].
    void set_thin_alpha(double thin_alpha);
    double thin_alpha() const { return m_thin_alpha; }
    void set_thin_levels(int levels);
    int thin_levels() const { return m_thin_levels; }

    double step() const { return m_step; }
    double prepare_ms() const { return m_prepare_ms; }  // the source's preparation (constructor)
    double map_ms() const { return m_state.ms(); }      // the installed state's compute_map()
    std::int64_t num_cells() const { return m_state.num_cells(); }
    std::int64_t num_visible_cells() const { return m_state.num_visible_cells(); }

private:
    // Whether a sample whose source coordinate lies in the box [lo, hi] may have opacity: some
    // source cell its interpolation can read (the box widened by HULL_MARGIN, clamped as
    // locate() clamps) may (the bricks: RGBA, a voxel of the cell has α > 0; scalar, the
    // cell's value range reaches a lookup entry with opacity). Exact per cell.
    bool hull_visible(const float lo[3], const float hi[3]) const;
    // Per axis the first corners [v0, v1] of the cells samples in [lo, hi] (widened by
    // HULL_MARGIN, clamped as locate() clamps) interpolate in; false when all lie outside.
    bool corner_range(const float lo[3], const float hi[3], std::int64_t v0[3],
                      std::int64_t v1[3]) const;
    // Whether a cell with first corner in [v0, v1] may have opacity (the bricks).
    bool bricks_visible(const std::int64_t v0[3], const std::int64_t v1[3]) const;
    // The stored source gradient (detail::GradientValue) of the prepared source, in parallel
    // over layers (each written by one task: the same values for any number of threads).
    // An rgba8 source's gradient goes into m_packed with its bytes (m_rgba8, then released).
    void build_gradient();
    // Computes the empty cubes of the octants (bit per octant) of `state` not yet computed
    // (the caller serializes access to `state`).
    static void compute_cubes(const MapOccupancy& state, int octants);
    // The sub-cells of a valid map cell (nodes g + 3 (base + off[c]), c = x + 2 y + 4 z; [lo, hi]
    // the box of their values) that may have opacity, bit s_x + 2 s_y + 4 s_z
    // (detail::sub_cell_of()): the map is trilinear in the cell, so on a half-cell it is
    // trilinear in the map's values at that half-cell's corners (the lattice of fractions 0,
    // 1/2, 1), whose box hull_visible() tests.
    std::uint8_t sub_cells_visible(const float* g, std::int64_t base, const std::int64_t off[8],
                                   const float lo[3], const float hi[3]) const;

    std::uint64_t m_id = 0;  // unique per caster of the process (MapOccupancy's tag)
    RayCastOptions m_options;
    // The source's floats and lookup table (an rgba8 source: one voxel, for the options' fields).
    std::unique_ptr<RayCaster> m_source;
    // An rgba8 source's bytes (4 per voxel), read by the march in place of a float copy.
    std::vector<std::uint8_t> m_rgba8;
    volume::Dims m_source_dims{0, 0, 0};
    volume::Dims m_target_dims{0, 0, 0};
    Vec3d m_target_spacing, m_target_origin;
    double m_step = 0.0;
    double m_thin_alpha = detail::THIN_ALPHA_BYTES / 255.0;
    int m_thin_levels = 0;  // RayCastOptions::thin_levels
    double m_prepare_ms = 0.0;
    // Per source cell (first corner v, the voxels {v, v + 1}³ clamped to the grid) whether a
    // sample interpolated in it may have opacity, a bit per cell, a 64-bit word per brick of 4³
    // cells (x fastest): RGBA, a voxel of the cell has α > 0 (the α bits dilated by one voxel
    // toward −x, −y, −z); scalar, the lookup entries of the cell's value range widened by
    // detail::LERP_ROUNDING have opacity (RayCaster's cell test), set once per transfer
    // function (the constructor).
    std::array<std::int64_t, 3> m_bricks{0, 0, 0};
    std::vector<std::uint64_t> m_brick_bits;
    // The installed map's state; render() computes its missing empty cubes under m_cubes_mutex.
    MapOccupancy m_state;
    mutable std::mutex m_cubes_mutex;
    // Shading: the source's gradient, 4 values per voxel (detail::GradientValue), else empty.
    std::vector<detail::GradientValue> m_gradient;
    // A shaded rgba8 source: per voxel its bytes and gradient in one record
    // (detail::PACKED_VOXEL_BYTES, as 8 GradientValues: 268 MB at 256³), in place of m_rgba8
    // and m_gradient.
    std::vector<detail::GradientValue> m_packed;
};

}  // namespace pliant::render
