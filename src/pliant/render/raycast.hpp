// Volume ray casting (Algorithm 1 of the deformable-volume paper, made fast): front-to-back alpha
// compositing of a scalar volume through a transfer function, or of an RGBA volume, with
// early ray termination and empty-space skipping; maximum intensity projection as a second mode.
//
//   const volume::Volume head = volume::shepp_logan_3d({256, 256, 256});
//   const volume::TransferFunction tf = volume::preset("mri-brain", head);
//   const render::Camera cam = render::frame_box(head.world_bounds(), 30, 20, 512, 512);
//   render::Image image;
//   const render::RayCastStats stats = render::raycast(head, &tf, cam, {}, image);
//
// Algorithm (per pixel, render::detail::raycast_pixel, a pure function of the pixel index over
// trivially copyable data, GPU-style):
//   1. The pixel-centre ray (Camera::pixel_ray) is clipped against the volume's box
//      [origin, origin + dims · spacing] (slab test; in the grid's frame for oriented volumes),
//      t ∈ [max(t_near, 0), t_far]: a camera inside the volume starts at its eye.
//   2. The clipped chord of length D is cut into N = ⌈D / Δs⌉ segments of the step Δs (world
//      units), the last one shortened to D − (N − 1)Δs; each segment is represented by the sample
//      at its midpoint. Sample positions depend only on the ray, never on skipping.
//   3. A sample is trilinear in the voxel values (voxel centres at origin + (i + 0.5) spacing;
//      clamp-to-edge in the half voxel at the box faces). Scalar volumes are interpolated first
//      and classified after (post-classification) through a 4096-entry lookup table over the
//      volume's value range [lo, hi] (nearest entry), built once per call from the transfer
//      function with the opacity already corrected for the step:
//        α_Δs = 1 − (1 − α)^(Δs / u)          (volume/transfer_function.hpp, corrected_opacity)
//      where α is the opacity per opacity unit u. RGBA volumes interpolate opacity-weighted
//      colour (α·r, α·g, α·b, α) — no colour bleeding from transparent voxels — and correct the
//      interpolated α per sample. The shortened last segment of length ℓ uses
//      1 − (1 − α_Δs)^(ℓ / Δs).
//   4. Front-to-back compositing (Levoy 1988; Engel et al. 2006, eq. 7.15):
//        C += (1 − A) · α_Δs · c,     A += (1 − A) · α_Δs,
//      stopping when A > early_termination (0.99). The pixel is C + (1 − A) · background.
//      Consequence: a uniform medium of colour c and opacity a per unit u over a chord L renders
//      c · (1 − (1 − a)^(L / u)) for every step (exact up to float rounding).
//   5. Empty-space skipping: the volume is covered by macro cells of 4³ trilinear cells; macro
//      cell c holds the samples whose lower voxel corner ⌊g⌋ is in [4c, 4c + 3] per axis, so it
//      reads exactly the voxels [4c, 4c + 4] (its footprint). A cell is occupied when some value
//      of its footprint has a non-zero opacity (min/max of the values against a prefix count of
//      the lookup table's non-zero entries, the range widened by 1/64 entry per side for the
//      rounding of the interpolation, detail::LERP_ROUNDING; max α for RGBA). A volume whose
//      background sits exactly at an entry of zero opacity (air at the bottom of the range under
//      `grayscale`) is thus skipped there. For each of the 8 octants of ray directions, every
//      empty cell stores the side s (≤ 255 cells) of the largest cube of empty cells that has it
//      as a corner and extends towards that octant (a largest-empty-square recurrence in 3D). A
//      sample whose cell is empty is not classified: the ray jumps to the first sample past the
//      cube of its octant (its far planes pulled in by 1/32 voxel so that float rounding cannot
//      carry a skipped sample out of the cube); unlike a distance field, the cube ignores what
//      lies behind the ray, so rays passing an object jump far. A ray with a zero direction
//      component (axis views) never moves along that axis, so the cubes towards either side of
//      it are valid too, and it jumps the largest of them. Inside an occupied cell, each
//      of its 8 sub-cells of 2³ trilinear cells has an occupancy bit of its own (footprint 3³
//      voxels), and a sample in an empty sub-cell is skipped alone. The occupancy test of a sample
//      uses the same integer corner its interpolation reads, and skipped samples contribute
//      nothing, so images are identical with or without skipping.
//   Oriented volumes (Volume::direction() D not the identity, an oblique scan): the kernel works
//   in the grid's own frame, where the volume is the axis-aligned box above. Each ray's origin
//   and direction (render: the camera's eye, forward, right and up; render_rays: the caller's
//   rays) and the clipping plane's normal are taken there by the inverse rigid motion
//   p ↦ Dᵀ (p − origin), in double before the cast to float; lengths, the step, the opacity
//   unit and |n · d| are unchanged by it, so steps 2–5 and shading are exactly those of an
//   axis-aligned volume, and the image is the volume rendered in world space without resampling.
//   An axis-aligned volume (D = I) skips the transform: its images are bit for bit unchanged.
//   Frame such a volume with Volume::world_bounds() (bounds() is its box in the grid's frame).
//   Clipping plane (optional): the half-space (p − point) · normal ≥ 0 is kept: step 1 also cuts
//   the ray to it (t ≥ or ≤ the plane's crossing; a ray parallel to the plane is kept whole or
//   missed), so the chord of step 2 is the kept part and a uniform medium renders
//   c · (1 − (1 − a)^(L / u)) with L the clipped chord. Skipping and shading are unchanged
//   (gradients still read the voxels beyond the plane).
//   Shading (optional): the colour of a sample is scaled by 0.3 + 0.7 |n · d|, n the normalized
//   gradient (central differences of trilinear samples one voxel apart, of the scalar value, or of
//   α for RGBA volumes; world-space through the spacing), d the ray direction (a headlight);
//   samples with a gradient of zero length are not shaded.
//   MIP: the sample with the largest value (scalar volumes) or largest α (RGBA) along the chord;
//   the pixel is c · a + (1 − a) · background with (c, a) its colour and opacity per unit
//   (not step-corrected), zero when nothing is hit. A sample in a macro cell whose largest value
//   does not exceed the running maximum jumps to the cell's end.
//
// Units: step and opacity_unit in world units (those of Volume::spacing). Colours linear in
// [0, 1], written to the 8-bit image by to_rgb8 (clamped, rounded; no gamma).
// Parallelism: 16 × 16 pixel tiles through core/parallel (one chunk per tile); every pixel is
// computed by the same float operations whatever the thread count, so images and statistics are
// bitwise identical for 1 and N threads.
// Cost: O(width · height · (samples + jumps) per ray); the lookup table, the macro-cell grid and
// its empty cubes are built in O(voxels) per call, plus a float copy of the voxels (4 bytes
// per voxel, 16 for RGBA, 20 for shaded RGBA: α apart for the gradients). The kernel is in
// render/detail/raycast_kernel.hpp.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::render {

namespace detail {
struct RayCastKernel;
}

enum class RayCastMode { composite, mip };

// Keeps the half-space (p − point) · normal ≥ 0 (world units); the other side is cut away.
struct ClipPlane {
    Vec3d point{0.0, 0.0, 0.0};
    Vec3d normal{0.0, 0.0, 1.0};  // need not be unit; finite and nonzero
};

struct RayCastOptions {
    // Distance between samples along a ray, world units (> 0), or 0: half the volume's smallest
    // spacing (two samples per voxel, the sampling theorem's rate for trilinear data).
    double step = 0.0;
    // World units that RGBA opacities, and transfer functions whose own opacity_unit is 0, are
    // given per (> 0), or 0: the volume's smallest spacing. A transfer function with an
    // opacity_unit > 0 keeps its own.
    double opacity_unit = 0.0;
    // Rays stop when their accumulated opacity exceeds this, in (0, 1]; 1 never stops early.
    double early_termination = 0.99;
    RayCastMode mode = RayCastMode::composite;
    bool shading = false;  // gradient (headlight) shading; composite mode only
    Color background{0.0f, 0.0f, 0.0f};
    bool empty_space_skipping = true;  // off: every sample evaluated (for tests and benchmarks)
    std::optional<ClipPlane> clip;     // none: the whole volume
    // MappedRayCaster with an rgba8 source only (others ignore it): the levels of its
    // opacity-adaptive step, 0 … 2 (MappedRayCaster::set_thin_levels(): runs of up to 2^levels
    // steps sampled once in faint haze); 0: every step sampled, as RayCaster samples.
    int thin_levels = 2;
};

struct RayCastStats {
    std::int64_t samples = 0;  // samples evaluated (classified), over all rays
    double ms = 0.0;           // wall-clock time of the rendering (raycast(): tables included)
};

// The prepared form for rendering one volume many times (orbits, benchmarks): the float copy of
// the voxels, the lookup table and the macro-cell grid are built once in the constructor
// (O(voxels), parallel) and render() only casts rays. Keeps no reference to its arguments.
// Scalar volumes (u8, i16, u16, f32) need a transfer function `tf` (validated here); RGBA
// volumes (rgba8 as channel/255, rgba32f) use their own colour and opacity and ignore `tf`.
// Throws InvalidInput for an empty volume, a scalar volume without tf, an invalid tf, or options
// out of range (the message names the option and its value). render() resizes `image` to
// camera.width() × camera.height(); it is const and thread safe for distinct images.
class RayCaster {
public:
    RayCaster(const volume::Volume& volume, const volume::TransferFunction* tf,
              const RayCastOptions& options = {});
    RayCastStats render(const Camera& camera, Image& image) const;
    // Casts the given world-space rays (origins, unit directions: e.g. the per-pixel rays of a
    // camera with a lens model) with the same scalar kernel as render's pixels; rgb gets the
    // composited colour of ray i at 3 i … 3 i + 2 (linear floats, not yet rounded to 8 bits).
    // InvalidInput when rgb.size() != 3 · rays.size(). Parallel over chunks of rays; bitwise
    // identical for any thread count.
    RayCastStats render_rays(std::span<const Ray> rays, std::span<float> rgb) const;
    // Prepares another volume (and tf) with the same options, as the constructor does, reusing
    // this caster's arrays: a volume of the same size and kind (the frames of a deformation)
    // allocates nothing, so the pages of the float copy are not faulted in again. InvalidInput
    // as in the constructor; after a throw the caster must not render until an update succeeds.
    // Not to be called during a render.
    void update(const volume::Volume& volume, const volume::TransferFunction* tf);
    // Changes the clipping plane of later renders (none: the whole volume) without preparing the
    // volume again; InvalidInput as in the constructor. Not to be called during a render.
    void set_clip(const std::optional<ClipPlane>& clip);

    double step() const { return m_step; }                  // world units
    double opacity_unit() const { return m_opacity_unit; }  // world units
    double prepare_ms() const { return m_prepare_ms; }      // time the constructor took
    std::int64_t num_cells() const;                         // macro cells
    std::int64_t num_occupied_cells() const;                // macro cells with some opacity

private:
    friend class MappedRayCaster;  // samples the source's prepared arrays (mapped_raycast.hpp)

    // The constructor's work: validation, then the float copy, lookup table, macro cells and
    // empty cubes.
    void prepare(const volume::Volume& volume, const volume::TransferFunction* tf);
    // The kernel's volume, table and option fields (everything but the camera's).
    void fill_kernel(detail::RayCastKernel& k) const;
    // A world vector in the grid's frame: Dᵀ v (v itself when the volume is axis-aligned).
    Vec3d grid_from_world(const Vec3d& v) const;

    RayCastOptions m_options;
    volume::Dims m_dims{0, 0, 0};
    Vec3d m_spacing, m_origin;
    // The volume's direction (volume/volume.hpp): rays, eyes and clip planes are taken into the
    // grid's frame by grid_from_world; the identity leaves them exactly as given.
    volume::Direction m_direction = volume::IDENTITY_DIRECTION;
    bool m_is_rgba = false;
    double m_step = 0.0;
    double m_opacity_unit = 0.0;
    double m_prepare_ms = 0.0;
    std::array<int, 3> m_cells{0, 0, 0};
    std::vector<float> m_values;           // scalar: lookup coordinate per voxel; RGBA: α·rgb, α
    std::vector<float> m_alpha;            // RGBA shaded: α per voxel (else empty)
    std::vector<float> m_lut;              // 4 per entry: r, g, b, α per step (scalar volumes)
    std::vector<float> m_lut_alpha;        // α per opacity unit, per entry (MIP)
    std::vector<std::uint8_t> m_occupied;  // per macro cell
    std::vector<std::uint8_t> m_empty_cube;    // 8 octants × macro cells: empty cube side, cells
    std::vector<std::uint8_t> m_sub_occupied;  // per macro cell: bit per occupied 2³ sub-cell
    std::vector<float> m_cell_max;  // per macro cell: largest value (scalar) or α (RGBA)
};

// One-off: RayCaster(volume, tf, options).render(camera, image); stats.ms includes the
// preparation.
RayCastStats raycast(const volume::Volume& volume, const volume::TransferFunction* tf,
                     const Camera& camera, const RayCastOptions& options, Image& image);

// The step a RayCaster uses for `options` (options.step, or half the smallest spacing).
double default_step(const volume::Volume& volume, const RayCastOptions& options);

enum class ViewAxis { pos_x, neg_x, pos_y, neg_y, pos_z, neg_z };

// "+x", "-x", "+y", "-y", "+z", "-z" (also "x" for "+x" …); InvalidInput listing them otherwise.
ViewAxis parse_view_axis(const char* text);

// An orthographic camera looking ALONG `axis` (forward = the axis direction; "+z" looks from
// below towards +z) at `box`, width × height pixels. Orientation (right, up) of the image:
//   +x: right −y, up +z        −x: right +y, up +z
//   +y: right +x, up +z        −y: right −x, up +z
//   +z: right −x, up +y        −z: right +x, up +y   (−z is the usual top view: x right, y up)
// The image height spans the box's extent along `up` and the width spans width/height times
// that; when width/height equals the box's aspect (extent along right / along up) the box fills
// the image exactly: pixel (i, j)'s centre sees the box at fraction (i + 0.5) / width along
// right and (j + 0.5) / height down from the top. Otherwise the box is fitted inside, centred,
// touching the image on the tighter side. The eye is on the box's near face's plane moved back
// by the box's extent along the axis (every ray enters the box at t > 0).
// Throws InvalidInput for an empty or non-finite box, or a size outside [1, 32768].
Camera view_camera(const AABBd& box, ViewAxis axis, int width, int height);

}  // namespace pliant::render
