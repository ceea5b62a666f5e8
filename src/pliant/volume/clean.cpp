#include "pliant/volume/clean.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

void check_rgba(const Volume& volume, const char* function) {
    if (volume.type() != VoxelType::rgba8 && volume.type() != VoxelType::rgba32f) {
        throw InvalidInput(fmt::format("{}: volume must be rgba8 or rgba32f, got {}", function,
                                       name(volume.type())));
    }
}

void check_threshold(double threshold_255, const char* function) {
    if (!(threshold_255 >= 0.0 && threshold_255 <= 255.0)) {
        throw InvalidInput(
            fmt::format("{}: threshold must be in [0, 255] (alpha scale 0-255), got {}", function,
                        threshold_255));
    }
}

std::uint8_t to_u8(double alpha) {
    return static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(alpha, 0.0, 1.0)));
}

// Applies alpha' = f(alpha) to every voxel, alpha in [0, 1] (rgba8 a / 255).
template <typename F>
void map_alpha(Volume& volume, F&& f) {
    const std::int64_t n = volume.num_voxels();
    if (volume.type() == VoxelType::rgba8) {
        const auto v = volume.values<VoxelType::rgba8>();
        parallel_for(n, [&](std::int64_t i) {
            auto& a = v[static_cast<std::size_t>(4 * i + 3)];
            a = to_u8(f(static_cast<double>(a) / 255.0));
        });
    } else {
        const auto v = volume.values<VoxelType::rgba32f>();
        parallel_for(n, [&](std::int64_t i) {
            auto& a = v[static_cast<std::size_t>(4 * i + 3)];
            if (!std::isnan(a)) {
                a = static_cast<float>(f(static_cast<double>(a)));
            }
        });
    }
}

}  // namespace

std::int64_t threshold_alpha(Volume& volume, double threshold_255) {
    check_rgba(volume, "threshold_alpha");
    check_threshold(threshold_255, "threshold_alpha");
    const std::int64_t n = volume.num_voxels();
    const auto plus = [](std::int64_t a, std::int64_t b) {
        return a + b;
    };
    if (volume.type() == VoxelType::rgba8) {
        // Exact on bytes: 255 · (a / 255) < T  ⇔  a < T.
        const auto v = volume.values<VoxelType::rgba8>();
        return parallel_reduce(
            n, std::int64_t{0},
            [&](std::int64_t begin, std::int64_t end) {
                std::int64_t count = 0;
                for (std::int64_t i = begin; i < end; ++i) {
                    auto& a = v[static_cast<std::size_t>(4 * i + 3)];
                    if (static_cast<double>(a) < threshold_255 && a > 0) {
                        a = 0;
                        ++count;
                    }
                }
                return count;
            },
            plus);
    }
    const auto v = volume.values<VoxelType::rgba32f>();
    return parallel_reduce(
        n, std::int64_t{0},
        [&](std::int64_t begin, std::int64_t end) {
            std::int64_t count = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                auto& a = v[static_cast<std::size_t>(4 * i + 3)];
                if (255.0 * static_cast<double>(a) < threshold_255 && a != 0.0f) {
                    count += a > 0.0f ? 1 : 0;
                    a = 0.0f;
                }
            }
            return count;
        },
        plus);
}

double normalize_alpha(Volume& volume) {
    check_rgba(volume, "normalize_alpha");
    const std::int64_t n = volume.num_voxels();
    const auto larger = [](double a, double b) {
        return std::max(a, b);
    };
    double alpha_max = 0.0;
    if (volume.type() == VoxelType::rgba8) {
        const auto v = volume.values<VoxelType::rgba8>();
        alpha_max = parallel_reduce(
            n, 0.0,
            [&](std::int64_t begin, std::int64_t end) {
                int m = 0;
                for (std::int64_t i = begin; i < end; ++i) {
                    m = std::max(m, static_cast<int>(v[static_cast<std::size_t>(4 * i + 3)]));
                }
                return static_cast<double>(m) / 255.0;
            },
            larger);
    } else {
        const auto v = volume.values<VoxelType::rgba32f>();
        alpha_max = parallel_reduce(
            n, 0.0,
            [&](std::int64_t begin, std::int64_t end) {
                double m = 0.0;
                for (std::int64_t i = begin; i < end; ++i) {
                    const double a = v[static_cast<std::size_t>(4 * i + 3)];
                    if (a > m) {  // false for NaN
                        m = a;
                    }
                }
                return m;
            },
            larger);
    }
    if (alpha_max > 0.0) {
        map_alpha(volume, [alpha_max](double a) { return a / alpha_max; });
    }
    return alpha_max;
}

void normalize_alpha_range(Volume& volume, double threshold_255) {
    check_rgba(volume, "normalize_alpha_range");
    check_threshold(threshold_255, "normalize_alpha_range");
    const double t = threshold_255 / 255.0;
    if (t >= 1.0) {
        map_alpha(volume, [](double a) { return a >= 1.0 ? 1.0 : 0.0; });
        return;
    }
    map_alpha(volume, [t](double a) { return a >= t ? (a - t) / (1.0 - t) : 0.0; });
}

void clean(Volume& volume, const CleanOptions& options) {
    check_rgba(volume, "clean");
    check_threshold(options.threshold_255, "clean");
    if (options.threshold_255 > 0.0) {
        threshold_alpha(volume, options.threshold_255);
    }
    switch (options.normalization) {
        case AlphaNormalization::none:
            break;
        case AlphaNormalization::max:
            normalize_alpha(volume);
            break;
        case AlphaNormalization::threshold_range:
            normalize_alpha_range(volume, options.threshold_255);
            break;
    }
}

TransferFunction threshold_alpha(const TransferFunction& tf, double threshold_255) {
    check_threshold(threshold_255, "threshold_alpha");
    tf.validate();
    TransferFunction out = tf;
    if (threshold_255 == 0.0) {
        return out;
    }
    const auto below = [threshold_255](double alpha) {
        return 255.0 * alpha < threshold_255;
    };
    const double t = threshold_255 / 255.0;
    const std::vector<OpacityPoint>& in = tf.opacity;
    out.opacity.clear();
    for (std::size_t i = 0; i < in.size(); ++i) {
        const OpacityPoint& p = in[i];
        out.opacity.push_back({p.value, below(p.alpha) ? 0.0f : p.alpha});
        if (i + 1 == in.size() || !(in[i + 1].value > p.value)) {
            continue;  // the last point, or a step: nothing lies between the two points
        }
        const OpacityPoint& q = in[i + 1];
        const bool p_below = below(p.alpha);
        if (p_below == below(q.alpha)) {
            continue;  // the segment does not cross the threshold
        }
        // The crossing α = t, clamped into the segment against rounding.
        const double f = (t - static_cast<double>(p.alpha)) /
                         (static_cast<double>(q.alpha) - static_cast<double>(p.alpha));
        const double v = std::clamp(p.value + f * (q.value - p.value), p.value, q.value);
        const auto at = static_cast<float>(t);
        if (p_below) {  // rising: 0 up to the crossing, then the curve
            out.opacity.push_back({v, 0.0f});
            out.opacity.push_back({v, at});
        } else {  // falling: the curve down to the crossing, then 0
            out.opacity.push_back({v, at});
            out.opacity.push_back({v, 0.0f});
        }
    }
    return out;
}

}  // namespace pliant::volume
