#include "pliant/volume/transfer_function.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

bool in_unit(float x) {
    return x >= 0.0f && x <= 1.0f;
}

// Index of the first point whose value is > v (points sorted): the interval is [i − 1, i].
template <typename Point>
std::size_t upper(const std::vector<Point>& points, double v) {
    return static_cast<std::size_t>(
        std::upper_bound(points.begin(), points.end(), v,
                         [](double x, const Point& p) { return x < p.value; }) -
        points.begin());
}

template <typename Point, typename Get>
float interpolate(const std::vector<Point>& points, double v, Get&& get) {
    const std::size_t i = upper(points, v);
    if (i == 0) {
        return get(points.front());
    }
    if (i == points.size()) {
        return get(points.back());
    }
    const Point& p0 = points[i - 1];
    const Point& p1 = points[i];
    // p0.value ≤ v < p1.value, so the interval is not empty.
    const double t = (v - p0.value) / (p1.value - p0.value);
    const double a = get(p0);
    const double b = get(p1);
    return static_cast<float>(a + t * (b - a));
}

template <VoxelType T>
void classify(const Volume& scalar, const TransferFunction& tf, double tf_unit, double out_unit,
              std::span<float> out) {
    const auto in = scalar.values<T>();
    const bool convert = tf_unit != out_unit;
    parallel_for(scalar.num_voxels(), [&](std::int64_t i) {
        std::array<float, 4> rgba =
            tf.evaluate(static_cast<double>(in[static_cast<std::size_t>(i)]));
        if (convert) {
            rgba[3] = static_cast<float>(corrected_opacity(rgba[3], out_unit, tf_unit));
        }
        const auto base = static_cast<std::size_t>(4 * i);
        for (std::size_t c = 0; c < 4; ++c) {
            out[base + c] = rgba[c];
        }
    });
}

template <VoxelType T>
std::array<double, 2> range_of(const Volume& volume) {
    const auto v = volume.values<T>();
    constexpr double INF = std::numeric_limits<double>::infinity();
    const auto r = parallel_reduce(
        volume.num_voxels(), std::array<double, 2>{INF, -INF},
        [&](std::int64_t begin, std::int64_t end) {
            std::array<double, 2> m{INF, -INF};
            for (std::int64_t i = begin; i < end; ++i) {
                const auto x = static_cast<double>(v[static_cast<std::size_t>(i)]);
                if (std::isfinite(x)) {
                    m[0] = std::min(m[0], x);
                    m[1] = std::max(m[1], x);
                }
            }
            return m;
        },
        [](std::array<double, 2> a, const std::array<double, 2>& b) {
            return std::array<double, 2>{std::min(a[0], b[0]), std::max(a[1], b[1])};
        });
    return r[0] <= r[1] ? r : std::array<double, 2>{0.0, 0.0};
}

void check_scalar(const Volume& volume, const char* function) {
    if (channels(volume.type()) != 1) {
        throw InvalidInput(fmt::format("{}: volume must be scalar (u8, i16, u16, f32), got {}",
                                       function, name(volume.type())));
    }
}

// Colour and opacity points at fractions f of [lo, hi].
TransferFunction relative(std::string name, double lo, double hi,
                          const std::vector<std::pair<double, std::array<float, 3>>>& colors,
                          const std::vector<std::pair<double, float>>& opacities) {
    TransferFunction tf;
    tf.name = std::move(name);
    for (const auto& [f, rgb] : colors) {
        tf.color.push_back({lo + f * (hi - lo), rgb});
    }
    for (const auto& [f, alpha] : opacities) {
        tf.opacity.push_back({lo + f * (hi - lo), alpha});
    }
    return tf;
}

}  // namespace

void TransferFunction::validate() const {
    const std::string who = fmt::format("transfer function '{}'", name);
    if (color.empty()) {
        throw InvalidInput(fmt::format("{}: color: needs at least one control point", who));
    }
    if (opacity.empty()) {
        throw InvalidInput(fmt::format("{}: opacity: needs at least one control point", who));
    }
    const auto check_value = [&](const char* list, std::size_t k, double value, double previous) {
        if (!std::isfinite(value)) {
            throw InvalidInput(
                fmt::format("{}: {}[{}]: value must be finite, got {}", who, list, k, value));
        }
        if (k > 0 && value < previous) {
            throw InvalidInput(fmt::format(
                "{}: {}[{}]: value {} is less than the previous point's {} (points must be "
                "sorted by value)",
                who, list, k, value, previous));
        }
    };
    for (std::size_t k = 0; k < color.size(); ++k) {
        check_value("color", k, color[k].value, k > 0 ? color[k - 1].value : 0.0);
        for (std::size_t c = 0; c < 3; ++c) {
            if (!in_unit(color[k].rgb[c])) {
                throw InvalidInput(fmt::format("{}: color[{}]: rgb[{}] must be in [0, 1], got {}",
                                               who, k, c, color[k].rgb[c]));
            }
        }
    }
    for (std::size_t k = 0; k < opacity.size(); ++k) {
        check_value("opacity", k, opacity[k].value, k > 0 ? opacity[k - 1].value : 0.0);
        if (!in_unit(opacity[k].alpha)) {
            throw InvalidInput(fmt::format("{}: opacity[{}]: alpha must be in [0, 1], got {}", who,
                                           k, opacity[k].alpha));
        }
    }
    if (!std::isfinite(opacity_unit) || opacity_unit < 0.0) {
        throw InvalidInput(fmt::format(
            "{}: opacity_unit must be finite and > 0 (or 0: the smallest voxel spacing), got {}",
            who, opacity_unit));
    }
}

std::array<float, 4> TransferFunction::evaluate(double value) const {
    if (std::isnan(value)) {
        return {0.0f, 0.0f, 0.0f, 0.0f};
    }
    return {interpolate(color, value, [](const ColorPoint& p) { return p.rgb[0]; }),
            interpolate(color, value, [](const ColorPoint& p) { return p.rgb[1]; }),
            interpolate(color, value, [](const ColorPoint& p) { return p.rgb[2]; }),
            interpolate(opacity, value, [](const OpacityPoint& p) { return p.alpha; })};
}

double smallest_spacing(const Volume& volume) {
    const Vec3d& s = volume.spacing();
    return std::min({s.x, s.y, s.z});
}

std::array<double, 2> value_range(const Volume& volume) {
    switch (volume.type()) {
        case VoxelType::u8:
            return range_of<VoxelType::u8>(volume);
        case VoxelType::i16:
            return range_of<VoxelType::i16>(volume);
        case VoxelType::u16:
            return range_of<VoxelType::u16>(volume);
        case VoxelType::f32:
            return range_of<VoxelType::f32>(volume);
        default:
            check_scalar(volume, "value_range");
    }
    return {0.0, 0.0};
}

const std::vector<std::string>& preset_names() {
    static const std::vector<std::string> NAMES{"ct-bone", "ct-skin", "mri-brain", "grayscale"};
    return NAMES;
}

TransferFunction preset(std::string_view name, const Volume& volume) {
    check_scalar(volume, "preset");
    TransferFunction tf;
    if (name == "ct-bone") {
        tf.name = "ct-bone";
        tf.color = {{150.0, {0.8f, 0.45f, 0.3f}},
                    {500.0, {0.95f, 0.88f, 0.75f}},
                    {1500.0, {1.0f, 1.0f, 1.0f}}};
        tf.opacity = {{150.0, 0.0f}, {250.0, 0.05f}, {600.0, 0.4f}, {1500.0, 0.8f}};
        return tf;
    }
    if (name == "ct-skin") {
        tf.name = "ct-skin";
        tf.color = {{-600.0, {0.9f, 0.65f, 0.55f}},
                    {150.0, {0.9f, 0.65f, 0.55f}},
                    {400.0, {1.0f, 0.97f, 0.9f}}};
        tf.opacity = {{-600.0, 0.0f}, {-400.0, 0.2f}, {150.0, 0.2f}, {400.0, 0.6f}, {1500.0, 0.9f}};
        return tf;
    }
    auto [lo, hi] = value_range(volume);
    if (!(hi > lo)) {
        hi = lo + 1.0;
    }
    if (name == "mri-brain") {
        return relative("mri-brain", lo, hi,
                        {{0.15, {0.45f, 0.2f, 0.15f}},
                         {0.45, {0.9f, 0.6f, 0.55f}},
                         {1.0, {1.0f, 0.95f, 0.92f}}},
                        {{0.15, 0.0f}, {0.3, 0.05f}, {0.6, 0.25f}, {1.0, 0.5f}});
    }
    if (name == "grayscale") {
        return relative("grayscale", lo, hi, {{0.0, {0.0f, 0.0f, 0.0f}}, {1.0, {1.0f, 1.0f, 1.0f}}},
                        {{0.0, 0.0f}, {1.0, 1.0f}});
    }
    throw InvalidInput(fmt::format("transfer function preset: unknown name '{}' (valid: {})", name,
                                   fmt::join(preset_names(), ", ")));
}

Volume apply(const Volume& scalar, const TransferFunction& tf, double output_unit) {
    check_scalar(scalar, "apply");
    tf.validate();
    if (!std::isfinite(output_unit) || output_unit < 0.0) {
        throw InvalidInput(fmt::format(
            "apply: output_unit must be finite and > 0 (or 0: the smallest voxel spacing), got {}",
            output_unit));
    }
    const double default_unit = smallest_spacing(scalar);
    const double tf_unit = tf.opacity_unit > 0.0 ? tf.opacity_unit : default_unit;
    const double out_unit = output_unit > 0.0 ? output_unit : default_unit;
    Volume rgba =
        Volume::allocate(scalar.dims(), VoxelType::rgba32f, scalar.spacing(), scalar.origin());
    const auto out = rgba.values<VoxelType::rgba32f>();
    switch (scalar.type()) {
        case VoxelType::u8:
            classify<VoxelType::u8>(scalar, tf, tf_unit, out_unit, out);
            break;
        case VoxelType::i16:
            classify<VoxelType::i16>(scalar, tf, tf_unit, out_unit, out);
            break;
        case VoxelType::u16:
            classify<VoxelType::u16>(scalar, tf, tf_unit, out_unit, out);
            break;
        default:
            classify<VoxelType::f32>(scalar, tf, tf_unit, out_unit, out);
            break;
    }
    return rgba;
}

}  // namespace pliant::volume
