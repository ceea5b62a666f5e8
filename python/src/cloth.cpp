// The cloth pipeline: scenes (read from JSON files, or built from JSON text or a dict), the
// simulation a caller steps frame by frame (pipeline::ClothSimulation), and `pliant cloth` as a
// function (pipeline::run_cloth_scene).
#include <fmt/format.h>
#include <pybind11/functional.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "common.hpp"
#include "pliant/cloth/scene.hpp"
#include "pliant/cloth/solver.hpp"
#include "pliant/pipeline/cloth_run.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"

namespace pliant::python {
namespace {

using pipeline::ClothSimulation;

// A simulation and the guard of the views of its solver's arrays: reset() rebuilds the solver.
struct PyClothSimulation {
    explicit PyClothSimulation(ClothSimulation s) : sim(std::move(s)) {}
    ClothSimulation sim;
    ViewGuard views;
};

// JSON text, or any object json.dumps accepts (a dict).
std::string json_text(const py::object& scene) {
    if (py::isinstance<py::str>(scene)) {
        return scene.cast<std::string>();
    }
    return py::module_::import("json").attr("dumps")(scene).cast<std::string>();
}

}  // namespace

void bind_cloth(py::module_& m) {
    using cloth::ClothMaterial;
    using cloth::ClothScene;

    py::class_<ClothMaterial>(m, "ClothMaterial",
                              "Cloth material (SI units); see docs/formats.md, 'Cloth scenes'.")
        .def_readwrite("areal_density", &ClothMaterial::areal_density, "kg/m^2")
        .def_readwrite("stretch_compliance", &ClothMaterial::stretch_compliance, "m/N")
        .def_readwrite("bend_compliance", &ClothMaterial::bend_compliance, "1/(N m)")
        .def_readwrite("strain_limit", &ClothMaterial::strain_limit, "unitless; inf: none")
        .def_readwrite("damping", &ClothMaterial::damping, "1/s")
        .def_readwrite("thickness", &ClothMaterial::thickness, "m")
        .def_readwrite("static_friction", &ClothMaterial::static_friction)
        .def_readwrite("kinetic_friction", &ClothMaterial::kinetic_friction)
        .def_readwrite("self_static_friction", &ClothMaterial::self_static_friction)
        .def_readwrite("self_kinetic_friction", &ClothMaterial::self_kinetic_friction);

    py::class_<ClothScene>(m, "ClothScene", R"doc(
A cloth scene (cloth::ClothScene): the cloth (a generated grid or a mesh file), pins, material,
obstacles, gravity, air, frames. Read one with read_cloth_scene(path) or build one from JSON
text or a dict with parse_cloth_scene(...) (the format of docs/formats.md, "Cloth scenes");
the attributes below can be changed before the scene is simulated.
)doc")
        .def_readwrite("frames", &ClothScene::frames)
        .def_readwrite("fps", &ClothScene::frames_per_second, "frames per second")
        .def_readwrite("substeps", &ClothScene::substeps, "substeps per frame")
        .def_readwrite("gravity", &ClothScene::gravity, "m/s^2")
        .def_readwrite("self_collision", &ClothScene::self_collision)
        .def_readwrite("untangle", &ClothScene::untangle)
        .def_readwrite("material", &ClothScene::material)
        .def_readwrite("translate", &ClothScene::translate, "m, applied to the cloth")
        .def_readwrite("rotate_degrees", &ClothScene::rotate_degrees,
                       "about x, then y, then z, before translate")
        .def_readwrite("frame_format", &ClothScene::frame_format, "'obj' or 'ply'")
        .def_property_readonly(
            "mesh", [](const ClothScene& s) { return s.mesh; },
            "The cloth's mesh file (absolute), or '' for a grid.");

    m.def("read_cloth_scene", &pipeline::read_cloth_scene, py::arg("path"),
          "Reads a scene JSON file (strict: IoError '<path>: <key>: <what>' for unknown keys, "
          "wrong types and values out of range). Mesh paths are made absolute.");
    m.def(
        "parse_cloth_scene",
        [](const py::object& scene, const std::string& name, const std::filesystem::path& base) {
            return pipeline::parse_cloth_scene(json_text(scene), name, base);
        },
        py::arg("scene"), py::arg("name") = "scene", py::arg("base") = ".",
        "A scene from JSON text or a dict (the scene file's format); `name` starts error "
        "messages, `base` resolves a relative mesh path.");

    py::class_<cloth::StrainStats>(m, "StrainStats",
                                   "Edge strain against the start: epsilon = length/rest - 1.")
        .def_readonly("p90", &cloth::StrainStats::p90)
        .def_readonly("p99", &cloth::StrainStats::p99)
        .def_readonly("max", &cloth::StrainStats::max)
        .def_readonly("over_10_percent", &cloth::StrainStats::over_10_percent)
        .def_readonly("over_100_percent", &cloth::StrainStats::over_100_percent);

    py::class_<pipeline::ClothFrameCheck>(m, "ClothFrameCheck")
        .def_readonly("intersecting_pairs", &pipeline::ClothFrameCheck::intersecting_pairs,
                      "Intersecting non-adjacent triangle pairs, decided exactly.")
        .def_readonly("obstacle_intersections",
                      &pipeline::ClothFrameCheck::obstacle_intersections,
                      "Where the cloth passes into an obstacle, decided exactly: intersecting "
                      "(cloth triangle, mesh obstacle triangle) pairs and cloth triangles "
                      "reaching into an analytic obstacle.")
        .def_readonly("strain", &pipeline::ClothFrameCheck::strain)
        .def_readonly("ms", &pipeline::ClothFrameCheck::ms)
        .def("__repr__", [](const pipeline::ClothFrameCheck& c) {
            return fmt::format(
                "pliant.ClothFrameCheck(intersecting_pairs={}, obstacle_intersections={}, "
                "strain_p99={:.4f})",
                c.intersecting_pairs, c.obstacle_intersections, c.strain.p99);
        });

    using cloth::SelfCollisionStats;
    py::class_<SelfCollisionStats>(m, "SelfCollisionStats")
        .def_readonly("gather_ms", &SelfCollisionStats::gather_ms)
        .def_readonly("project_ms", &SelfCollisionStats::project_ms)
        .def_readonly("enforce_ms", &SelfCollisionStats::enforce_ms)
        .def_readonly("refit_ms", &SelfCollisionStats::refit_ms)
        .def_readonly("traverse_ms", &SelfCollisionStats::traverse_ms)
        .def_readonly("narrow_ms", &SelfCollisionStats::narrow_ms)
        .def_readonly("response_ms", &SelfCollisionStats::response_ms)
        .def_readonly("candidate_pairs", &SelfCollisionStats::candidate_pairs)
        .def_readonly("contacts", &SelfCollisionStats::contacts)
        .def_readonly("ccd_hits", &SelfCollisionStats::ccd_hits)
        .def_readonly("reverted_vertices", &SelfCollisionStats::reverted_vertices)
        .def_readonly("gathers", &SelfCollisionStats::gathers);

    py::class_<cloth::ClothStepStats>(m, "ClothStepStats")
        .def_readonly("ms", &cloth::ClothStepStats::ms, "Wall time of the step.")
        .def_readonly("solve_ms", &cloth::ClothStepStats::solve_ms)
        .def_readonly("obstacle_contacts", &cloth::ClothStepStats::obstacle_contacts)
        .def_readonly("obstacle_swept_contacts", &cloth::ClothStepStats::obstacle_swept_contacts)
        .def_readonly("obstacle_edge_contacts", &cloth::ClothStepStats::obstacle_edge_contacts)
        .def_readonly("obstacle_max_step", &cloth::ClothStepStats::obstacle_max_step)
        .def_readonly("obstacles_lagging", &cloth::ClothStepStats::obstacles_lagging)
        .def_readonly("obstacle_max_lag", &cloth::ClothStepStats::obstacle_max_lag)
        .def_readonly("has_self_collision", &cloth::ClothStepStats::has_self_collision)
        .def_readonly("self_collision", &cloth::ClothStepStats::self)
        .def("__repr__", [](const cloth::ClothStepStats& s) {
            return fmt::format("pliant.ClothStepStats(ms={:.1f}, contacts={})", s.ms,
                               s.self.contacts);
        });

    py::class_<PyClothSimulation>(m, "ClothSimulation", R"doc(
A cloth scene as a simulation driven frame by frame (pipeline::ClothSimulation): what
`pliant cloth` and the viewer run.

    sim = pliant.ClothSimulation.from_file("scenes/drape.json")
    for f in range(sim.scene.frames):
        sim.step()                          # one frame: 1/fps s in `substeps` substeps
        print(sim.check().intersecting_pairs)
    x = sim.positions                       # (N, 3) float64 view, m

positions, velocities, inverse_masses and triangles are read-only views of the solver's memory
(no copy): they follow the simulation as it steps (keep a frame with .copy()). reset() rebuilds
the solver, so it raises InvalidInput while such a view is alive. Not thread-safe.
)doc")
        .def(py::init([](ClothScene scene, std::string name, std::uint64_t max_memory_bytes) {
                 py::gil_scoped_release release;
                 return std::make_unique<PyClothSimulation>(ClothSimulation::from_scene(
                     std::move(scene), std::move(name), {.max_memory_bytes = max_memory_bytes}));
             }),
             py::arg("scene"), py::arg("name") = "scene", py::arg("max_memory_bytes") = 0,
             "Builds the solver (reads the mesh files the scene names) and prepares the start: "
             "cloth that starts intersecting itself is untangled when the scene says so. "
             "`name` starts messages. InvalidInput / IoError for a scene that cannot be built.")
        .def_static(
            "from_file",
            [](const std::filesystem::path& path, std::uint64_t max_memory_bytes) {
                py::gil_scoped_release release;
                return std::make_unique<PyClothSimulation>(
                    ClothSimulation::from_scene(pipeline::read_cloth_scene(path), path.string(),
                                                {.max_memory_bytes = max_memory_bytes}));
            },
            py::arg("path"), py::arg("max_memory_bytes") = 0,
            "read_cloth_scene(path), then the simulation of it.")
        .def(
            "step", [](PyClothSimulation& s) { return s.sim.step(); },
            py::call_guard<py::gil_scoped_release>(),
            "Advances one frame (1/fps s in the scene's substeps); returns its ClothStepStats. "
            "InvalidInput when the simulation diverged. Releases the GIL.")
        .def(
            "check", [](const PyClothSimulation& s) { return s.sim.check(); },
            py::call_guard<py::gil_scoped_release>(),
            "Exact intersecting-pair count and edge strain of the current positions.")
        .def(
            "reset",
            [](PyClothSimulation& s) {
                s.views.check_none_alive("ClothSimulation.reset");
                py::gil_scoped_release release;
                s.sim.reset();
            },
            "Back to the prepared start, frame 0. InvalidInput while a view of positions, "
            "velocities, inverse_masses or triangles is alive (the solver is rebuilt).")
        .def_property_readonly("frame", [](const PyClothSimulation& s) { return s.sim.frame(); })
        .def_property_readonly(
            "time", [](const PyClothSimulation& s) { return s.sim.time(); }, "s since the start")
        .def_property_readonly(
            "scene", [](const PyClothSimulation& s) { return s.sim.scene(); }, "A copy.")
        .def_property_readonly("name", [](const PyClothSimulation& s) { return s.sim.name(); })
        .def_property_readonly(
            "initial_intersections",
            [](const PyClothSimulation& s) { return s.sim.start().initial_intersections; },
            "Intersecting pairs of the cloth as given, before untangling.")
        .def_property_readonly("num_vertices",
                               [](const PyClothSimulation& s) { return s.sim.positions().size(); })
        .def_property_readonly("num_triangles",
                               [](const PyClothSimulation& s) { return s.sim.triangles().size(); })
        .def_property_readonly(
            "positions",
            [](const py::object& self) {
                auto& s = self.cast<PyClothSimulation&>();
                return guarded_vec3_view(s.sim.positions(), self, s.views);
            },
            "(N, 3) float64 read-only view of the solver's positions (m, no copy).")
        .def_property_readonly(
            "velocities",
            [](const py::object& self) {
                auto& s = self.cast<PyClothSimulation&>();
                return guarded_vec3_view(s.sim.solver().velocities(), self, s.views);
            },
            "(N, 3) float64 read-only view of the velocities (m/s, no copy).")
        .def_property_readonly(
            "inverse_masses",
            [](const py::object& self) {
                auto& s = self.cast<PyClothSimulation&>();
                const std::span<const double> w = s.sim.solver().inverse_masses();
                return guarded_view(w.data(), w.size(), 0, self, s.views);
            },
            "(N,) float64 read-only view of the inverse masses (1/kg; 0: pinned or grabbed).")
        .def_property_readonly(
            "triangles",
            [](const py::object& self) {
                auto& s = self.cast<PyClothSimulation&>();
                const std::span<const geometry::Triangle> t = s.sim.triangles();
                return guarded_view(t.empty() ? nullptr : t.data()->data(), t.size(), 3, self,
                                    s.views);
            },
            "(T, 3) int32 read-only view of the triangles (no copy).")
        .def(
            "set_velocities",
            [](PyClothSimulation& s, const DoubleArray& velocities) {
                s.sim.solver().set_velocities(
                    vec3d_rows(velocities, "ClothSimulation.set_velocities: velocities"));
            },
            py::arg("velocities"), "Replaces the velocities ((N, 3), m/s).")
        .def(
            "grab",
            [](PyClothSimulation& s, std::int32_t vertex, const Vec3d& target) {
                s.sim.solver().grab(vertex, target);
            },
            py::arg("vertex"), py::arg("target"),
            "Makes `vertex` kinematic and moves it to `target` (m) over the next step.")
        .def(
            "release_grab", [](PyClothSimulation& s) { s.sim.solver().release_grab(); },
            "Ends the grab: the vertex gets its mass back.")
        .def("__repr__", [](const PyClothSimulation& s) {
            return fmt::format("pliant.ClothSimulation('{}', {} vertices, {} triangles, frame {})",
                               s.sim.name(), s.sim.positions().size(), s.sim.triangles().size(),
                               s.sim.frame());
        });

    m.def(
        "run_cloth",
        [](const ClothScene& scene, const std::filesystem::path& out,
           const std::optional<int>& frames, const std::string& name, bool preview,
           std::pair<int, int> preview_size, std::uint64_t max_memory_bytes,
           const std::function<void(int, int, double)>& progress) {
            pipeline::ClothRunOptions options;
            options.frames = frames.value_or(scene.frames);
            options.preview = preview;
            options.preview_width = preview_size.first;
            options.preview_height = preview_size.second;
            options.max_memory_bytes = max_memory_bytes;
            // Ctrl-C stops the run after the frame in progress (pliant.Interrupted).
            options.keep_going = [] {
                py::gil_scoped_acquire gil;
                if (PyErr_CheckSignals() != 0) {
                    PyErr_Clear();
                    return false;
                }
                return true;
            };
            if (progress) {
                options.progress = [&progress](int done, int total, double ms) {
                    py::gil_scoped_acquire gil;
                    progress(done, total, ms);
                };
            }
            nlohmann::ordered_json stats;
            {
                py::gil_scoped_release release;
                stats = pipeline::run_cloth_scene(scene, name, out, options);
            }
            return to_python(stats);
        },
        py::arg("scene"), py::arg("out"), py::arg("frames") = py::none(), py::kw_only(),
        py::arg("name") = "scene", py::arg("preview") = true,
        py::arg("preview_size") = std::pair<int, int>(640, 480), py::arg("max_memory_bytes") = 0,
        py::arg("progress") = nullptr,
        "What `pliant cloth` does: simulates `frames` frames (None: the scene's) into the "
        "directory `out` (frames/, stats.json, preview.mp4) and returns stats.json as a dict. "
        "progress(done, total, ms_per_frame) is called after every frame. Ctrl-C stops after "
        "the frame in progress and raises pliant.Interrupted. Releases the GIL.");
}

}  // namespace pliant::python
