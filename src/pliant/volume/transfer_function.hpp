// Transfer functions: classification of a scalar volume (value → colour and opacity) and the
// opacity correction that makes images independent of the ray caster's sampling step.
//
// Opacity is per unit distance. An opacity α (control points here, and the alpha channel of every
// RGBA volume) is the fraction of light a slab `unit` world units thick absorbs, where `unit` is
// the opacity unit: the transfer function's opacity_unit, or `--opacity-unit U` on the command
// line, by default the volume's smallest voxel spacing. A ray step of Δs world units uses
//   α_Δs = 1 − (1 − α)^(Δs / unit)                                    (corrected_opacity)
// so that two steps of Δs/2 absorb what one step of Δs does: 1 − (1 − α_{Δs/2})² = α_Δs
// (Engel et al., "Real-Time Volume Graphics", 2006, eq. 9.9; Max 1995).
//
// A TransferFunction is two piecewise-linear maps over the scalar value (in the volume's units:
// Hounsfield units for CT): colour control points (value, r, g, b) and opacity control points
// (value, α). Between two points the map interpolates linearly; below the first point it takes
// the first point's value, above the last the last's (clamped). Points with equal values make a
// step: a value exactly at them takes the last of them. Colours are straight (not premultiplied).
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "pliant/core/host_device.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume {

struct ColorPoint {
    double value = 0.0;
    std::array<float, 3> rgb{0.0f, 0.0f, 0.0f};  // each in [0, 1]
};

struct OpacityPoint {
    double value = 0.0;
    float alpha = 0.0f;  // in [0, 1], per opacity_unit world units
};

struct TransferFunction {
    std::string name;                   // for messages ("ct-bone", a file name, …)
    std::vector<ColorPoint> color;      // ≥ 1 point, sorted by value (non-decreasing)
    std::vector<OpacityPoint> opacity;  // ≥ 1 point, sorted by value (non-decreasing)
    // World units the opacities are given per (> 0), or 0: the smallest voxel spacing of the
    // volume it is applied to.
    double opacity_unit = 0.0;

    // InvalidInput naming the function and the point ("transfer function 'x': opacity[2]: …")
    // when a list is empty, a value is not finite or smaller than the previous point's, a colour
    // component or an opacity is outside [0, 1] (or NaN), or opacity_unit is not finite and ≥ 0.
    void validate() const;

    // (r, g, b, α) at `value`; α per opacity_unit. Assumes validate() passed. NaN → (0, 0, 0, 0).
    // O(log n) in the number of points. Thread-safe (const).
    std::array<float, 4> evaluate(double value) const;
};

// 1 − (1 − α)^(step / unit), computed as −expm1((step / unit) · log1p(−α)): exact 0 for α ≤ 0 or
// step ≤ 0, exact 1 for α ≥ 1 (step > 0), α for step == unit, accurate for tiny steps.
// step, unit in world units, unit > 0 (not checked: a per-sample kernel). Defined below.

// Preset names: "ct-bone", "ct-skin", "mri-brain", "grayscale".
const std::vector<std::string>& preset_names();

// A preset transfer function for `volume` (a scalar volume; its value range is used by the
// relative presets). Ranges:
//   ct-bone    Hounsfield units. Opacity 0 up to 150 HU, 0.05 at 250, 0.4 at 600, 0.8 at 1500;
//              colour from a reddish (0.8, 0.45, 0.3) at 150 HU through ivory (0.95, 0.88, 0.75)
//              at 500 to white at 1500. Cancellous bone starts around 200–300 HU, cortical bone
//              is 1000+ HU.
//   ct-skin    Hounsfield units. Opacity 0 below −600 HU, 0.2 at −400 … 0.2 at 150 (the
//              air/skin boundary and soft tissue, around −100 … 100 HU), 0.6 at 400, 0.9 at 1500
//              (bone); colour skin (0.9, 0.65, 0.55) to 150 HU, bone white (1, 0.97, 0.9) above
//              400.
//   mri-brain  relative to the volume's range [lo, hi] (MRI intensities have no absolute scale),
//              at fractions f of it: opacity 0 up to f = 0.15 (background, CSF), 0.05 at 0.3
//              (grey matter), 0.25 at 0.6 (white matter), 0.5 at 1; colour dark red-brown
//              (0.45, 0.2, 0.15) at 0.15, pink (0.9, 0.6, 0.55) at 0.45, near-white at 1.
//   grayscale  the volume's own lo..hi: colour black → white, opacity 0 → 1 linearly.
// lo, hi are the volume's smallest and largest value (NaN ignored; hi = lo + 1 when equal).
// opacity_unit is 0 (the volume's smallest spacing). InvalidInput for an unknown name (the
// message lists the valid ones) or an RGBA volume.
TransferFunction preset(std::string_view name, const Volume& volume);

// Smallest and largest value of a scalar volume (NaN ignored); {0, 0} when it has no finite
// value. InvalidInput for RGBA volumes. Parallel, deterministic.
std::array<double, 2> value_range(const Volume& volume);

// Classification: the rgba32f volume (same dims, spacing, origin) holding tf.evaluate(v) for each
// voxel value v of the scalar volume, its opacity converted from tf.opacity_unit to output_unit
// (α' = corrected_opacity(α, output_unit, tf_unit); unchanged when the units are equal).
// output_unit 0 means the volume's smallest spacing, the default unit of RGBA volumes.
// Validates tf; InvalidInput for an RGBA input volume or output_unit that is not finite and ≥ 0.
// Parallel over voxels, bitwise identical for any number of threads.
Volume apply(const Volume& scalar, const TransferFunction& tf, double output_unit = 0.0);

// The smallest of the volume's three spacings (the default opacity unit).
double smallest_spacing(const Volume& volume);

PLIANT_HOST_DEVICE inline double corrected_opacity(double alpha, double step, double unit) {
    if (!(alpha > 0.0) || !(step > 0.0)) {
        return 0.0;
    }
    if (alpha >= 1.0) {
        return 1.0;
    }
    if (step == unit) {
        return alpha;
    }
    // (1 − α)^r = exp(r · log1p(−α)); 1 − exp(x) = −expm1(x) keeps tiny results accurate.
    return -std::expm1((step / unit) * std::log1p(-alpha));
}

}  // namespace pliant::volume
