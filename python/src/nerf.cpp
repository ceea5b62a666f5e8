// Radiance fields: posed-image datasets (nerf::Dataset, transforms.json), and the pipeline's
// three steps: render a dataset from a volume, train a field and export it as an RGBA volume,
// evaluate a volume on a dataset's views (pipeline::render_dataset / train_volume /
// evaluate_volume).
#include <fmt/format.h>
#include <pybind11/functional.h>

#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

#include "common.hpp"
#include "pliant/core/error.hpp"
#include "pliant/nerf/dataset.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/nerf/trainer.hpp"
#include "pliant/pipeline/nerf_dataset_file.hpp"
#include "pliant/pipeline/nerf_run.hpp"

namespace pliant::python {
namespace {

using nerf::Dataset;

render::Color color(const Vec3d& c) {
    return {static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
}

py::array pose_array(const nerf::Pose& pose) {
    std::vector<double> m(pose.m.begin(), pose.m.end());
    return owning_array(std::move(m), {3, 4});
}

const nerf::View& view_at(const Dataset& d, py::ssize_t i) {
    const auto n = static_cast<py::ssize_t>(d.views.size());
    if (i < -n || i >= n) {
        throw py::index_error(fmt::format("view {} out of range for {} views", i, n));
    }
    return d.views[static_cast<std::size_t>(i < 0 ? i + n : i)];
}

// Training, export and cleaning options from keyword arguments (TypeError for unknown ones).
pipeline::TrainRunOptions train_options_from(const py::kwargs& kwargs) {
    pipeline::TrainRunOptions o;
    nerf::TrainOptions& t = o.train;
    std::optional<double> threshold;
    std::string normalization = "max";
    for (const auto& [key_handle, value] : kwargs) {
        const auto key = key_handle.cast<std::string>();
        if (key == "resolution") {
            t.resolution = value.cast<int>();
        } else if (key == "stages") {
            t.stages = value.cast<int>();
        } else if (key == "iterations") {
            t.iterations = value.cast<std::int64_t>();
        } else if (key == "seconds") {
            t.seconds = value.cast<double>();
        } else if (key == "batch_rays") {
            t.batch_rays = value.cast<int>();
        } else if (key == "lr_density") {
            t.lr_density = value.cast<float>();
        } else if (key == "lr_color") {
            t.lr_color = value.cast<float>();
        } else if (key == "lr_final_factor") {
            t.lr_final_factor = value.cast<float>();
        } else if (key == "tv_density") {
            t.tv_density = value.cast<float>();
        } else if (key == "tv_color") {
            t.tv_color = value.cast<float>();
        } else if (key == "seed") {
            t.seed = value.cast<std::uint64_t>();
        } else if (key == "max_bytes") {
            t.max_bytes = value.cast<std::size_t>();
        } else if (key == "export_resolution") {
            o.exported.resolution = value.cast<int>();
        } else if (key == "export_type") {
            const auto type = value.cast<std::string>();
            if (type != "rgba8" && type != "rgba32f") {
                throw InvalidInput(fmt::format(
                    "train_volume: export_type '{}': expected one of rgba8, rgba32f", type));
            }
            o.exported.type =
                type == "rgba8" ? volume::VoxelType::rgba8 : volume::VoxelType::rgba32f;
        } else if (key == "clean_threshold") {
            if (!value.is_none()) {
                threshold = value.cast<double>();
            }
        } else if (key == "normalization") {
            normalization = value.cast<std::string>();
        } else {
            throw py::type_error(fmt::format(
                "train_volume: unknown option '{}'; expected resolution, stages, iterations, "
                "seconds, batch_rays, lr_density, lr_color, lr_final_factor, tv_density, "
                "tv_color, seed, max_bytes, export_resolution, export_type, clean_threshold, "
                "normalization",
                key));
        }
    }
    if (threshold) {
        volume::CleanOptions clean{.threshold_255 = *threshold};
        if (normalization == "none") {
            clean.normalization = volume::AlphaNormalization::none;
        } else if (normalization == "max") {
            clean.normalization = volume::AlphaNormalization::max;
        } else if (normalization == "threshold_range") {
            clean.normalization = volume::AlphaNormalization::threshold_range;
        } else {
            throw InvalidInput(fmt::format(
                "train_volume: normalization '{}': expected one of none, max, threshold_range",
                normalization));
        }
        o.clean = clean;
    }
    return o;
}

}  // namespace

void bind_nerf(py::module_& m) {
    py::class_<nerf::Intrinsics>(m, "Intrinsics",
                                 "Pinhole intrinsics: image size, focal lengths and principal "
                                 "point in pixels.")
        .def(py::init([](int width, int height, double fx, double fy, double cx, double cy) {
                 nerf::Intrinsics in;
                 in.width = width;
                 in.height = height;
                 in.fx = fx;
                 in.fy = fy;
                 in.cx = cx;
                 in.cy = cy;
                 return in;
             }),
             py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
             py::arg("cy"))
        .def_readwrite("width", &nerf::Intrinsics::width)
        .def_readwrite("height", &nerf::Intrinsics::height)
        .def_readwrite("fx", &nerf::Intrinsics::fx)
        .def_readwrite("fy", &nerf::Intrinsics::fy)
        .def_readwrite("cx", &nerf::Intrinsics::cx)
        .def_readwrite("cy", &nerf::Intrinsics::cy);

    py::class_<Dataset>(m, "Dataset", R"doc(
A posed-image dataset (nerf::Dataset): intrinsics, and per view a name, a camera-to-world pose
((3, 4) float64, OpenGL axes: the camera looks down -z, +y up) and an image.
image(i) is an (H, W, 3) float32 view of the dataset's memory (no copy, writeable), colours in
[0, 1] composited over `background`.
)doc")
        .def(py::init([](const nerf::Intrinsics& intrinsics, const DoubleArray& poses,
                         const FloatArray& images,
                         const std::optional<std::vector<std::string>>& names,
                         const std::optional<AABBd>& box, const Vec3d& background) {
                 const bool poses_ok = poses.ndim() == 3 && poses.shape(2) == 4 &&
                                       (poses.shape(1) == 3 || poses.shape(1) == 4);
                 if (!poses_ok) {
                     throw InvalidInput("Dataset: poses: expected shape (N, 3, 4) or (N, 4, 4)");
                 }
                 const py::ssize_t n = poses.shape(0);
                 const py::ssize_t h = intrinsics.height;
                 const py::ssize_t w = intrinsics.width;
                 if (images.ndim() != 4 || images.shape(0) != n || images.shape(1) != h ||
                     images.shape(2) != w || images.shape(3) != 3) {
                     throw InvalidInput(fmt::format(
                         "Dataset: images: expected shape ({}, {}, {}, 3) for {} poses and "
                         "{}x{} intrinsics",
                         n, h, w, n, w, h));
                 }
                 if (names && static_cast<py::ssize_t>(names->size()) != n) {
                     throw InvalidInput(
                         fmt::format("Dataset: names: {} names for {} poses", names->size(), n));
                 }
                 Dataset d;
                 d.intrinsics = intrinsics;
                 d.box = box;
                 d.background = color(background);
                 const auto pixels = static_cast<std::size_t>(3 * h * w);
                 for (py::ssize_t i = 0; i < n; ++i) {
                     nerf::View view;
                     view.name =
                         names ? (*names)[static_cast<std::size_t>(i)] : fmt::format("view_{}", i);
                     for (std::size_t r = 0; r < 3; ++r) {
                         for (std::size_t c = 0; c < 4; ++c) {
                             view.camera_to_world.m[4 * r + c] = poses.at(
                                 i, static_cast<py::ssize_t>(r), static_cast<py::ssize_t>(c));
                         }
                     }
                     view.rgb.resize(pixels);
                     std::memcpy(view.rgb.data(), images.data(i), pixels * sizeof(float));
                     d.views.push_back(std::move(view));
                 }
                 nerf::validate(d);
                 return d;
             }),
             py::arg("intrinsics"), py::arg("poses"), py::arg("images"),
             py::arg("names") = py::none(), py::arg("box") = py::none(),
             py::arg("background") = Vec3d{0, 0, 0},
             "A dataset from (N, 3, 4) or (N, 4, 4) camera-to-world poses and (N, H, W, 3) "
             "float32 images in [0, 1] (copied). InvalidInput for singular poses and bad "
             "intrinsics.")
        .def_readonly("intrinsics", &Dataset::intrinsics)
        .def_readonly("box", &Dataset::box, "The scene box ((lo), (hi)) of the file, or None.")
        .def_property_readonly("background",
                               [](const Dataset& d) {
                                   return py::make_tuple(d.background.r, d.background.g,
                                                         d.background.b);
                               })
        .def_property_readonly("num_views", [](const Dataset& d) { return d.views.size(); })
        .def("__len__", [](const Dataset& d) { return d.views.size(); })
        .def(
            "name", [](const Dataset& d, py::ssize_t i) { return view_at(d, i).name; },
            py::arg("i"))
        .def(
            "pose",
            [](const Dataset& d, py::ssize_t i) {
                return pose_array(view_at(d, i).camera_to_world);
            },
            py::arg("i"), "The (3, 4) camera-to-world matrix of view i (a copy).")
        .def(
            "camera",
            [](const Dataset& d, py::ssize_t i) {
                return nerf::camera_from_view(d.intrinsics, view_at(d, i).camera_to_world);
            },
            py::arg("i"), "View i as a Camera (square pixels, centred principal point).")
        .def(
            "image",
            [](const py::object& self, py::ssize_t i) {
                const auto& d = self.cast<const Dataset&>();
                const nerf::View& view = view_at(d, i);
                if (view.rgb.empty()) {
                    throw InvalidInput(fmt::format(
                        "Dataset.image: view {} has no image (read with load_images=False)", i));
                }
                const py::ssize_t h = d.intrinsics.height;
                const py::ssize_t w = d.intrinsics.width;
                const py::ssize_t f = sizeof(float);
                return py::array(py::dtype::of<float>(), {h, w, py::ssize_t{3}},
                                 {w * 3 * f, 3 * f, f}, view.rgb.data(), self);
            },
            py::arg("i"), "View i's image: an (H, W, 3) float32 view (no copy).")
        .def("__repr__", [](const Dataset& d) {
            return fmt::format("pliant.Dataset({} views of {}x{})", d.views.size(),
                               d.intrinsics.width, d.intrinsics.height);
        });

    m.def(
        "read_nerf_dataset",
        [](const std::filesystem::path& path, const Vec3d& background, bool load_images,
           std::size_t max_bytes) {
            py::gil_scoped_release release;
            return pipeline::read_nerf_dataset(path, {.background = color(background),
                                                      .load_images = load_images,
                                                      .max_bytes = max_bytes});
        },
        py::arg("path"), py::arg("background") = Vec3d{0, 0, 0}, py::arg("load_images") = true,
        py::arg("max_bytes") = pipeline::ReadNerfDatasetOptions{}.max_bytes,
        "Reads a NeRF-synthetic / instant-ngp transforms.json and its images (composited over "
        "`background`).");

    const pipeline::DatasetRunOptions dataset_defaults;
    m.def(
        "render_dataset",
        [](const volume::Volume& source, const std::filesystem::path& dir,
           const volume::TransferFunction* tf, int views, std::pair<int, int> size, double fov,
           int test_every, const Vec3d& background, double step) {
            const pipeline::DatasetRunOptions options{
                .views = views,
                .size = {size.first, size.second},
                .fov = fov,
                .test_every = test_every,
                .background = {static_cast<float>(background.x), static_cast<float>(background.y),
                               static_cast<float>(background.z)},
                .step = step};
            nlohmann::ordered_json result;
            {
                py::gil_scoped_release release;
                result = pipeline::render_dataset(source, tf, options, dir);
            }
            return to_python(result);
        },
        py::arg("source"), py::arg("dir"), py::arg("tf") = py::none(), py::kw_only(),
        py::arg("views") = dataset_defaults.views,
        py::arg("size") = std::pair<int, int>(dataset_defaults.size[0], dataset_defaults.size[1]),
        py::arg("fov") = dataset_defaults.fov, py::arg("test_every") = dataset_defaults.test_every,
        py::arg("background") = Vec3d{0, 0, 0}, py::arg("step") = dataset_defaults.step,
        "What `pliant dataset` does: `views` ray-cast views of `source` from a Fibonacci "
        "sphere into dir/train, dir/test and dir/transforms_{train,test}.json (view i is a test "
        "view when i % test_every == 0). Returns the command's JSON as a dict. Releases the GIL.");

    py::class_<nerf::TrainProgress>(m, "TrainProgress")
        .def_readonly("iteration", &nerf::TrainProgress::iteration)
        .def_readonly("progress", &nerf::TrainProgress::progress)
        .def_readonly("loss", &nerf::TrainProgress::loss)
        .def_readonly("psnr", &nerf::TrainProgress::psnr)
        .def_readonly("resolution", &nerf::TrainProgress::resolution)
        .def_readonly("occupied_cells", &nerf::TrainProgress::occupied_cells)
        .def_readonly("elapsed_ms", &nerf::TrainProgress::elapsed_ms);

    m.def(
        "train_volume",
        [](const Dataset& dataset, const std::function<void(const nerf::TrainProgress&)>& progress,
           const py::kwargs& kwargs) {
            pipeline::TrainRunOptions options = train_options_from(kwargs);
            if (progress) {
                options.on_progress = [&progress](const nerf::TrainProgress& p) {
                    py::gil_scoped_acquire gil;
                    progress(p);
                };
            }
            // Ctrl-C stops training; the field so far is exported, then KeyboardInterrupt.
            bool interrupted = false;
            const auto keep_going = [&interrupted] {
                py::gil_scoped_acquire gil;
                if (PyErr_CheckSignals() != 0) {
                    PyErr_Clear();
                    interrupted = true;
                }
                return !interrupted;
            };
            pipeline::TrainRunResult result;
            {
                py::gil_scoped_release release;
                result = pipeline::train_volume(dataset, options, keep_going);
            }
            if (interrupted) {
                PyErr_SetNone(PyExc_KeyboardInterrupt);
                throw py::error_already_set();
            }
            return py::make_tuple(std::move(result.volume), to_python(result.json));
        },
        py::arg("dataset"), py::kw_only(), py::arg("progress") = py::none(),
        R"doc(What `pliant nerf train` does: trains a voxel radiance field on `dataset` and exports
it as an RGBA volume. Returns (volume, stats dict). progress(TrainProgress) is called after every
iteration. Releases the GIL; Ctrl-C stops training (KeyboardInterrupt).

Options (keywords): resolution (128), stages (3), iterations (2000), seconds (0: use iterations),
batch_rays (4096), lr_density, lr_color (0.1), lr_final_factor (0.1), tv_density, tv_color (0),
seed (1), max_bytes; export_resolution (256), export_type ('rgba8' or 'rgba32f');
clean_threshold (None: no cleaning; else the 0-255 alpha threshold) and normalization ('max',
'threshold_range', 'none').)doc");

    m.def(
        "evaluate_volume",
        [](const Dataset& dataset, const volume::Volume& v, const Vec3d& background,
           const std::optional<std::filesystem::path>& images_dir) {
            nlohmann::ordered_json result;
            {
                py::gil_scoped_release release;
                result = pipeline::evaluate_volume(
                    dataset, v,
                    {static_cast<float>(background.x), static_cast<float>(background.y),
                     static_cast<float>(background.z)},
                    images_dir.value_or(std::filesystem::path()));
            }
            return to_python(result);
        },
        py::arg("dataset"), py::arg("volume"), py::arg("background") = Vec3d{0, 0, 0},
        py::arg("images_dir") = py::none(),
        "What `pliant nerf eval` does: ray-casts the RGBA volume from every view and returns "
        "{psnr, ssim, views: [...]} (means over the views). Releases the GIL.");

    m.def(
        "psnr",
        [](const FloatArray& a, const FloatArray& b) {
            return nerf::psnr({a.data(), static_cast<std::size_t>(a.size())},
                              {b.data(), static_cast<std::size_t>(b.size())});
        },
        py::arg("a"), py::arg("b"), "PSNR (dB) of two images with values in [0, 1].");
    m.def(
        "ssim",
        [](const FloatArray& a, const FloatArray& b) {
            if (a.ndim() != 3 || a.shape(2) != 3) {
                throw InvalidInput("ssim: a: expected an (H, W, 3) image");
            }
            return nerf::ssim({a.data(), static_cast<std::size_t>(a.size())},
                              {b.data(), static_cast<std::size_t>(b.size())},
                              static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
        },
        py::arg("a"), py::arg("b"), "SSIM of two (H, W, 3) images with values in [0, 1].");
}

}  // namespace pliant::python
