// Image quality metrics for held-out views: PSNR and SSIM on RGB float images in [0, 1]
// (3 · width · height, row-major, interleaved).
//
//   PSNR = 10 log10(1 / MSE), MSE over all pixels and channels (peak 1). Identical images: +inf.
//   SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, eq. 13): per channel, local means, variances and
//     covariance under an 11 × 11 Gaussian window (σ 1.5, normalized), C1 = (0.01)², C2 =
//     (0.03)² (dynamic range 1), over the "valid" window positions only (the window entirely
//     inside the image, as the paper's reference code and the NeRF evaluations do); the mean
//     over positions, then over the three channels. Images smaller than 11 pixels on a side use
//     a window clipped to the image (one position). Separable filtering, O(pixels · 22).
#pragma once

#include <span>

namespace pliant::nerf {

// InvalidInput when the sizes disagree with 3 · width · height.
double psnr(std::span<const float> a, std::span<const float> b);
double ssim(std::span<const float> a, std::span<const float> b, int width, int height);

}  // namespace pliant::nerf
