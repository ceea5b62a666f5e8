// Deformable volumes: tet meshes and grids over volumes, the XPBD soft body and its drivers,
// resampling of deformed tets into a grid, pipeline::DeformableVolume and `pliant deform` as a
// function (pipeline::run_deform).
#include <fmt/format.h>
#include <pybind11/functional.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "common.hpp"
#include "pliant/core/error.hpp"
#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/io/tetgen.hpp"
#include "pliant/pbd/drivers.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/pipeline/deform_run.hpp"
#include "pliant/pipeline/deformable_volume.hpp"
#include "pliant/volume/resample.hpp"

namespace pliant::python {
namespace {

using geometry::TetMesh;
using pbd::SoftBody;
using pipeline::DeformableVolume;

pbd::Axis parse_axis(const std::string& text) {
    if (text == "x") {
        return pbd::Axis::x;
    }
    if (text == "y") {
        return pbd::Axis::y;
    }
    if (text == "z") {
        return pbd::Axis::z;
    }
    throw InvalidInput(fmt::format("axis '{}': expected one of x, y, z", text));
}

std::string axis_name(pbd::Axis axis) {
    return {"xyz"[static_cast<int>(axis)]};
}

// The soft body's options from keyword arguments (TypeError for unknown ones).
pbd::SoftBodyOptions body_options_from(const py::kwargs& kwargs) {
    pbd::SoftBodyOptions o;
    for (const auto& [key_handle, value] : kwargs) {
        const auto key = key_handle.cast<std::string>();
        if (key == "stiffness") {
            o.stiffness = value.cast<double>();
        } else if (key == "edge_share") {
            o.edge_share = value.cast<double>();
        } else if (key == "density") {
            o.density = value.cast<double>();
        } else if (key == "damping") {
            o.damping = value.cast<double>();
        } else if (key == "substeps") {
            o.substeps = value.cast<int>();
        } else if (key == "gravity") {
            o.gravity = value.cast<Vec3d>();
        } else if (key == "edge_compliance") {
            o.edge_compliance = value.cast<double>();
        } else if (key == "volume_compliance") {
            o.volume_compliance = value.cast<double>();
        } else {
            throw py::type_error(fmt::format(
                "soft body: unknown option '{}'; expected stiffness, edge_share, density, "
                "damping, substeps, gravity, edge_compliance, volume_compliance",
                key));
        }
    }
    return o;
}

constexpr const char* BODY_OPTIONS_DOC = R"doc(
Soft-body options (keywords): stiffness (PBD k in (0, 1], 1.0), edge_share (beta: edges get
beta k, 0.05), density (kg per world unit cubed, 1000), damping (1/s, 1.0), substeps (10),
gravity ((0, 0, 0), world units/s^2), edge_compliance and volume_compliance (0: none).)doc";

// A pipeline::DeformableVolume and the guard of the Python references to its soft body, which
// reset_body() replaces.
struct PyDeformableVolume {
    std::unique_ptr<DeformableVolume> deformable;
    ViewGuard views;
};

}  // namespace

void bind_pbd(py::module_& m) {
    py::class_<TetMesh>(m, "TetMesh", R"doc(
A tetrahedral mesh that owns its data (geometry::TetMesh): positions (N, 3) float32 and tets
(T, 4) int32, positively oriented; both writeable views of the mesh's memory (no copy).
)doc")
        .def(py::init([](const FloatArray& positions, const IndexArray& tets) {
                 const auto p = vec3f_rows(positions, "TetMesh: positions");
                 const auto t = index_rows<4>(tets, "TetMesh: tets");
                 TetMesh mesh;
                 mesh.positions.assign(p.begin(), p.end());
                 mesh.tets.assign(t.begin(), t.end());
                 return mesh;
             }),
             py::arg("positions"), py::arg("tets"),
             "A mesh from (N, 3) and (T, 4) arrays (copied).")
        .def_property_readonly(
            "positions",
            [](const py::object& self) {
                return vec3_view(std::span<const Vec3f>(self.cast<TetMesh&>().positions), self,
                                 true);
            },
            "(N, 3) float32 view (world units).")
        .def_property_readonly(
            "tets",
            [](const py::object& self) {
                return index_view<4>(std::span<const geometry::Tet>(self.cast<TetMesh&>().tets),
                                     self, true);
            },
            "(T, 4) int32 view.")
        .def_property_readonly("num_vertices", &TetMesh::num_vertices)
        .def_property_readonly("num_tets", &TetMesh::num_tets)
        .def("__repr__", [](const TetMesh& mesh) {
            return fmt::format("pliant.TetMesh({} vertices, {} tets)", mesh.num_vertices(),
                               mesh.num_tets());
        });
    m.def("read_tetgen", &io::read_tetgen, py::arg("path"),
          "A TetGen mesh (.node + .ele; either name, or the base name).");
    m.def("write_tetgen", &io::write_tetgen, py::arg("base"), py::arg("mesh"),
          "Writes base.node and base.ele.");

    py::class_<pbd::TetGrid>(m, "TetGrid", R"doc(
A tet mesh over a volume (pbd::build_tet_grid): cells of B^3 voxels, 5 tets each, only the
cells near visible voxels unless full_box.
)doc")
        .def_readonly("mesh", &pbd::TetGrid::mesh, "The rest mesh (a view into this grid).")
        .def_readonly("cell_voxels", &pbd::TetGrid::cell_voxels)
        .def_property_readonly("cells",
                               [](const pbd::TetGrid& g) {
                                   return py::make_tuple(g.cells[0], g.cells[1], g.cells[2]);
                               })
        .def_property_readonly("num_active_cells", &pbd::TetGrid::num_active_cells);
    m.def(
        "build_tet_grid",
        [](const volume::Volume& v, int cell_voxels, bool full_box,
           const volume::TransferFunction* tf) {
            py::gil_scoped_release release;
            return pbd::build_tet_grid(
                v, {.cell_voxels = cell_voxels, .full_box = full_box, .tf = tf});
        },
        py::arg("volume"), py::arg("cell_voxels") = 4, py::arg("full_box") = false,
        py::arg("tf") = py::none(),
        "The tet grid over a volume; a scalar volume's visible voxels are those tf gives an "
        "opacity (None: value != 0), an RGBA volume's those with alpha > 0.");

    const pbd::WaveDriver wave;
    py::class_<pbd::WaveDriver>(m, "WaveDriver",
                                "A travelling wave of the rest shape (box units, seconds).")
        .def(py::init([](const std::string& direction, const std::string& displacement,
                         double amplitude, double wavelength, double speed, double ramp_time) {
                 return pbd::WaveDriver{parse_axis(direction),
                                        parse_axis(displacement),
                                        amplitude,
                                        wavelength,
                                        speed,
                                        ramp_time};
             }),
             py::arg("direction") = axis_name(wave.direction),
             py::arg("displacement") = axis_name(wave.displacement),
             py::arg("amplitude") = wave.amplitude, py::arg("wavelength") = wave.wavelength,
             py::arg("speed") = wave.speed, py::arg("ramp_time") = wave.ramp_time)
        .def_readwrite("amplitude", &pbd::WaveDriver::amplitude)
        .def_readwrite("wavelength", &pbd::WaveDriver::wavelength)
        .def_readwrite("speed", &pbd::WaveDriver::speed)
        .def_readwrite("ramp_time", &pbd::WaveDriver::ramp_time);
    const pbd::TwistDriver twist;
    py::class_<pbd::TwistDriver>(
        m, "TwistDriver",
        "Turns the max face about `axis` by `angle` degrees relative to the min face.")
        .def(py::init([](const std::string& axis, double angle, double ramp_time, double grip) {
                 return pbd::TwistDriver{parse_axis(axis), angle, ramp_time, grip};
             }),
             py::arg("axis") = axis_name(twist.axis), py::arg("angle") = twist.angle,
             py::arg("ramp_time") = twist.ramp_time, py::arg("grip") = twist.grip)
        .def_readwrite("angle", &pbd::TwistDriver::angle)
        .def_readwrite("ramp_time", &pbd::TwistDriver::ramp_time)
        .def_readwrite("grip", &pbd::TwistDriver::grip);
    const pbd::BubbleDriver bubble;
    py::class_<pbd::BubbleDriver>(m, "BubbleDriver",
                                  "Inflates the rest volume around a centre (box coordinates).")
        .def(py::init([](const Vec3d& centre, double radius, double inflation, double ramp_time) {
                 return pbd::BubbleDriver{centre, radius, inflation, ramp_time};
             }),
             py::arg("centre") = bubble.centre, py::arg("radius") = bubble.radius,
             py::arg("inflation") = bubble.inflation, py::arg("ramp_time") = bubble.ramp_time)
        .def_readwrite("radius", &pbd::BubbleDriver::radius)
        .def_readwrite("inflation", &pbd::BubbleDriver::inflation)
        .def_readwrite("ramp_time", &pbd::BubbleDriver::ramp_time);
    const pbd::RotateDriver rotate;
    py::class_<pbd::RotateDriver>(m, "RotateDriver",
                                  "Rotates the whole body rigidly about `axis` through `centre`.")
        .def(py::init([](const std::string& axis, double angle, double ramp_time,
                         const std::optional<Vec3d>& centre) {
                 return pbd::RotateDriver{parse_axis(axis), angle, ramp_time, centre};
             }),
             py::arg("axis") = axis_name(rotate.axis), py::arg("angle") = rotate.angle,
             py::arg("ramp_time") = rotate.ramp_time, py::arg("centre") = py::none())
        .def_readwrite("angle", &pbd::RotateDriver::angle)
        .def_readwrite("ramp_time", &pbd::RotateDriver::ramp_time);

    py::class_<pbd::SoftBodyStats>(m, "SoftBodyStats")
        .def_readonly("volume_ratio", &pbd::SoftBodyStats::volume_ratio,
                      "Total signed tet volume now / at rest.")
        .def_readonly("inverted_tets", &pbd::SoftBodyStats::inverted_tets)
        .def_readonly("ms_per_substep", &pbd::SoftBodyStats::ms_per_substep)
        .def_readonly("step_ms", &pbd::SoftBodyStats::step_ms);

    py::class_<SoftBody>(m, "SoftBody",
                         (std::string(R"doc(
The XPBD soft body on a tet mesh (pbd::SoftBody): edge and tet-volume constraints, drivers,
drag, pins. positions, velocities, rest_positions, inv_masses, tets and edges are read-only
views of the body's memory (no copy) that follow it as it steps.
)doc") + BODY_OPTIONS_DOC)
                             .c_str())
        .def(py::init([](const TetMesh& rest, const py::kwargs& kwargs) {
                 const pbd::SoftBodyOptions options = body_options_from(kwargs);
                 py::gil_scoped_release release;
                 return std::make_unique<SoftBody>(rest, options);
             }),
             py::arg("rest"), "A body at rest on a tet mesh (coloured greedily).")
        .def(py::init([](const pbd::TetGrid& grid, const py::kwargs& kwargs) {
                 const pbd::SoftBodyOptions options = body_options_from(kwargs);
                 py::gil_scoped_release release;
                 return std::make_unique<SoftBody>(grid, options);
             }),
             py::arg("grid"), "A body at rest on a tet grid (coloured from its lattice).")
        .def("add_driver", &SoftBody::add_driver, py::arg("driver"),
             "Adds a WaveDriver, TwistDriver, BubbleDriver or RotateDriver.")
        .def("clear_drivers", &SoftBody::clear_drivers)
        .def("set_drag", &SoftBody::set_drag, py::arg("vertex"), py::arg("target"),
             py::arg("radius") = 0.0f,
             "Pulls `vertex` (and those within `radius`) to `target` over the next step.")
        .def("release_drag", &SoftBody::release_drag)
        .def("set_stiffness", &SoftBody::set_stiffness, py::arg("stiffness"))
        .def(
            "pin",
            [](SoftBody& body, const IndexArray& vertices) {
                if (vertices.ndim() != 1) {
                    throw InvalidInput("SoftBody.pin: vertices: expected a 1-D array of indices");
                }
                body.pin({vertices.data(), static_cast<std::size_t>(vertices.shape(0))});
            },
            py::arg("vertices"), "Pins vertices (inverse mass 0).")
        .def(
            "set_positions",
            [](SoftBody& body, const FloatArray& positions) {
                body.set_positions(vec3f_rows(positions, "SoftBody.set_positions: positions"));
            },
            py::arg("positions"))
        .def(
            "set_velocities",
            [](SoftBody& body, const FloatArray& velocities) {
                body.set_velocities(vec3f_rows(velocities, "SoftBody.set_velocities: velocities"));
            },
            py::arg("velocities"))
        .def("step", &SoftBody::step, py::arg("dt"), py::call_guard<py::gil_scoped_release>(),
             "Advances dt seconds in `substeps` substeps. Releases the GIL.")
        .def("stats", &SoftBody::stats, py::call_guard<py::gil_scoped_release>())
        .def_property_readonly("time", &SoftBody::time)
        .def_property_readonly(
            "positions",
            [](const py::object& self) {
                return vec3_view(self.cast<SoftBody&>().positions(), self, false);
            },
            "(N, 3) float32 read-only view (world units).")
        .def_property_readonly("velocities",
                               [](const py::object& self) {
                                   return vec3_view(self.cast<SoftBody&>().velocities(), self,
                                                    false);
                               })
        .def_property_readonly("rest_positions",
                               [](const py::object& self) {
                                   return vec3_view(self.cast<SoftBody&>().rest_positions(), self,
                                                    false);
                               })
        .def_property_readonly(
            "inv_masses",
            [](const py::object& self) {
                const std::span<const float> w = self.cast<SoftBody&>().inv_masses();
                return records_view(w.data(), w.size(), 0, self, false);
            },
            "(N,) float32 (0: pinned).")
        .def_property_readonly("tets",
                               [](const py::object& self) {
                                   return index_view<4>(self.cast<SoftBody&>().tets(), self, false);
                               })
        .def_property_readonly("edges", [](const py::object& self) {
            return index_view<2>(self.cast<SoftBody&>().edges(), self, false);
        });

    py::class_<volume::ResampleStats>(m, "ResampleStats")
        .def_readonly("num_tets", &volume::ResampleStats::num_tets)
        .def_readonly("num_tets_skipped", &volume::ResampleStats::num_tets_skipped)
        .def_readonly("num_degenerate", &volume::ResampleStats::num_degenerate)
        .def_readonly("num_inverted", &volume::ResampleStats::num_inverted)
        .def_readonly("num_voxels_written", &volume::ResampleStats::num_voxels_written);
    m.def(
        "resample",
        [](const volume::Volume& source, const TetMesh& rest, const FloatArray& deformed,
           volume::Volume& target, bool skip_inverted) {
            const auto p = vec3f_rows(deformed, "resample: deformed_positions");
            py::gil_scoped_release release;
            return volume::resample(source, rest.tets, rest.positions, p, target,
                                    {.skip_inverted = skip_inverted});
        },
        py::arg("source"), py::arg("rest"), py::arg("deformed_positions"), py::arg("target"),
        py::arg("skip_inverted") = false,
        "Rasterizes the tet mesh `rest` (in the source's frame) deformed to deformed_positions "
        "((N, 3) float32) into `target` (its dims, spacing and origin define the grid; every "
        "voxel is overwritten), sampling `source` at the rest positions. Returns ResampleStats. "
        "Releases the GIL.");

    py::class_<PyDeformableVolume>(m, "DeformableVolume",
                                   (std::string(R"doc(
The deformable-volume pipeline on one source volume (pipeline::DeformableVolume): a tet grid over
its visible voxels (or a TetGen mesh), the soft body on it, and the resampler.

    dv = pliant.DeformableVolume(source, tf=None, stiffness=0.8)
    dv.body.add_driver(pliant.TwistDriver(angle=90))
    dv.body.step(1 / 24)
    deformed = dv.resample()        # a Volume like the source

The source (and tf) are kept alive by this object. reset_body() replaces the body, so it raises
InvalidInput while a reference to `body` (or a view of its arrays) is alive.
)doc") + BODY_OPTIONS_DOC)
                                       .c_str())
        .def(py::init([](const volume::Volume& source, const volume::TransferFunction* tf,
                         int cell_voxels, bool full_box,
                         const std::optional<std::filesystem::path>& mesh,
                         const py::kwargs& kwargs) {
                 const pbd::SoftBodyOptions options = body_options_from(kwargs);
                 py::gil_scoped_release release;
                 auto out = std::make_unique<PyDeformableVolume>();
                 out->deformable = std::make_unique<DeformableVolume>(
                     source, tf,
                     pbd::TetGridOptions{.cell_voxels = cell_voxels, .full_box = full_box},
                     mesh.value_or(std::filesystem::path()), options);
                 return out;
             }),
             py::arg("source"), py::arg("tf") = py::none(), py::kw_only(),
             py::arg("cell_voxels") = 4, py::arg("full_box") = false, py::arg("mesh") = py::none(),
             py::keep_alive<1, 2>(), py::keep_alive<1, 3>())
        .def_property_readonly(
            "body",
            [](const py::object& self) {
                auto& d = self.cast<PyDeformableVolume&>();
                py::object body =
                    py::cast(&d.deformable->body(), py::return_value_policy::reference);
                py::detail::keep_alive_impl(body, guard_base(self, d.views));
                return body;
            },
            "The SoftBody (a reference: it keeps this object alive).")
        .def_property_readonly(
            "rest", [](const PyDeformableVolume& d) { return d.deformable->rest(); },
            "A copy of the rest tet mesh (the body's rest_positions and tets are views).")
        .def(
            "reset_body",
            [](PyDeformableVolume& d) {
                d.views.check_none_alive("DeformableVolume.reset_body");
                py::gil_scoped_release release;
                d.deformable->reset_body();
            },
            "A new body at rest, time 0, same options; drivers and drag are not carried over.")
        .def(
            "target_like", [](const PyDeformableVolume& d) { return d.deformable->target_like(); },
            "An empty volume like the source, for resample().")
        .def(
            "resample",
            [](const PyDeformableVolume& d, volume::Volume* target,
               bool return_stats) -> py::object {
                py::object out;
                volume::Volume* into = target;
                if (target != nullptr) {
                    out = py::cast(target, py::return_value_policy::reference);
                } else {
                    out = py::cast(d.deformable->target_like());
                    into = out.cast<volume::Volume*>();
                }
                volume::ResampleStats stats;
                {
                    py::gil_scoped_release release;
                    stats = d.deformable->resample(*into);
                }
                if (return_stats) {
                    return py::make_tuple(out, stats);
                }
                return out;
            },
            py::arg("target") = py::none(), py::arg("return_stats") = false,
            "The body's current shape resampled into `target` (None: a new volume like the "
            "source); returns the target (with return_stats: (target, ResampleStats)). Releases "
            "the GIL.");

    m.def(
        "run_deform",
        [](const volume::Volume& source, const std::filesystem::path& out,
           const volume::TransferFunction* tf, const pbd::Driver& driver, int frames, double fps,
           const std::optional<std::filesystem::path>& video,
           const std::optional<std::filesystem::path>& still, std::pair<int, int> size,
           std::array<double, 3> camera, bool shading, double step, int cell_voxels, bool full_box,
           const std::optional<std::filesystem::path>& mesh, const std::string& driver_name,
           const std::function<void(int, int, double)>& progress, int thin_levels,
           const py::kwargs& kwargs) {
            pipeline::DeformRunOptions options;
            options.driver_name = driver_name;
            options.driver = driver;
            options.grid = {.cell_voxels = cell_voxels, .full_box = full_box};
            options.mesh = mesh.value_or(std::filesystem::path());
            options.body = body_options_from(kwargs);
            options.frames = frames;
            options.fps = fps;
            options.out = out;
            options.video = video.value_or(std::filesystem::path());
            options.still = still.value_or(std::filesystem::path());
            options.size = {size.first, size.second};
            options.camera = camera;
            options.shading = shading;
            options.step = step;
            options.thin_levels = thin_levels;
            if (progress) {
                options.progress = [&progress](int done, int total, double ms) {
                    py::gil_scoped_acquire gil;
                    progress(done, total, ms);
                };
            }
            nlohmann::ordered_json result;
            {
                py::gil_scoped_release release;
                result = pipeline::run_deform(source, tf, options);
            }
            return to_python(result);
        },
        py::arg("source"), py::arg("out"), py::arg("tf") = py::none(), py::kw_only(),
        py::arg("driver"), py::arg("frames") = 48, py::arg("fps") = 24.0,
        py::arg("video") = py::none(), py::arg("still") = py::none(),
        py::arg("size") = std::pair<int, int>(512, 512),
        py::arg("camera") = std::array<double, 3>{30.0, 20.0, 0.0}, py::arg("shading") = false,
        py::arg("step") = 0.0, py::arg("cell_voxels") = 4, py::arg("full_box") = false,
        py::arg("mesh") = py::none(), py::arg("driver_name") = "python",
        py::arg("progress") = py::none(),
        py::arg("thin_levels") = pipeline::DeformRunOptions{}.thin_levels,
        (std::string(
             "What `pliant deform` does: `frames` steps of 1/fps s under `driver`, the "
             "last frame resampled into the volume file `out` (written); `video` (MP4) and `still` "
             "(PNG) rendered with the orbit camera (azimuth, elevation, distance; 0: "
             "framed); an rgba8 source's faint haze sampled once per 2^thin_levels steps "
             "(0: every step; default 2). Returns the command's JSON as a dict. Releases the "
             "GIL.") +
         BODY_OPTIONS_DOC)
            .c_str());
}

}  // namespace pliant::python
