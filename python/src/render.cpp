// Rendering: cameras, the volume ray caster (render::RayCaster) into numpy images, PNG files.
//
// Images are (H, W, 3) uint8 arrays, row 0 at the top, RGB, values as computed (no gamma): the
// array owns the rendered pixels (moved, not copied).
#include <fmt/format.h>

#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

#include "common.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/png.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/raycast.hpp"

namespace pliant::python {
namespace {

using render::Camera;

py::array image_array(render::Image&& image) {
    const py::ssize_t h = image.height;
    const py::ssize_t w = image.width;
    return owning_array(std::move(image.pixels), {h, w, 3});
}

render::Image image_from_array(const py::array_t<std::uint8_t, py::array::c_style>& array) {
    if (array.ndim() != 3 || array.shape(2) != 3) {
        throw InvalidInput("image: expected a uint8 array of shape (H, W, 3)");
    }
    render::Image image(static_cast<int>(array.shape(1)), static_cast<int>(array.shape(0)));
    std::memcpy(image.pixels.data(), array.data(), image.pixels.size());
    return image;
}

render::Color color(const Vec3d& c) {
    return {static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
}

// The ray caster's options from keyword arguments (TypeError for unknown ones).
render::RayCastOptions options_from(const py::kwargs& kwargs) {
    render::RayCastOptions o;
    for (const auto& [key_handle, value] : kwargs) {
        const auto key = key_handle.cast<std::string>();
        if (key == "step") {
            o.step = value.cast<double>();
        } else if (key == "opacity_unit") {
            o.opacity_unit = value.cast<double>();
        } else if (key == "early_termination") {
            o.early_termination = value.cast<double>();
        } else if (key == "mode") {
            const auto mode = value.cast<std::string>();
            if (mode != "composite" && mode != "mip") {
                throw InvalidInput(
                    fmt::format("ray caster: mode '{}': expected one of composite, mip", mode));
            }
            o.mode = mode == "mip" ? render::RayCastMode::mip : render::RayCastMode::composite;
        } else if (key == "shading") {
            o.shading = value.cast<bool>();
        } else if (key == "background") {
            o.background = color(value.cast<Vec3d>());
        } else if (key == "empty_space_skipping") {
            o.empty_space_skipping = value.cast<bool>();
        } else if (key == "clip") {
            if (!value.is_none()) {
                const auto [point, normal] = value.cast<std::pair<Vec3d, Vec3d>>();
                o.clip = render::ClipPlane{point, normal};
            }
        } else {
            throw py::type_error(fmt::format(
                "ray caster: unknown option '{}'; expected step, opacity_unit, "
                "early_termination, mode, shading, background, empty_space_skipping, clip",
                key));
        }
    }
    return o;
}

constexpr const char* RAYCAST_OPTIONS_DOC = R"doc(
Options (keywords): step (world units; 0: half the smallest spacing), opacity_unit (world units
RGBA opacities and unit-less transfer functions are per; 0: the smallest spacing),
early_termination (0.99), mode ('composite' or 'mip'), shading (False), background ((r, g, b),
black), empty_space_skipping (True; images are identical without it), clip (None, or
(point, normal): keeps (p - point) . normal >= 0).)doc";

}  // namespace

void bind_render(py::module_& m) {
    py::class_<Camera>(m, "Camera", R"doc(
A pinhole perspective or orthographic camera over a width x height image (render::Camera).
Pixel (i, j) is column i, row j from the top-left; its centre is (i + 0.5, j + 0.5).
)doc")
        .def_static("perspective", &Camera::perspective, py::arg("eye"), py::arg("target"),
                    py::arg("up"), py::arg("fov_y_degrees"), py::arg("width"), py::arg("height"))
        .def_static("orthographic", &Camera::orthographic, py::arg("eye"), py::arg("target"),
                    py::arg("up"), py::arg("view_height"), py::arg("width"), py::arg("height"))
        .def_static(
            "framing",
            [](const AABBd& box, double azimuth, double elevation, int width, int height,
               const std::string& projection, double fov_y_degrees, double margin) {
                if (projection != "perspective" && projection != "orthographic") {
                    throw InvalidInput(
                        fmt::format("Camera.framing: projection '{}': expected one of perspective, "
                                    "orthographic",
                                    projection));
                }
                return render::frame_box(
                    box, azimuth, elevation, width, height,
                    {.projection = projection == "perspective" ? render::Projection::perspective
                                                               : render::Projection::orthographic,
                     .fov_y_degrees = fov_y_degrees,
                     .margin = margin});
            },
            py::arg("box"), py::arg("azimuth"), py::arg("elevation"), py::arg("width"),
            py::arg("height"), py::kw_only(), py::arg("projection") = "perspective",
            py::arg("fov_y_degrees") = 30.0, py::arg("margin") = 1.1,
            "A camera looking at the centre of `box` ((lo, hi), e.g. Volume.world_bounds) from "
            "(azimuth, elevation) in degrees, far enough for the whole box to fit.")
        .def_static("orbit", &render::orbit_camera, py::arg("box"), py::arg("azimuth"),
                    py::arg("elevation"), py::arg("distance"), py::arg("width"), py::arg("height"),
                    "The CLI's orbit camera around the box's centre (distance <= 0 frames it).")
        .def_static(
            "along_axis",
            [](const AABBd& box, const std::string& axis, int width, int height) {
                return render::view_camera(box, render::parse_view_axis(axis.c_str()), width,
                                           height);
            },
            py::arg("box"), py::arg("axis"), py::arg("width"), py::arg("height"),
            "The orthographic camera looking along axis '+x', '-x', '+y', '-y', '+z' or '-z' "
            "whose image is the box (render::view_camera).")
        .def_property_readonly("width", &Camera::width)
        .def_property_readonly("height", &Camera::height)
        .def_property_readonly("eye", &Camera::eye)
        .def_property_readonly("target", &Camera::target)
        .def_property_readonly("forward", &Camera::forward)
        .def_property_readonly("right", &Camera::right)
        .def_property_readonly("up", &Camera::up)
        .def_property_readonly("fov_y_degrees", &Camera::fov_y_degrees)
        .def_property_readonly("focal_pixels", &Camera::focal_pixels)
        .def(
            "project",
            [](const Camera& c, const Vec3d& p) {
                const render::PixelPoint q = c.project(p);
                return py::make_tuple(q.x, q.y, q.depth);
            },
            py::arg("point"), "(x, y, depth): continuous pixel coordinates and camera depth.")
        .def(
            "pixel_ray",
            [](const Camera& c, int i, int j) {
                const render::Ray r = c.pixel_ray(i, j);
                return py::make_tuple(r.origin, r.direction);
            },
            py::arg("i"), py::arg("j"), "(origin, unit direction) of pixel (i, j)'s centre ray.");

    py::class_<render::RayCastStats>(m, "RayCastStats")
        .def_readonly("samples", &render::RayCastStats::samples)
        .def_readonly("ms", &render::RayCastStats::ms);

    py::class_<render::RayCaster>(m, "RayCaster",
                                  (std::string(R"doc(
A volume prepared for ray casting many images (render::RayCaster): front-to-back compositing
with early termination and empty-space skipping, or maximum intensity projection. Scalar volumes
need a TransferFunction; RGBA volumes use their own colour and opacity. Keeps no reference to
the volume. render() releases the GIL and returns an (H, W, 3) uint8 image.
)doc") + RAYCAST_OPTIONS_DOC)
                                      .c_str())
        .def(py::init([](const volume::Volume& v, const volume::TransferFunction* tf,
                         const py::kwargs& kwargs) {
                 const render::RayCastOptions options = options_from(kwargs);
                 py::gil_scoped_release release;
                 return std::make_unique<render::RayCaster>(v, tf, options);
             }),
             py::arg("volume"), py::arg("tf") = py::none())
        .def(
            "render",
            [](const render::RayCaster& caster, const Camera& camera, bool return_stats) {
                render::Image image;
                render::RayCastStats stats;
                {
                    py::gil_scoped_release release;
                    stats = caster.render(camera, image);
                }
                py::array pixels = image_array(std::move(image));
                if (return_stats) {
                    return py::object(py::make_tuple(pixels, stats));
                }
                return py::object(pixels);
            },
            py::arg("camera"), py::arg("return_stats") = false,
            "The (H, W, 3) uint8 image seen by `camera` (with return_stats: (image, "
            "RayCastStats)).")
        .def(
            "set_clip",
            [](render::RayCaster& caster, const std::optional<std::pair<Vec3d, Vec3d>>& clip) {
                caster.set_clip(clip ? std::optional<render::ClipPlane>(
                                           render::ClipPlane{clip->first, clip->second})
                                     : std::nullopt);
            },
            py::arg("clip"), "(point, normal) or None: the clipping plane of later renders.")
        .def_property_readonly("step", &render::RayCaster::step)
        .def_property_readonly("opacity_unit", &render::RayCaster::opacity_unit)
        .def_property_readonly("prepare_ms", &render::RayCaster::prepare_ms)
        .def_property_readonly("num_cells", &render::RayCaster::num_cells)
        .def_property_readonly("num_occupied_cells", &render::RayCaster::num_occupied_cells);

    m.def(
        "raycast",
        [](const volume::Volume& v, const Camera& camera, const volume::TransferFunction* tf,
           const py::kwargs& kwargs) {
            const render::RayCastOptions options = options_from(kwargs);
            render::Image image;
            {
                py::gil_scoped_release release;
                render::raycast(v, tf, camera, options, image);
            }
            return image_array(std::move(image));
        },
        py::arg("volume"), py::arg("camera"), py::arg("tf") = py::none(),
        (std::string("One image of `volume` seen by `camera`: RayCaster(volume, tf, "
                     "**options).render(camera).") +
         RAYCAST_OPTIONS_DOC)
            .c_str());

    m.def(
        "write_png",
        [](const std::filesystem::path& path,
           const py::array_t<std::uint8_t, py::array::c_style>& image) {
            const render::Image copy = image_from_array(image);
            py::gil_scoped_release release;
            io::write_png(path, copy);
        },
        py::arg("path"), py::arg("image"), "Writes an (H, W, 3) uint8 image as PNG, atomically.");
    m.def(
        "read_png",
        [](const std::filesystem::path& path) {
            render::Image image;
            {
                py::gil_scoped_release release;
                image = io::read_png(path);
            }
            return image_array(std::move(image));
        },
        py::arg("path"), "A PNG file as an (H, W, 3) uint8 image.");
}

}  // namespace pliant::python
