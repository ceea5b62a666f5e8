// Resampling of a deformed tetrahedral mesh into a regular grid: parallel tet rasterization with
// source-coordinate interpolation (Park & Kye 2022, "revised" parallel resampling; issue 6).
//
//   const pbd::TetGrid grid = pbd::build_tet_grid(source);            // rest mesh over the volume
//   const volume::Resampler resampler(source, grid.mesh.tets, grid.mesh.positions);
//   volume::Volume target = volume::Volume::allocate(source.dims(), source.type(),
//                                                    source.spacing(), source.origin());
//   resampler.resample(deformed_positions, target);                   // every frame
//
// For each deformed tet (vertices a, b, c, d) the resampler visits the target voxel centres x
// inside it, computes barycentric coordinates relative to the reference vertex d,
//   x − d = T·λ,   T = [a − d, b − d, c − d]   (λ = T⁻¹(x − d), T⁻¹ precomputed per tet),
// interpolates the rest position r = r_d + [r_a − r_d, r_b − r_d, r_c − r_d]·λ, samples the source
// trilinearly at r and writes the voxel. Both steps are affine in x, so they are composed once per
// tet into one affine map from target voxel indices to source grid coordinates (algebraically
// the same λ interpolation, 3 multiply-adds per voxel instead of 18).
//
// Visiting (the "revised" method): for every layer k of the tet's box, the rows j its
// cross-section can reach (from the edges' crossings, slopes precomputed per tet); for every such
// row the x-interval of voxel centres inside the tet from the four face planes (each face bounds
// the row from below or above: root = β·(−1/a), routed to the lower or upper bound by min/max,
// no branch), and only the voxels of that interval are sampled; the bounding box is never tested
// voxel by voxel. Centres within 1e-6 voxel of a root are decided by the per-voxel tie rule
// itself, so the interval is exactly the set the brute force accepts. A face parallel to the rows
// (a = 0) accepts whole rows: it narrows the rows of a layer, or (b = 0 too) the tet's layers,
// exactly. With cells of a few voxels a row holds ~1.3 voxels, so the voxels of a slab's tets are
// collected, in order, into a batch of per-voxel source coordinates and target indices (rows
// written branch-free, 4 entries at a time) and sampled in one loop when it is full.
//
// SIMD: with AVX2 (chosen at run time, detail/resample_avx2.hpp) 4 tets are set up at once, the
// rows of a tet are spanned 4 at a time and f32 sources are sampled 4 voxels at a time; each lane
// does the scalar kernel's operations in the same order (no FMA), so the output is bitwise the
// same on every CPU.
//
// Tie rule (which tet owns a voxel centre on a shared face, edge or vertex): a face's plane
// function h(x) is computed from the face's three vertices sorted by vertex index, identically
// for the two tets that share it (up to an exact sign flip), so both tets see the same value.
// A voxel centre is inside a tet when, for each of its four faces, h > 0 on the tet's side, or
// h = 0 and the tet lies on the side the perturbation ε·(1, ε, ε²) (in voxel index space; ε → 0⁺)
// points to — i.e. the face's inward normal is lexicographically positive (first non-zero
// component of (n_x, n_y, n_z) > 0). This is the 3D top-left rule: it decides every point as if
// it were moved infinitesimally towards +x (then +y, then +z), so when the plane values are exact
// every voxel centre in the interior of a conforming mesh's union is written by exactly one tet,
// and a centre on the union's boundary by at most one. The values are exact when coordinates
// have few significant bits (identity and whole-voxel translations of a TetGrid on power-of-two
// spacings: the cases where centres land exactly on faces, edges and vertices). Otherwise the
// rule is still exact per face (a centre is never claimed by both or neither of two tets sharing
// a face), and only a centre within double rounding (~1e-16 relative) of an edge or vertex can be
// claimed by two tets or none.
//
// Determinism: the target is cut into slabs of whole z layers (16 at 256³: a tet straddling two
// slabs is set up in both); each tet is binned (count → prefix sum → fill, in tet order) into the
// slabs its box overlaps, and one task per slab zeroes the slab and rasterizes its tets in
// increasing index order, clipped to the slab. A voxel is written only
// by the task owning its slab, so there are no concurrent writes, and where tets overlap (folded
// or inverted deformations) the tet with the highest index wins. Results are bitwise identical for
// any number of threads and independent of the slab size.
//
// Sampling: trilinear at voxel centres (source grid coordinate g = (r − origin)/spacing − 0.5
// has voxel centres at integers); inside the source box [origin, origin + dims·spacing] but within
// half a voxel of a face the sample is clamped to the edge voxel; outside the box it is 0.
// RGBA sources interpolate opacity-weighted colour (Wittenbrink, Malzbender & Goss 1998): the
// sample's α is the trilinear α, its straight colour Σ w α c / Σ w α (0 where α = 0), so that a
// surface's colour is not darkened by the transparent voxels beside it and the ray caster, which
// interpolates premultiplied colour, sees the same colour in the resampled volume as in the
// source (detail::interpolate_corners).
//
// Skipping: the Resampler keeps only tets whose rest box, grown by the trilinear footprint, holds
// a visible source voxel (volume/visibility.hpp: value ≠ 0 for scalars, or opacity > 0 under
// options.tf; alpha > 0 for RGBA). Skipped tets' voxels stay 0, which is exactly what resampling
// them would give for scalar volumes without tf; otherwise they differ only in voxels that are
// invisible (opacity 0).
//
// Per frame, each kept tet's rest orientation and whether its samples stay inside the source
// are not recomputed: the constructor stores them (one byte per kept tet).
//
// Tets: degenerate deformed tets (zero or non-finite determinant, or a face with zero normal)
// cover no volume and are skipped (counted). Inverted tets (deformed orientation opposite to the
// rest orientation) are rasterized like any other — their region gets the mirrored rest content —
// unless options.skip_inverted (counted either way).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume {

struct ResampleOptions {
    // Visibility of a scalar source's voxels for skipping tets (as pbd::TetGridOptions::tf);
    // nullptr: value ≠ 0. Ignored for RGBA sources. Referenced, not copied.
    const TransferFunction* tf = nullptr;
    // Skip inverted tets instead of rasterizing them.
    bool skip_inverted = false;
};

struct ResampleStats {
    std::int64_t num_tets = 0;          // #T
    std::int64_t num_tets_skipped = 0;  // source region empty (decided per rest mesh)
    // Among the kept tets whose deformed box holds a target voxel centre (the others are never
    // set up): deformed tets of zero volume (skipped), and tets whose deformed orientation is
    // opposite to the rest one.
    std::int64_t num_degenerate = 0;
    std::int64_t num_inverted = 0;
    std::int64_t num_voxels_written = 0;  // voxel writes (each covered voxel once, for a
                                          // non-overlapping mesh)
};

// Target voxel types a source type can be resampled into:
//   source type itself (integer types: rounded to nearest, clamped to the type's range);
//   f32 from u8, i16, u16 (the values themselves, no rescaling);
//   rgba32f from rgba8 (channels / 255, the rgba8 convention round(255·c)).
bool can_resample_into(VoxelType source, VoxelType target);

// A rest mesh over a source volume, prepared for repeated resampling of its deformations.
// References source, tets, rest_positions and options.tf: they must outlive the Resampler and
// not change.
class Resampler {
public:
    // source: non-empty volume. tets: #T × 4 vertex indices in [0, #V) (positively oriented at
    // rest, as TetGrid's are). rest_positions: #V world points in the source's frame, finite.
    // InvalidInput otherwise (the message names the argument, the tet and the value).
    // Cost: one pass over the source (visibility) and one over the tets; parallel, deterministic.
    Resampler(const Volume& source, std::span<const geometry::Tet> tets,
              std::span<const Vec3f> rest_positions, const ResampleOptions& options = {});

    // Resamples the mesh deformed to deformed_positions (#V world points, finite) into target,
    // whose dims, spacing and origin define the output grid (any grid: usually the source's).
    // Every voxel of target is overwritten: voxels no kept tet covers become 0.
    // InvalidInput for a size mismatch, a non-finite position, an empty target or a target type
    // can_resample_into() refuses. Parallel; bitwise identical for any number of threads.
    ResampleStats resample(std::span<const Vec3f> deformed_positions, Volume& target) const;

    // For tests and diagnostics: counts[v] (saturating at 255) = how many kept tets claim the
    // centre of voxel v of a grid like `grid` (its dims, spacing, origin; its data is not used)
    // under the tie rule — the writes resample() would make. counts.size() == grid.num_voxels().
    void count_coverage(std::span<const Vec3f> deformed_positions, const Volume& grid,
                        std::span<std::uint8_t> counts) const;

    std::int64_t num_tets() const { return static_cast<std::int64_t>(m_tets.size()); }
    // Indices of the tets that are not skipped, increasing.
    std::span<const std::int32_t> kept_tets() const { return m_kept; }

private:
    const Volume* m_source;
    std::span<const geometry::Tet> m_tets;
    std::span<const Vec3f> m_rest;
    ResampleOptions m_options;
    std::vector<std::int32_t> m_kept;
    // Per kept tet: its rest orientation and whether its samples stay inside the source
    // (detail::RestInfo in one byte), computed once.
    std::vector<std::uint8_t> m_rest_codes;
};

// One-off: Resampler(source, tets, rest_positions, options).resample(deformed_positions, target).
ResampleStats resample(const Volume& source, std::span<const geometry::Tet> tets,
                       std::span<const Vec3f> rest_positions,
                       std::span<const Vec3f> deformed_positions, Volume& target,
                       const ResampleOptions& options = {});

}  // namespace pliant::volume
