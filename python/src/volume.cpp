// Volumes: volume::Volume as numpy arrays, files (io::read_volume / write_volume), generated
// phantoms, cleaning, transfer functions.
//
// Array convention: a volume of dims (nx, ny, nz) is the C-contiguous array of shape
// (nz, ny, nx) for scalar types and (nz, ny, nx, 4) for RGBA, so that array[k, j, i] is voxel
// (i, j, k) (x fastest in memory, as the library, NRRD and NIfTI store it). No copy either way
// out; Volume.from_array copies in.
#include "pliant/volume/volume.hpp"

#include <fmt/format.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "common.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/transfer_function_json.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/volume/clean.hpp"
#include "pliant/volume/generate.hpp"
#include "pliant/volume/reorient.hpp"
#include "pliant/volume/transfer_function.hpp"

namespace pliant::python {
namespace {

using volume::Volume;
using volume::VoxelType;

constexpr std::array<VoxelType, 6> ALL_TYPES{VoxelType::u8,  VoxelType::i16,   VoxelType::u16,
                                             VoxelType::f32, VoxelType::rgba8, VoxelType::rgba32f};

VoxelType parse_type(const std::string& text) {
    for (const VoxelType type : ALL_TYPES) {
        if (volume::name(type) == text) {
            return type;
        }
    }
    throw InvalidInput(
        fmt::format("voxel type '{}': expected one of u8, i16, u16, f32, rgba8, rgba32f", text));
}

// The numpy dtype of one channel.
py::dtype channel_dtype(VoxelType type) {
    switch (type) {
        case VoxelType::u8:
        case VoxelType::rgba8:
            return py::dtype::of<std::uint8_t>();
        case VoxelType::i16:
            return py::dtype::of<std::int16_t>();
        case VoxelType::u16:
            return py::dtype::of<std::uint16_t>();
        case VoxelType::f32:
        case VoxelType::rgba32f:
            return py::dtype::of<float>();
    }
    return py::dtype::of<float>();
}

py::array volume_view(const py::object& self) {
    auto& v = self.cast<Volume&>();
    const auto& d = v.dims();
    const auto c = static_cast<py::ssize_t>(volume::channels(v.type()));
    const auto b = static_cast<py::ssize_t>(volume::bytes_per_channel(v.type()));
    std::vector<py::ssize_t> shape{d[2], d[1], d[0]};
    std::vector<py::ssize_t> strides{d[1] * d[0] * c * b, d[0] * c * b, c * b};
    if (c == 4) {
        shape.push_back(4);
        strides.push_back(b);
    }
    return py::array(channel_dtype(v.type()), shape, strides,
                     v.empty() ? nullptr : v.bytes().data(), self);
}

// A volume holding a copy of `array`: (nz, ny, nx) scalars or (nz, ny, nx, 4) RGBA.
Volume volume_from_array(const py::array& input, const Vec3d& spacing, const Vec3d& origin) {
    const auto array = py::array::ensure(input, py::array::c_style);
    if (!array) {
        throw InvalidInput("Volume.from_array: array: expected a numpy array");
    }
    const bool rgba = array.ndim() == 4 && array.shape(3) == 4;
    if (array.ndim() != 3 && !rgba) {
        throw InvalidInput(fmt::format(
            "Volume.from_array: array: expected shape (nz, ny, nx) or (nz, ny, nx, 4), got {} "
            "dimensions",
            array.ndim()));
    }
    const py::dtype dtype = array.dtype();
    std::optional<VoxelType> type;
    if (dtype.is(py::dtype::of<std::uint8_t>())) {
        type = rgba ? VoxelType::rgba8 : VoxelType::u8;
    } else if (dtype.is(py::dtype::of<float>())) {
        type = rgba ? VoxelType::rgba32f : VoxelType::f32;
    } else if (!rgba && dtype.is(py::dtype::of<std::int16_t>())) {
        type = VoxelType::i16;
    } else if (!rgba && dtype.is(py::dtype::of<std::uint16_t>())) {
        type = VoxelType::u16;
    }
    if (!type) {
        throw InvalidInput(fmt::format(
            "Volume.from_array: array: dtype {} is not a voxel type; expected uint8, int16, "
            "uint16 or float32 for (nz, ny, nx), uint8 or float32 for (nz, ny, nx, 4)",
            py::str(py::handle(dtype)).cast<std::string>()));
    }
    Volume v =
        Volume::allocate({array.shape(2), array.shape(1), array.shape(0)}, *type, spacing, origin);
    std::memcpy(v.bytes().data(), array.data(), v.size_bytes());
    return v;
}

}  // namespace

void bind_volume(py::module_& m) {
    py::class_<Volume>(m, "Volume", R"doc(
A regular grid of voxels placed in the world (volume::Volume), owning its data.

dims: (nx, ny, nz). type: 'u8', 'i16', 'u16', 'f32' (scalars) or 'rgba8', 'rgba32f' (straight
colour and opacity per opacity unit). Voxel (i, j, k) is centred at origin + D (i + 0.5) spacing,
D the direction (the identity unless the grid is oblique; see `direction`).
array: the voxels as a writeable numpy view of the volume's memory (no copy), shape (nz, ny, nx)
for scalars and (nz, ny, nx, 4) for RGBA, so array[k, j, i] is voxel (i, j, k).
)doc")
        .def_static(
            "zeros",
            [](const volume::Dims& dims, const std::string& type, const Vec3d& spacing,
               const Vec3d& origin) {
                return Volume::allocate(dims, parse_type(type), spacing, origin);
            },
            py::arg("dims"), py::arg("type") = "f32", py::arg("spacing") = Vec3d{1, 1, 1},
            py::arg("origin") = Vec3d{0, 0, 0}, "A zero-filled volume of dims (nx, ny, nz).")
        .def_static("from_array", &volume_from_array, py::arg("array"),
                    py::arg("spacing") = Vec3d{1, 1, 1}, py::arg("origin") = Vec3d{0, 0, 0},
                    "A volume holding a copy of `array`: (nz, ny, nx) of uint8, int16, uint16 or "
                    "float32, or (nz, ny, nx, 4) RGBA of uint8 or float32.")
        .def_property_readonly("array", &volume_view,
                               "Writeable view of the voxels: (nz, ny, nx) or (nz, ny, nx, 4).")
        .def_property_readonly(
            "dims",
            [](const Volume& v) { return py::make_tuple(v.dims()[0], v.dims()[1], v.dims()[2]); },
            "(nx, ny, nz)")
        .def_property_readonly("type",
                               [](const Volume& v) { return std::string(volume::name(v.type())); })
        .def_property("spacing", &Volume::spacing, &Volume::set_spacing, "world units per voxel")
        .def_property("origin", &Volume::origin, &Volume::set_origin,
                      "the corner of the voxel box (world units)")
        .def_property_readonly("bounds", &Volume::bounds,
                               "((xmin, ymin, zmin), (xmax, ymax, zmax)): the box the voxels cover "
                               "(for an oblique volume: in the grid's own frame)")
        .def_property(
            "direction",
            [](const Volume& v) {
                const volume::Direction& d = v.direction();
                return py::make_tuple(d[0], d[1], d[2]);
            },
            [](Volume& v, const volume::Direction& d) { v.set_direction(d); },
            "The world directions of the i, j and k axes: three unit, orthogonal vectors (the "
            "columns of the rotation world_from_grid), the identity for an axis-aligned volume. "
            "The ray caster renders an oblique volume as it lies in world space.")
        .def_property_readonly("is_axis_aligned", &Volume::is_axis_aligned,
                               "True when the direction is exactly the identity")
        .def_property_readonly("world_bounds", &Volume::world_bounds,
                               "The smallest world box holding the (possibly turned) voxel box: "
                               "what cameras frame")
        .def_property_readonly("num_voxels", &Volume::num_voxels)
        .def_property_readonly("size_bytes", &Volume::size_bytes)
        .def("voxel_center", &Volume::voxel_center, py::arg("i"), py::arg("j"), py::arg("k"))
        .def(
            "copy", [](const Volume& v) { return v; }, "A deep copy.")
        .def("__repr__", [](const Volume& v) {
            return fmt::format("pliant.Volume({}x{}x{} {}, spacing ({}, {}, {}))", v.dims()[0],
                               v.dims()[1], v.dims()[2], volume::name(v.type()), v.spacing().x,
                               v.spacing().y, v.spacing().z);
        });

    m.def(
        "read_volume",
        [](const std::filesystem::path& path, std::size_t max_bytes,
           const std::string& orientation) {
            if (orientation != "axis_aligned" && orientation != "keep") {
                throw InvalidInput(fmt::format(
                    "read_volume: orientation '{}': expected 'axis_aligned' or 'keep'",
                    orientation));
            }
            return io::read_volume(
                path, {.max_bytes = max_bytes,
                       .orientation = orientation == "keep" ? io::Orientation::keep
                                                            : io::Orientation::axis_aligned});
        },
        py::arg("path"), py::arg("max_bytes") = Volume::MAX_BYTES,
        py::arg("orientation") = "axis_aligned", py::call_guard<py::gil_scoped_release>(),
        "Reads .nrrd, .nhdr, .nii, .nii.gz, .hdr, .mha, .mhd, .vdb, .json/.raw, .inv3 or DICOM by "
        "extension. An oblique grid: orientation 'axis_aligned' resamples it onto an "
        "axis-aligned grid (trilinear), 'keep' keeps its direction (the ray caster renders it as "
        "it lies). IoError for broken files, Unsupported for features pliant does not read.");
    m.def(
        "resample_to_axis_aligned",
        [](const Volume& v, const Vec3d& spacing, double outside) {
            return volume::resample_to_axis_aligned(
                v, {.spacing = spacing, .outside = outside});
        },
        py::arg("volume"), py::arg("spacing") = Vec3d{0, 0, 0}, py::arg("outside") = 0.0,
        py::call_guard<py::gil_scoped_release>(),
        "An axis-aligned volume covering an oblique one (volume::resample_to_axis_aligned: "
        "trilinear; spacing (0, 0, 0): the smallest spacing on every axis; `outside`: the value "
        "beyond the oblique box).");
    m.def(
        "write_volume",
        [](const std::filesystem::path& path, const Volume& v, bool gzip) {
            io::write_volume(path, v, {.gzip = gzip});
        },
        py::arg("path"), py::arg("volume"), py::arg("gzip") = false,
        py::call_guard<py::gil_scoped_release>(),
        "Writes .nrrd, .nhdr, .nii, .nii.gz or .json/.raw by extension, atomically.");

    m.def(
        "shepp_logan",
        [](const volume::Dims& dims, const std::string& variant) {
            if (variant != "kak_slaney" && variant != "yu_ye_wang") {
                throw InvalidInput(fmt::format(
                    "shepp_logan: variant '{}': expected one of kak_slaney, yu_ye_wang", variant));
            }
            py::gil_scoped_release release;
            return volume::shepp_logan_3d(dims, variant == "kak_slaney"
                                                    ? volume::SheppLoganVariant::kak_slaney
                                                    : volume::SheppLoganVariant::yu_ye_wang);
        },
        py::arg("dims"), py::arg("variant") = "kak_slaney",
        "The 3D Shepp-Logan phantom as an f32 volume spanning [-1, 1]^3.");
    m.def(
        "uniform_sphere",
        [](const volume::Dims& dims, double radius,
           const std::variant<float, std::array<float, 4>>& value, const Vec3d& spacing,
           const Vec3d& origin, const std::optional<Vec3d>& center, int supersample) {
            const volume::SphereOptions options{.spacing = spacing,
                                                .origin = origin,
                                                .has_center = center.has_value(),
                                                .center = center.value_or(Vec3d{}),
                                                .supersample = supersample};
            py::gil_scoped_release release;
            if (const auto* rgba = std::get_if<std::array<float, 4>>(&value)) {
                return volume::uniform_sphere(dims, radius, *rgba, options);
            }
            return volume::uniform_sphere(dims, radius, std::get<float>(value), options);
        },
        py::arg("dims"), py::arg("radius"), py::arg("value") = 1.0f,
        py::arg("spacing") = Vec3d{1, 1, 1}, py::arg("origin") = Vec3d{0, 0, 0},
        py::arg("center") = py::none(), py::arg("supersample") = 1,
        "A sphere of `radius` world units: an f32 volume holding `value` inside, or an rgba32f "
        "volume when value is (r, g, b, a). Centred in the box unless `center` is given; "
        "supersample n > 1 anti-aliases the edge.");
    m.def(
        "rgba_test_object",
        [](const volume::Dims& dims, const std::string& type) {
            const VoxelType t = parse_type(type);
            py::gil_scoped_release release;
            return volume::rgba_test_object(dims, t);
        },
        py::arg("dims"), py::arg("type") = "rgba32f",
        "Red, green and blue arrows along +x, +y, +z, a grey sphere and a yellow cube in [-1, "
        "1]^3.");

    py::class_<volume::TransferFunction>(m, "TransferFunction", R"doc(
Classification of a scalar volume: piecewise-linear colour (value, r, g, b) and opacity
(value, alpha) control points, alpha per opacity_unit world units (0: the volume's smallest
spacing). Colours straight, in [0, 1].
)doc")
        .def(py::init([](const std::vector<std::array<double, 4>>& color,
                         const std::vector<std::array<double, 2>>& opacity, double opacity_unit,
                         std::string name) {
                 volume::TransferFunction tf;
                 tf.name = std::move(name);
                 for (const auto& c : color) {
                     tf.color.push_back({c[0],
                                         {static_cast<float>(c[1]), static_cast<float>(c[2]),
                                          static_cast<float>(c[3])}});
                 }
                 for (const auto& o : opacity) {
                     tf.opacity.push_back({o[0], static_cast<float>(o[1])});
                 }
                 tf.opacity_unit = opacity_unit;
                 tf.validate();
                 return tf;
             }),
             py::arg("color"), py::arg("opacity"), py::arg("opacity_unit") = 0.0,
             py::arg("name") = "python",
             "color: [(value, r, g, b), ...], opacity: [(value, alpha), ...], each sorted by "
             "value. InvalidInput naming the point for values out of range.")
        .def_readonly("name", &volume::TransferFunction::name)
        .def_readonly("opacity_unit", &volume::TransferFunction::opacity_unit)
        .def_property_readonly(
            "color",
            [](const volume::TransferFunction& tf) {
                py::list out;
                for (const auto& c : tf.color) {
                    out.append(py::make_tuple(c.value, c.rgb[0], c.rgb[1], c.rgb[2]));
                }
                return out;
            })
        .def_property_readonly("opacity",
                               [](const volume::TransferFunction& tf) {
                                   py::list out;
                                   for (const auto& o : tf.opacity) {
                                       out.append(py::make_tuple(o.value, o.alpha));
                                   }
                                   return out;
                               })
        .def(
            "evaluate",
            [](const volume::TransferFunction& tf, double value) {
                const auto c = tf.evaluate(value);
                return py::make_tuple(c[0], c[1], c[2], c[3]);
            },
            py::arg("value"), "(r, g, b, alpha) at `value`.");

    m.def("transfer_function_presets", &volume::preset_names,
          "Names of the presets: ct-bone, ct-skin, mri-brain, grayscale.");
    m.def("preset_transfer_function", &volume::preset, py::arg("name"), py::arg("volume"),
          "A preset for a scalar volume (relative presets use its value range).");
    m.def("load_transfer_function", &io::load_transfer_function, py::arg("name_or_file"),
          py::arg("volume"), "A preset name (for `volume`) or a transfer-function JSON file.");
    m.def(
        "value_range",
        [](const Volume& v) {
            const auto r = volume::value_range(v);
            return py::make_tuple(r[0], r[1]);
        },
        py::arg("volume"), "(smallest, largest) finite value of a scalar volume.");
    m.def("apply_transfer_function", &volume::apply, py::arg("volume"), py::arg("tf"),
          py::arg("output_unit") = 0.0, py::call_guard<py::gil_scoped_release>(),
          "The rgba32f volume of tf applied to every voxel of a scalar volume.");

    m.def(
        "threshold_alpha",
        [](Volume& v, double threshold_255) { return volume::threshold_alpha(v, threshold_255); },
        py::arg("volume"), py::arg("threshold_255"), py::call_guard<py::gil_scoped_release>(),
        "In place on an RGBA volume: alpha = 0 where 255 alpha < threshold_255. Returns the "
        "number of voxels zeroed.");
    m.def(
        "threshold_alpha",
        [](const volume::TransferFunction& tf, double threshold_255) {
            return volume::threshold_alpha(tf, threshold_255);
        },
        py::arg("tf"), py::arg("threshold_255"),
        "The transfer function whose opacity is 0 where 255 alpha < threshold_255.");
    m.def("normalize_alpha", &volume::normalize_alpha, py::arg("volume"),
          py::call_guard<py::gil_scoped_release>(),
          "In place: alpha / alpha_max. Returns alpha_max before normalization.");
    m.def(
        "clean",
        [](Volume& v, double threshold_255, const std::string& normalization) {
            volume::CleanOptions options{.threshold_255 = threshold_255};
            if (normalization == "none") {
                options.normalization = volume::AlphaNormalization::none;
            } else if (normalization == "max") {
                options.normalization = volume::AlphaNormalization::max;
            } else if (normalization == "threshold_range") {
                options.normalization = volume::AlphaNormalization::threshold_range;
            } else {
                throw InvalidInput(fmt::format(
                    "clean: normalization '{}': expected one of none, max, threshold_range",
                    normalization));
            }
            py::gil_scoped_release release;
            volume::clean(v, options);
        },
        py::arg("volume"), py::arg("threshold_255") = 0.0, py::arg("normalization") = "max",
        "In place on an RGBA volume: the threshold (0-255 alpha scale), then the alpha "
        "normalization ('max', 'threshold_range' or 'none'), as the paper's cleaning step.");
}

}  // namespace pliant::python
