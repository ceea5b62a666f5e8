// Transfer function files (JSON) → volume::TransferFunction. The format is in docs/formats.md
// ("Transfer functions"):
//
//   {"name": "bone", "opacity_unit": 1.0,
//    "color":   [{"value": 150, "rgb": [0.8, 0.45, 0.3]}, {"value": 1500, "rgb": [1, 1, 1]}],
//    "opacity": [{"value": 150, "alpha": 0}, {"value": 1500, "alpha": 0.8}]}
//
//   const volume::TransferFunction tf = io::read_transfer_function("bone.json");
//
// Strict: text that is not JSON, an unknown key, a missing required key ("color", "opacity",
// "value", "rgb", "alpha") or a value of the wrong type or range throws IoError
// "<name>: <key path>: expected <x>, got <y>" (key paths like `opacity[2].alpha`); points out of
// order are reported by TransferFunction::validate's rules, also as IoError starting with <name>.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::io {

volume::TransferFunction read_transfer_function(const std::filesystem::path& path);

// `name_or_file`: a preset (volume::preset_names) computed for `volume`, else a transfer
// function JSON file (read_transfer_function; IoError when missing or broken). Logs a warning
// (core/log.hpp) when the choice is legal but almost certainly not meant: a CT preset ("ct-…",
// Hounsfield units) on a volume whose smallest value is above CT_AIR_ABOVE (no air: an MRI or an
// unscaled image, which the preset shows nearly black), or a function that makes fewer than
// NEARLY_INVISIBLE_FRACTION of a scalar volume's voxels visible (a nearly empty image).
inline constexpr double CT_AIR_ABOVE = -200.0;
inline constexpr double NEARLY_INVISIBLE_FRACTION = 1e-4;
volume::TransferFunction load_transfer_function(const std::string& name_or_file,
                                                const volume::Volume& volume);

// The same from JSON text; `name` (the file name) starts error messages and is the function's
// name unless the JSON has one.
volume::TransferFunction parse_transfer_function(std::string_view text, std::string_view name);

}  // namespace pliant::io
