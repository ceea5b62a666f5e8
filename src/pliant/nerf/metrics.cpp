#include "pliant/nerf/metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::nerf {

double psnr(std::span<const float> a, std::span<const float> b) {
    if (a.size() != b.size() || a.empty()) {
        throw InvalidInput(fmt::format("nerf::psnr: image sizes {} and {} must be equal and > 0",
                                       a.size(), b.size()));
    }
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double d = static_cast<double>(a[i]) - b[i];
        sum += d * d;
    }
    const double mse = sum / static_cast<double>(a.size());
    return mse > 0.0 ? -10.0 * std::log10(mse) : std::numeric_limits<double>::infinity();
}

namespace {

// Separable "valid" filtering of one channel plane with a window of size wx × wy (1D kernels kx,
// ky): out has (width − wx + 1) × (height − wy + 1) values.
std::vector<double> filter_valid(const std::vector<double>& in, int width, int height,
                                 const std::vector<double>& kx, const std::vector<double>& ky) {
    const int wx = static_cast<int>(kx.size()), wy = static_cast<int>(ky.size());
    const int ow = width - wx + 1, oh = height - wy + 1;
    std::vector<double> rows(static_cast<std::size_t>(ow) * height);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < ow; ++x) {
            double s = 0.0;
            for (int k = 0; k < wx; ++k) {
                s += kx[k] * in[static_cast<std::size_t>(y) * width + x + k];
            }
            rows[static_cast<std::size_t>(y) * ow + x] = s;
        }
    }
    std::vector<double> out(static_cast<std::size_t>(ow) * oh);
    for (int y = 0; y < oh; ++y) {
        for (int x = 0; x < ow; ++x) {
            double s = 0.0;
            for (int k = 0; k < wy; ++k) {
                s += ky[k] * rows[static_cast<std::size_t>(y + k) * ow + x];
            }
            out[static_cast<std::size_t>(y) * ow + x] = s;
        }
    }
    return out;
}

std::vector<double> gaussian(int size, double sigma) {
    std::vector<double> k(static_cast<std::size_t>(size));
    double sum = 0.0;
    const double centre = 0.5 * (size - 1);
    for (int i = 0; i < size; ++i) {
        k[i] = std::exp(-0.5 * (i - centre) * (i - centre) / (sigma * sigma));
        sum += k[i];
    }
    for (double& v : k) {
        v /= sum;
    }
    return k;
}

}  // namespace

double ssim(std::span<const float> a, std::span<const float> b, int width, int height) {
    const std::size_t n = 3 * static_cast<std::size_t>(std::max(width, 0)) * std::max(height, 0);
    if (width < 1 || height < 1 || a.size() != n || b.size() != n) {
        throw InvalidInput(fmt::format(
            "nerf::ssim: {} x {} image, sizes {} and {}, expected 3 x width x height = {}", width,
            height, a.size(), b.size(), n));
    }
    const std::vector<double> kx = gaussian(std::min(11, width), 1.5);
    const std::vector<double> ky = gaussian(std::min(11, height), 1.5);
    constexpr double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
    double total = 0.0;
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    std::vector<double> x(pixels), y(pixels), xx(pixels), yy(pixels), xy(pixels);
    for (int c = 0; c < 3; ++c) {
        for (std::size_t p = 0; p < pixels; ++p) {
            x[p] = a[3 * p + c];
            y[p] = b[3 * p + c];
            xx[p] = x[p] * x[p];
            yy[p] = y[p] * y[p];
            xy[p] = x[p] * y[p];
        }
        const auto mx = filter_valid(x, width, height, kx, ky);
        const auto my = filter_valid(y, width, height, kx, ky);
        const auto sxx = filter_valid(xx, width, height, kx, ky);
        const auto syy = filter_valid(yy, width, height, kx, ky);
        const auto sxy = filter_valid(xy, width, height, kx, ky);
        double sum = 0.0;
        for (std::size_t p = 0; p < mx.size(); ++p) {
            const double vx = sxx[p] - mx[p] * mx[p];
            const double vy = syy[p] - my[p] * my[p];
            const double cov = sxy[p] - mx[p] * my[p];
            sum += ((2 * mx[p] * my[p] + C1) * (2 * cov + C2)) /
                   ((mx[p] * mx[p] + my[p] * my[p] + C1) * (vx + vy + C2));
        }
        total += sum / static_cast<double>(mx.size());
    }
    return total / 3.0;
}

}  // namespace pliant::nerf
