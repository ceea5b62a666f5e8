// Cleaning RGBA volumes (rgba8 or rgba32f, straight colour, opacity α in [0, 1] per opacity
// unit): removing the faint, cloudy "floaters" a radiance field leaves in empty space, then
// restoring the range of the opacities that remain. The pipeline of the deformable-NeRF paper
// (Park & Kye) thresholds at T = 5, 20 or 35 on a 0–255 alpha scale and then normalizes alpha.
// The paper names the two steps without formulas we could consult; the formulas below are
// pliant's definitions, chosen to be simple, exact on rgba8 and idempotent:
//
//   threshold T (0 ≤ T ≤ 255):   α' = 0 where 255 · α < T, else α' = α
//     (rgba8 stores a = 255 α, so the test is a < T exactly; colour channels are kept.)
//     T = 0 is the identity.
//
//   alpha normalization, AlphaNormalization::max (the default):
//     α' = α / α_max,  α_max = the largest α in the volume,
//     so the most opaque voxel becomes 1 and ratios between opacities are kept. A volume whose
//     α_max is 0 (all transparent) is left unchanged.
//   AlphaNormalization::threshold_range (the alternative, after a threshold T > 0):
//     α' = (α − t) / (1 − t) for α ≥ t,  t = T / 255,  (0 below t),
//     which maps [t, 1] onto [0, 1] and so removes the jump the hard threshold leaves at t.
//
// rgba8 results are round(255 α') (ties away from zero), computed in double. Both functions run
// in parallel over voxels; results are bitwise identical for any number of threads. They modify
// the volume in place and throw InvalidInput for a scalar volume or a T outside [0, 255] (the
// message names the argument and the value). NaN opacities (rgba32f) are left as they are.
#pragma once

#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::volume {

enum class AlphaNormalization { none, max, threshold_range };

// α' = 0 where 255 α < threshold_255. Returns the number of voxels whose opacity was zeroed
// (voxels that had α > 0 and fell under the threshold).
std::int64_t threshold_alpha(Volume& volume, double threshold_255);

// α' = α / α_max (see above). Returns α_max before normalization (0 for an all-transparent
// volume, which is left unchanged).
double normalize_alpha(Volume& volume);

// α' = (α − t)/(1 − t) for α ≥ t = threshold_255/255, else 0. threshold_255 = 255 sets every
// opacity below 1 to 0 and keeps 1.
void normalize_alpha_range(Volume& volume, double threshold_255);

struct CleanOptions {
    double threshold_255 = 0.0;  // T on the 0–255 alpha scale; 0 = no threshold
    AlphaNormalization normalization = AlphaNormalization::max;
};

// Threshold, then the chosen normalization.
void clean(Volume& volume, const CleanOptions& options);

// The same threshold on a scalar volume's classification, for volumes that are shown through a
// transfer function rather than stored as RGBA: the transfer function whose opacity is
//   α'(v) = 0 where 255 · α(v) < threshold_255, else α(v),
// colours unchanged. Exact as a piecewise-linear function: where the opacity curve crosses
// t = threshold_255 / 255 inside a segment, a step point pair is inserted at the crossing
// (value rounded to double; at the crossing value of a falling segment itself α' is 0 rather
// than t, as a step takes the last of its points). threshold_255 = 0 returns tf unchanged.
// Validates tf; InvalidInput for a T outside [0, 255].
TransferFunction threshold_alpha(const TransferFunction& tf, double threshold_255);

}  // namespace pliant::volume
