// Transfer function JSON; the format is in docs/formats.md, the contract in the header.
#include "pliant/io/transfer_function_json.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/json_text.hpp"
#include "pliant/io/read_file.hpp"
#include "pliant/volume/visibility.hpp"

namespace pliant::io {
namespace {

using Json = nlohmann::json;

using io::json_type_name;

class Reader {
public:
    explicit Reader(std::string name) : m_name(std::move(name)) {}

    [[noreturn]] void fail(const std::string& where, const std::string& expected,
                           const std::string& got) const {
        throw IoError(fmt::format("{}: {}: expected {}, got {}", m_name, where, expected, got));
    }

    // Rejects keys outside `known` (the list is short: a linear scan).
    void check_keys(const Json& object, const std::string& where,
                    std::initializer_list<const char*> known) const {
        if (!object.is_object()) {
            fail(where, "an object", json_type_name(object));
        }
        for (const auto& [key, value] : object.items()) {
            bool ok = false;
            for (const char* k : known) {
                ok = ok || key == k;
            }
            if (!ok) {
                std::string list;
                for (const char* k : known) {
                    list += list.empty() ? fmt::format("\"{}\"", k) : fmt::format(", \"{}\"", k);
                }
                fail(where.empty() ? key : fmt::format("{}.{}", where, key),
                     fmt::format("one of the keys {}", list), "an unknown key");
            }
        }
    }

    const Json& required(const Json& object, const std::string& where, const char* key,
                         const char* what) const {
        const auto it = object.find(key);
        if (it == object.end()) {
            fail(path(where, key), fmt::format("a required {}", what), "nothing");
        }
        return *it;
    }

    double finite(const Json& value, const std::string& where) const {
        if (!value.is_number() || !std::isfinite(value.get<double>())) {
            fail(where, "a finite number", json_type_name(value));
        }
        return value.get<double>();
    }

    float unit(const Json& value, const std::string& where) const {
        const double x = finite(value, where);
        if (!(x >= 0.0 && x <= 1.0)) {
            fail(where, "a number in [0, 1]", fmt::format("{}", x));
        }
        return static_cast<float>(x);
    }

    const Json& points(const Json& root, const char* key) const {
        const Json& list = required(root, "", key, "array of control points");
        if (!list.is_array() || list.empty()) {
            fail(key, "a non-empty array of control points",
                 list.is_array() ? "an empty array" : json_type_name(list));
        }
        return list;
    }

    static std::string path(const std::string& where, const char* key) {
        return where.empty() ? std::string(key) : fmt::format("{}.{}", where, key);
    }

    const std::string& name() const { return m_name; }

private:
    std::string m_name;
};

}  // namespace

volume::TransferFunction parse_transfer_function(std::string_view text, std::string_view name) {
    const Reader r{std::string(name)};
    const Json root = parse_json(text, name);
    if (!root.is_object()) {
        r.fail("the transfer function", "a JSON object", json_type_name(root));
    }
    r.check_keys(root, "", {"name", "opacity_unit", "color", "opacity"});

    volume::TransferFunction tf;
    tf.name = std::string(name);
    if (const auto it = root.find("name"); it != root.end()) {
        if (!it->is_string()) {
            r.fail("name", "a string", json_type_name(*it));
        }
        tf.name = it->get<std::string>();
    }
    if (const auto it = root.find("opacity_unit"); it != root.end()) {
        tf.opacity_unit = r.finite(*it, "opacity_unit");
        if (!(tf.opacity_unit > 0.0)) {
            r.fail("opacity_unit",
                   "a number > 0 (world units; omit it for the smallest voxel spacing)",
                   fmt::format("{}", tf.opacity_unit));
        }
    }

    const Json& colors = r.points(root, "color");
    for (std::size_t k = 0; k < colors.size(); ++k) {
        const std::string where = fmt::format("color[{}]", k);
        r.check_keys(colors[k], where, {"value", "rgb"});
        volume::ColorPoint point;
        point.value = r.finite(r.required(colors[k], where, "value", "number"), where + ".value");
        const Json& rgb = r.required(colors[k], where, "rgb", "[r, g, b] array");
        if (!rgb.is_array() || rgb.size() != 3) {
            r.fail(where + ".rgb", "an array of 3 numbers in [0, 1]",
                   json_type_name(rgb) +
                       (rgb.is_array() ? fmt::format(" of {} elements", rgb.size()) : ""));
        }
        for (std::size_t c = 0; c < 3; ++c) {
            point.rgb[c] = r.unit(rgb[c], fmt::format("{}.rgb[{}]", where, c));
        }
        tf.color.push_back(point);
    }
    const Json& opacities = r.points(root, "opacity");
    for (std::size_t k = 0; k < opacities.size(); ++k) {
        const std::string where = fmt::format("opacity[{}]", k);
        r.check_keys(opacities[k], where, {"value", "alpha"});
        volume::OpacityPoint point;
        point.value =
            r.finite(r.required(opacities[k], where, "value", "number"), where + ".value");
        point.alpha = r.unit(r.required(opacities[k], where, "alpha", "number"), where + ".alpha");
        tf.opacity.push_back(point);
    }
    try {
        tf.validate();
    } catch (const InvalidInput& e) {
        throw IoError(fmt::format("{}: {}", name, e.what()));
    }
    return tf;
}

volume::TransferFunction read_transfer_function(const std::filesystem::path& path) {
    const std::string text = read_file(path);
    return parse_transfer_function(text, path.string());
}

volume::TransferFunction load_transfer_function(const std::string& name_or_file,
                                                const volume::Volume& volume) {
    const auto& presets = volume::preset_names();
    volume::TransferFunction tf =
        std::find(presets.begin(), presets.end(), name_or_file) != presets.end()
            ? volume::preset(name_or_file, volume)
            : read_transfer_function(name_or_file);
    // Legal but almost certainly not meant: a function that shows (almost) nothing of this volume
    // (a CT preset on an MRI, a file made for another value range).
    if (volume::channels(volume.type()) == 1 && volume.num_voxels() > 0) {
        const std::array<double, 2> range = volume::value_range(volume);
        // The CT presets are in Hounsfield units: a CT has air near −1000.
        if (name_or_file.starts_with("ct-") && range[0] > CT_AIR_ABOVE) {
            log_warning(
                "transfer function '{}' is for CT in Hounsfield units (air near -1000, bone above "
                "150), but this volume's values run from {:g} to {:g}: it is probably not such a "
                "CT (an MRI?) and the image may be nearly black; try mri-brain or grayscale",
                tf.name, range[0], range[1]);
            return tf;
        }
        const std::vector<std::uint8_t> visible = volume::visible_voxels(volume, &tf);
        const auto num_visible = std::count(visible.begin(), visible.end(), std::uint8_t{1});
        const double fraction =
            static_cast<double>(num_visible) / static_cast<double>(volume.num_voxels());
        if (fraction < NEARLY_INVISIBLE_FRACTION) {
            log_warning(
                "transfer function '{}' makes {:.3g} % of the volume's voxels visible (its values "
                "run from {:g} to {:g}): the image will be nearly empty; choose another transfer "
                "function (presets: {})",
                tf.name, 100.0 * fraction, range[0], range[1], fmt::join(presets, ", "));
        }
    }
    return tf;
}

}  // namespace pliant::io
