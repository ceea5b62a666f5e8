// Cloth scene JSON; the format is in docs/formats.md, the contract in cloth_scene.hpp.
#include "pliant/pipeline/cloth_scene_file.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <string>

#include "pliant/cloth/material_preset.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/json_text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::pipeline {
namespace {

using Json = nlohmann::json;

using io::json_type_name;

// One JSON object being read: every key must be taken exactly by one of the get functions, and
// finish() rejects keys nobody took. Errors name the file and the key path.
// Bounds on the magnitude of a scene vector's nonzero components (see vector_value).
constexpr double MIN_VECTOR_COMPONENT = 1e-30;
constexpr double MAX_VECTOR_COMPONENT = MAX_SCENE_COORDINATE;
// make_grid_sheet's limit per side (geometry/generate.hpp).
constexpr std::int64_t MAX_GRID_QUADS_PER_SIDE = 16384;

// v as an integer when it is a JSON integer within [lo, hi], else nothing. Unsigned values above
// INT64_MAX are compared as they are, not wrapped by get<std::int64_t>().
std::optional<std::int64_t> integer_in(const Json& v, std::int64_t lo, std::int64_t hi) {
    if (v.is_number_unsigned()) {
        const auto u = v.get<std::uint64_t>();
        if (hi < 0 || u > static_cast<std::uint64_t>(hi)) {
            return std::nullopt;
        }
        const auto x = static_cast<std::int64_t>(u);
        return x >= lo ? std::optional<std::int64_t>(x) : std::nullopt;
    }
    if (v.is_number_integer()) {
        const auto x = v.get<std::int64_t>();
        return x >= lo && x <= hi ? std::optional<std::int64_t>(x) : std::nullopt;
    }
    return std::nullopt;
}

class ObjectReader {
public:
    ObjectReader(const Json& object, std::string name, std::string path)
        : m_object(object), m_name(std::move(name)), m_path(std::move(path)) {
        if (!object.is_object()) {
            fail(m_path.empty() ? "the scene" : m_path, "an object", json_type_name(object));
        }
    }

    [[noreturn]] void fail(const std::string& key, const std::string& expected,
                           const std::string& got) const {
        throw IoError(fmt::format("{}: {}: expected {}, got {}", m_name, key, expected, got));
    }

    std::string key_path(const std::string& key) const {
        return m_path.empty() ? key : fmt::format("{}.{}", m_path, key);
    }

    const Json* find(const std::string& key) {
        m_known.insert(key);
        const auto it = m_object.find(key);
        return it == m_object.end() ? nullptr : &*it;
    }

    bool has(const std::string& key) const { return m_object.contains(key); }

    double number(const std::string& key, double fallback, double lo, double hi) {
        const Json* value = find(key);
        if (value == nullptr) {
            return fallback;
        }
        if (!value->is_number()) {
            fail(key_path(key), "a number", json_type_name(*value));
        }
        const double x = value->get<double>();
        if (!(x >= lo && x <= hi)) {
            fail(key_path(key), fmt::format("a number in [{}, {}]", lo, hi), fmt::format("{}", x));
        }
        return x;
    }

    // As number(), and `null` gives if_null.
    double nullable_number(const std::string& key, double fallback, double lo, double hi,
                           double if_null) {
        const Json* value = find(key);
        if (value != nullptr && value->is_null()) {
            return if_null;
        }
        return number(key, fallback, lo, hi);
    }

    int integer(const std::string& key, int fallback, int lo, int hi) {
        const Json* value = find(key);
        if (value == nullptr) {
            return fallback;
        }
        if (!value->is_number_integer()) {  // true for unsigned values too
            fail(key_path(key), "an integer", json_type_name(*value));
        }
        const std::optional<std::int64_t> x = integer_in(*value, lo, hi);
        if (!x) {
            fail(key_path(key), fmt::format("an integer in [{}, {}]", lo, hi), value->dump());
        }
        return static_cast<int>(*x);
    }

    Vec3d vector(const std::string& key, const Vec3d& fallback) {
        const Json* value = find(key);
        if (value == nullptr) {
            return fallback;
        }
        return vector_value(*value, key_path(key));
    }

    Vec3d required_vector(const std::string& key) {
        if (!has(key)) {
            fail(key_path(key), "a required [x, y, z] array", "nothing");
        }
        return vector(key, {});
    }

    Vec3d vector_value(const Json& value, const std::string& where) const {
        if (!value.is_array() || value.size() != 3) {
            fail(where, "an array of 3 numbers",
                 json_type_name(value) +
                     (value.is_array() ? fmt::format(" of {} elements", value.size()) : ""));
        }
        double c[3];
        for (std::size_t k = 0; k < 3; ++k) {
            if (!value[k].is_number() || !std::isfinite(value[k].get<double>())) {
                fail(fmt::format("{}[{}]", where, k), "a finite number", json_type_name(value[k]));
            }
            c[k] = value[k].get<double>();
            // Scene vectors are positions (m), velocities, accelerations and angles: beyond
            // these bounds they are mistakes, and the exact predicates' domain (below 1e-90 or
            // above 1e90) is left in the first steps.
            const double magnitude = std::abs(c[k]);
            if (magnitude != 0.0 &&
                !(magnitude >= MIN_VECTOR_COMPONENT && magnitude <= MAX_VECTOR_COMPONENT)) {
                fail(fmt::format("{}[{}]", where, k),
                     fmt::format("0 or a magnitude in [{}, {}]", MIN_VECTOR_COMPONENT,
                                 MAX_VECTOR_COMPONENT),
                     value[k].dump());
            }
        }
        return {c[0], c[1], c[2]};
    }

    std::string text(const std::string& key, const std::string& fallback,
                     const std::set<std::string>& allowed) {
        const Json* value = find(key);
        if (value == nullptr) {
            return fallback;
        }
        if (!value->is_string() || allowed.count(value->get<std::string>()) == 0) {
            std::string list;
            for (const std::string& a : allowed) {
                list += fmt::format("{}\"{}\"", list.empty() ? "" : ", ", a);
            }
            fail(key_path(key), fmt::format("one of {}", list),
                 value->is_string() ? fmt::format("\"{}\"", value->get<std::string>())
                                    : json_type_name(*value));
        }
        return value->get<std::string>();
    }

    // Calls read(reader) on the object at key, when present.
    bool object(const std::string& key, const std::function<void(ObjectReader&)>& read) {
        const Json* value = find(key);
        if (value == nullptr) {
            return false;
        }
        ObjectReader inner(*value, m_name, key_path(key));
        read(inner);
        inner.finish();
        return true;
    }

    const Json* array(const std::string& key) {
        const Json* value = find(key);
        if (value != nullptr && !value->is_array()) {
            fail(key_path(key), "an array", json_type_name(*value));
        }
        return value;
    }

    const std::string& name() const { return m_name; }

    // A key as it can be printed: JSON-escaped and quoted when it holds control characters (a
    // NUL would cut the error message short).
    static std::string printable_key(const std::string& key) {
        const bool plain = std::none_of(key.begin(), key.end(), [](char c) {
            return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
        });
        return plain ? key : Json(key).dump(-1, ' ', false, Json::error_handler_t::replace);
    }

    void finish() const {
        for (const auto& [key, value] : m_object.items()) {
            if (m_known.count(key) == 0) {
                std::string list;
                for (const std::string& k : m_known) {
                    list += fmt::format("{}{}", list.empty() ? "" : ", ", k);
                }
                fail(key_path(printable_key(key)), fmt::format("a known key ({})", list),
                     "an unknown key");
            }
        }
    }

private:
    const Json& m_object;
    std::string m_name;
    std::string m_path;
    std::set<std::string> m_known;
};

constexpr double HUGE_VALUE = 1e12;

// Starts the scene's fabric from a preset (material_preset.hpp): its density and stiffnesses.
void apply_preset(ObjectReader& r, const std::string& key, const std::string& name,
                  cloth::ClothScene& scene) {
    const std::optional<cloth::FabricProperties> fabric = cloth::fabric_preset(name);
    if (!fabric) {
        std::string list;
        for (const std::string& n : cloth::fabric_preset_names()) {
            list += fmt::format("{}\"{}\"", list.empty() ? "" : ", ", n);
        }
        r.fail(key, fmt::format("a material preset ({})", list), fmt::format("\"{}\"", name));
    }
    scene.material_preset = name;
    scene.material.areal_density = fabric->areal_density;
    scene.stretch_stiffness = fabric->stretch_stiffness;
    scene.bend_stiffness = fabric->bend_stiffness;
}

// A stiffness in physical units, or the compliance it replaces (not both).
void read_stiffness(ObjectReader& r, const std::string& stiffness_key,
                    const std::string& compliance_key, std::optional<double>& stiffness,
                    double& compliance) {
    if (r.has(stiffness_key) && r.has(compliance_key)) {
        r.fail(r.key_path(stiffness_key), fmt::format("either it or {}", compliance_key), "both");
    }
    if (r.has(compliance_key)) {
        compliance = r.number(compliance_key, compliance, 0.0, HUGE_VALUE);
        stiffness.reset();
    }
    if (r.has(stiffness_key)) {
        stiffness = r.number(stiffness_key, 0.0, 1e-12, HUGE_VALUE);
    }
    r.find(stiffness_key);
    r.find(compliance_key);
}

void read_material(ObjectReader& r, cloth::ClothScene& scene) {
    cloth::ClothMaterial& m = scene.material;
    if (const Json* preset = r.find("preset")) {
        if (!preset->is_string()) {
            r.fail(r.key_path("preset"), "a material preset name", json_type_name(*preset));
        }
        apply_preset(r, r.key_path("preset"), preset->get<std::string>(), scene);
    }
    m.areal_density = r.number("areal_density", m.areal_density, 1e-9, HUGE_VALUE);
    read_stiffness(r, "stretch_stiffness", "stretch_compliance", scene.stretch_stiffness,
                   m.stretch_compliance);
    read_stiffness(r, "bend_stiffness", "bend_compliance", scene.bend_stiffness, m.bend_compliance);
    const bool dihedral = m.bending == cloth::BendingModel::dihedral;
    m.bending = r.text("bending", dihedral ? "dihedral" : "isometric", {"dihedral", "isometric"}) ==
                        "dihedral"
                    ? cloth::BendingModel::dihedral
                    : cloth::BendingModel::isometric;
    const bool edges = m.stretch_solver == cloth::StretchSolver::edges;
    m.stretch_solver =
        r.text("stretch_solver", edges ? "edges" : "chains", {"edges", "chains"}) == "edges"
            ? cloth::StretchSolver::edges
            : cloth::StretchSolver::chains;
    m.strain_limit = r.nullable_number("strain_limit", m.strain_limit, 0.0, HUGE_VALUE,
                                       std::numeric_limits<double>::infinity());
    m.damping = r.number("damping", m.damping, 0.0, HUGE_VALUE);
    m.thickness = r.number("thickness", m.thickness, 0.0, HUGE_VALUE);
    m.static_friction = r.number("static_friction", m.static_friction, 0.0, HUGE_VALUE);
    m.kinetic_friction = r.number("kinetic_friction", m.kinetic_friction, 0.0, HUGE_VALUE);
    m.self_static_friction =
        r.number("self_static_friction", m.self_static_friction, 0.0, HUGE_VALUE);
    m.self_kinetic_friction =
        r.number("self_kinetic_friction", m.self_kinetic_friction, 0.0, HUGE_VALUE);
}

cloth::Placement read_placement(ObjectReader& r) {
    cloth::Placement placement;
    placement.rotate_degrees = r.vector("rotate_degrees", placement.rotate_degrees);
    placement.translate = r.vector("translate", placement.translate);
    return placement;
}

// {"pivot": [x, y, z], "keyframes": [{"time": t, "translate": [...], "rotate_degrees": [...]}]}
cloth::Motion read_motion(ObjectReader& r) {
    cloth::Motion motion;
    motion.pivot = r.vector("pivot", motion.pivot);
    const Json* keyframes = r.array("keyframes");
    if (keyframes == nullptr || keyframes->empty()) {
        r.fail(r.key_path("keyframes"), "a non-empty array of keyframes",
               keyframes == nullptr ? "nothing" : "an empty array");
    }
    for (std::size_t k = 0; k < keyframes->size(); ++k) {
        const std::string where = fmt::format("{}[{}]", r.key_path("keyframes"), k);
        ObjectReader key((*keyframes)[k], r.name(), where);
        cloth::Keyframe keyframe;
        if (!key.has("time")) {
            key.fail(key.key_path("time"), "a required time in seconds", "nothing");
        }
        keyframe.time = key.number("time", 0.0, -HUGE_VALUE, HUGE_VALUE);
        keyframe.translate = key.vector("translate", keyframe.translate);
        keyframe.rotate_degrees = key.vector("rotate_degrees", keyframe.rotate_degrees);
        key.finish();
        if (!motion.keyframes.empty() && !(keyframe.time > motion.keyframes.back().time)) {
            key.fail(key.key_path("time"),
                     fmt::format("a time after the previous keyframe's {}",
                                 motion.keyframes.back().time),
                     fmt::format("{}", keyframe.time));
        }
        motion.keyframes.push_back(keyframe);
    }
    return motion;
}

cloth::PinGroup read_pin_group(ObjectReader& p) {
    cloth::PinGroup group;
    if (const Json* vertices = p.array("vertices")) {
        for (std::size_t k = 0; k < vertices->size(); ++k) {
            const Json& v = (*vertices)[k];
            const std::optional<std::int64_t> index =
                integer_in(v, 0, std::numeric_limits<std::int32_t>::max());
            if (!index) {
                p.fail(fmt::format("{}[{}]", p.key_path("vertices"), k),
                       "a vertex index (integer >= 0)", v.dump());
            }
            group.vertices.push_back(static_cast<std::int32_t>(*index));
        }
    }
    if (const Json* regions = p.array("regions")) {
        for (std::size_t k = 0; k < regions->size(); ++k) {
            ObjectReader region((*regions)[k], p.name(),
                                fmt::format("{}[{}]", p.key_path("regions"), k));
            cloth::PinRegion pin{region.required_vector("min"), region.required_vector("max")};
            region.finish();
            group.regions.push_back(pin);
        }
    }
    p.object("motion", [&](ObjectReader& m) { group.motion = read_motion(m); });
    p.object("attach", [&](ObjectReader& a) {
        cloth::PinAttach attach;
        const Json* obstacle = a.find("obstacle");
        if (obstacle != nullptr && obstacle->is_string() && !obstacle->get<std::string>().empty()) {
            attach.obstacle = obstacle->get<std::string>();
        } else if (const std::optional<std::int64_t> index =
                       obstacle != nullptr ? integer_in(*obstacle, 0, 1'000'000) : std::nullopt) {
            attach.obstacle_index = *index;
        } else {
            a.fail(a.key_path("obstacle"), "an obstacle's name or its index in \"obstacles\"",
                   obstacle == nullptr ? "nothing" : obstacle->dump());
        }
        attach.max_distance = a.number("max_distance", attach.max_distance, 0.0, HUGE_VALUE);
        group.attach = attach;
    });
    if (group.attach && !group.motion.is_static()) {
        p.fail(p.key_path("attach"),
               R"(either "attach" or "motion" (attached pins follow the obstacle))", "both");
    }
    return group;
}

// One side of a seam: vertex indices, or {"from": i, "to": j} (i, i ± 1, …, j inclusive).
std::vector<std::int32_t> read_seam_side(ObjectReader& r, const std::string& key) {
    const Json* side = r.find(key);
    const std::string where = r.key_path(key);
    if (side == nullptr) {
        r.fail(where, R"(a required list of vertex indices or {"from": i, "to": j})", "nothing");
    }
    std::vector<std::int32_t> out;
    constexpr std::int64_t MAX_INDEX = std::numeric_limits<std::int32_t>::max();
    if (side->is_array()) {
        for (std::size_t k = 0; k < side->size(); ++k) {
            const std::optional<std::int64_t> v = integer_in((*side)[k], 0, MAX_INDEX);
            if (!v) {
                r.fail(fmt::format("{}[{}]", where, k), "a vertex index (an integer >= 0)",
                       (*side)[k].dump());
            }
            out.push_back(static_cast<std::int32_t>(*v));
        }
    } else if (side->is_object()) {
        ObjectReader range(*side, r.name(), where);
        const std::int64_t from = range.integer("from", -1, 0, std::numeric_limits<int>::max());
        const std::int64_t to = range.integer("to", -1, 0, std::numeric_limits<int>::max());
        if (!range.has("from") || !range.has("to")) {
            r.fail(where, R"(both "from" and "to")", range.has("from") ? "only from" : "not from");
        }
        range.finish();
        if (std::abs(to - from) >= 10'000'000) {
            r.fail(where, "a range of at most 10,000,000 vertices",
                   fmt::format("{} to {}", from, to));
        }
        const std::int64_t step = to >= from ? 1 : -1;
        for (std::int64_t v = from;; v += step) {
            out.push_back(static_cast<std::int32_t>(v));
            if (v == to) {
                break;
            }
        }
    } else {
        r.fail(where, R"(a list of vertex indices or {"from": i, "to": j})", json_type_name(*side));
    }
    if (out.empty()) {
        r.fail(where, "at least one vertex", "an empty list");
    }
    return out;
}

cloth::SceneSeam read_seam(ObjectReader& r) {
    cloth::SceneSeam seam;
    seam.a = read_seam_side(r, "a");
    seam.b = read_seam_side(r, "b");
    if (seam.a.size() != seam.b.size()) {
        r.fail(r.key_path("b"), fmt::format("as many vertices as a ({})", seam.a.size()),
               fmt::format("{}", seam.b.size()));
    }
    seam.seconds = r.number("seconds", seam.seconds, 1e-6, 1e6);
    return seam;
}

cloth::Air read_air(ObjectReader& r) {
    cloth::Air air;
    air.density = r.number("density", 1.2, 0.0, HUGE_VALUE);
    air.drag_coefficient = r.number("drag_coefficient", air.drag_coefficient, 0.0, HUGE_VALUE);
    air.wind = r.vector("wind", air.wind);
    air.gust_amplitude = r.number("gust_amplitude", air.gust_amplitude, 0.0, HUGE_VALUE);
    air.gust_period = r.number("gust_period", air.gust_period, 1e-9, HUGE_VALUE);
    air.gust_wavelength = r.number("gust_wavelength", air.gust_wavelength, 1e-9, HUGE_VALUE);
    return air;
}

cloth::SceneObstacle read_obstacle(const Json& value, const std::string& name,
                                   const std::string& path, const std::filesystem::path& base) {
    ObjectReader r(value, name, path);
    cloth::SceneObstacle scene_obstacle;
    cloth::Obstacle& obstacle = scene_obstacle.shape;
    int kinds = 0;
    kinds += r.object("plane", [&](ObjectReader& o) {
        cloth::PlaneObstacle plane;
        plane.point = o.vector("point", plane.point);
        plane.normal = o.vector("normal", plane.normal);
        if (!(squared_norm(plane.normal) > 0.0)) {
            o.fail(o.key_path("normal"), "a nonzero vector", "[0, 0, 0]");
        }
        obstacle = plane;
    });
    kinds += r.object("sphere", [&](ObjectReader& o) {
        cloth::SphereObstacle sphere;
        sphere.center = o.vector("center", sphere.center);
        sphere.radius = o.number("radius", sphere.radius, 1e-12, HUGE_VALUE);
        obstacle = sphere;
    });
    kinds += r.object("box", [&](ObjectReader& o) {
        cloth::BoxObstacle box;
        box.min = o.required_vector("min");
        box.max = o.required_vector("max");
        if (!(box.min.x < box.max.x && box.min.y < box.max.y && box.min.z < box.max.z)) {
            o.fail(o.key_path("max"), "max > min on every axis",
                   fmt::format("min ({}, {}, {}), max ({}, {}, {})", box.min.x, box.min.y,
                               box.min.z, box.max.x, box.max.y, box.max.z));
        }
        obstacle = box;
    });
    kinds += r.object("mesh", [&](ObjectReader& o) {
        const auto relative = [&](const std::string& file_name) {
            const std::filesystem::path given(file_name);
            return given.is_absolute() ? given : base / given;
        };
        const Json* file = o.find("file");
        const Json* frames = o.find("frames");
        if (frames != nullptr) {
            // A deforming mesh: a pattern or a list of files.
            if (file != nullptr) {
                o.fail(o.key_path("frames"), R"(either "file" or "frames")", "both");
            }
            if (frames->is_string() && !frames->get<std::string>().empty()) {
                scene_obstacle.frames_pattern = relative(frames->get<std::string>());
                scene_obstacle.mesh = scene_obstacle.frames_pattern;  // until expanded
            } else if (frames->is_array() && !frames->empty()) {
                for (std::size_t k = 0; k < frames->size(); ++k) {
                    const Json& f = (*frames)[k];
                    if (!f.is_string() || f.get<std::string>().empty()) {
                        o.fail(fmt::format("{}[{}]", o.key_path("frames"), k),
                               "a file name (OBJ or PLY)", json_type_name(f));
                    }
                    scene_obstacle.frames.push_back(relative(f.get<std::string>()));
                }
                scene_obstacle.mesh = scene_obstacle.frames.front();
            } else {
                o.fail(o.key_path("frames"),
                       R"(a file pattern ("body/frame_%04d.obj") or a non-empty list of files)",
                       frames->dump());
            }
            scene_obstacle.frames_fps = o.number("fps", 0.0, 1e-3, 1e6);
            scene_obstacle.frame_start = o.integer("start", -1, 0, 100'000'000);
            scene_obstacle.frame_count = o.integer("count", 0, 1, 1'000'000);
            if (const Json* loop = o.find("loop")) {
                if (!loop->is_boolean()) {
                    o.fail(o.key_path("loop"), "true or false", json_type_name(*loop));
                }
                scene_obstacle.loop = loop->get<bool>();
            }
        } else {
            if (file == nullptr || !file->is_string() || file->get<std::string>().empty()) {
                o.fail(o.key_path("file"), "a file name (OBJ or PLY)",
                       file == nullptr ? "nothing" : json_type_name(*file));
            }
            scene_obstacle.mesh = relative(file->get<std::string>());
        }
        scene_obstacle.mesh_placement = read_placement(o);
    });
    if (const Json* given = r.find("name")) {
        if (!given->is_string() || given->get<std::string>().empty()) {
            r.fail(path + ".name", "a non-empty string", json_type_name(*given));
        }
        scene_obstacle.name = given->get<std::string>();
    }
    r.object("motion", [&](ObjectReader& m) { scene_obstacle.motion = read_motion(m); });
    r.finish();
    if (kinds != 1) {
        r.fail(path, R"(exactly one of "plane", "sphere", "box", "mesh")",
               fmt::format("{} of them", kinds));
    }
    if (std::holds_alternative<cloth::BoxObstacle>(obstacle) && scene_obstacle.mesh.empty() &&
        scene_obstacle.motion.rotates()) {
        r.fail(path + ".motion", "no rotation (boxes stay axis-aligned; use a mesh to turn one)",
               "a rotating keyframe");
    }
    return scene_obstacle;
}

// Names are unique; each attached pin group names an obstacle that is a mesh (by name or index),
// resolved to its index.
void resolve_attachments(cloth::ClothScene& scene, const std::string& file) {
    for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
        for (std::size_t j = 0; j < k; ++j) {
            if (!scene.obstacles[k].name.empty() &&
                scene.obstacles[k].name == scene.obstacles[j].name) {
                throw IoError(fmt::format(
                    "{}: obstacles[{}].name: expected a name no other obstacle has, got \"{}\" "
                    "(also obstacles[{}])",
                    file, k, scene.obstacles[k].name, j));
            }
        }
    }
    for (cloth::PinGroup& group : scene.pins) {
        if (!group.attach) {
            continue;
        }
        cloth::PinAttach& attach = *group.attach;
        if (!attach.obstacle.empty()) {
            const auto found = std::find_if(
                scene.obstacles.begin(), scene.obstacles.end(),
                [&](const cloth::SceneObstacle& o) { return o.name == attach.obstacle; });
            if (found == scene.obstacles.end()) {
                std::string names;
                for (const cloth::SceneObstacle& o : scene.obstacles) {
                    if (!o.name.empty()) {
                        names += fmt::format("{}\"{}\"", names.empty() ? "" : ", ", o.name);
                    }
                }
                throw IoError(fmt::format(
                    "{}: {}.attach.obstacle: expected the name of an obstacle ({}), got \"{}\"",
                    file, group.key, names.empty() ? "none has a name" : names, attach.obstacle));
            }
            attach.obstacle_index = found - scene.obstacles.begin();
        }
        if (attach.obstacle_index >= static_cast<std::int64_t>(scene.obstacles.size()) ||
            scene.obstacles[static_cast<std::size_t>(attach.obstacle_index)].mesh.empty()) {
            throw IoError(fmt::format(
                "{}: {}.attach.obstacle: expected a mesh obstacle, got obstacle {} ({})", file,
                group.key, attach.obstacle_index,
                attach.obstacle_index >= static_cast<std::int64_t>(scene.obstacles.size())
                    ? fmt::format("the scene has {} obstacles", scene.obstacles.size())
                    : "an analytic shape"));
        }
    }
}

}  // namespace

cloth::ClothScene parse_cloth_scene(std::string_view text, std::string_view name,
                                    const std::filesystem::path& base) {
    const std::string file(name);
    const Json json = io::parse_json(text, file);
    cloth::ClothScene scene;
    ObjectReader root(json, file, "");

    const bool has_cloth = root.object("cloth", [&](ObjectReader& c) {
        const bool has_grid = c.object("grid", [&](ObjectReader& g) {
            cloth::GridSheet grid;
            const Json* size = g.find("size");
            if (size != nullptr) {
                if (!size->is_array() || size->size() != 2 || !(*size)[0].is_number() ||
                    !(*size)[1].is_number() || !((*size)[0].get<double>() >= 1e-6) ||
                    !((*size)[1].get<double>() >= 1e-6) || !((*size)[0].get<double>() <= 1e6) ||
                    !((*size)[1].get<double>() <= 1e6)) {
                    g.fail(g.key_path("size"), "[width, height] in metres, each in [1e-6, 1e6]",
                           size->dump());
                }
                grid.size = {(*size)[0].get<double>(), (*size)[1].get<double>()};
            }
            const Json* quads = g.find("quads");
            if (quads != nullptr) {
                // Each side in [1, MAX_GRID_QUADS_PER_SIDE] (0 when not), then the product,
                // which cannot overflow.
                const auto side = [](const Json& v) {
                    return integer_in(v, 1, MAX_GRID_QUADS_PER_SIDE).value_or(0);
                };
                const bool pair = quads->is_array() && quads->size() == 2;
                const std::int64_t nx = pair ? side((*quads)[0]) : 0;
                const std::int64_t ny = pair ? side((*quads)[1]) : 0;
                if (nx == 0 || ny == 0 || nx * ny > 50'000'000) {
                    g.fail(g.key_path("quads"),
                           fmt::format("[nx, ny], integers in [1, {}] with nx * ny <= 50,000,000",
                                       MAX_GRID_QUADS_PER_SIDE),
                           quads->dump());
                }
                grid.quads = {static_cast<int>(nx), static_cast<int>(ny)};
            }
            scene.grid = grid;
        });
        const Json* mesh = c.find("mesh");
        if (mesh != nullptr) {
            if (!mesh->is_string() || mesh->get<std::string>().empty()) {
                c.fail(c.key_path("mesh"), "a file name (OBJ or PLY)", json_type_name(*mesh));
            }
            const std::filesystem::path path(mesh->get<std::string>());
            scene.mesh = path.is_absolute() ? path : base / path;
        }
        const bool has_units = c.has("units");
        const std::string units = c.text("units", "m", {"m", "cm", "mm"});
        scene.mesh_scale = units == "cm" ? 0.01 : units == "mm" ? 0.001 : 1.0;
        if (c.has("scale")) {
            if (has_units) {
                c.fail(c.key_path("scale"), R"(either it or "units")", "both");
            }
            scene.mesh_scale = c.number("scale", 1.0, 1e-9, 1e9);
        }
        c.find("scale");
        if ((has_units || c.has("scale")) && mesh == nullptr) {
            c.fail(c.key_path(has_units ? "units" : "scale"),
                   R"(a cloth "mesh" (grids are sized in metres))", "a grid");
        }
        if (has_grid == (mesh != nullptr)) {
            c.fail("cloth", R"(exactly one of "grid" and "mesh")", has_grid ? "both" : "neither");
        }
        scene.rotate_degrees = c.vector("rotate_degrees", scene.rotate_degrees);
        scene.translate = c.vector("translate", scene.translate);
        if (const Json* instances = c.array("instances")) {
            for (std::size_t k = 0; k < instances->size(); ++k) {
                ObjectReader instance((*instances)[k], c.name(),
                                      fmt::format("{}[{}]", c.key_path("instances"), k));
                scene.instances.push_back(read_placement(instance));
                instance.finish();
            }
        }
    });
    if (!has_cloth) {
        root.fail("cloth", "a required object", "nothing");
    }

    // "pins": one group (an object) or several (an array of objects).
    if (const Json* pins = root.find("pins")) {
        if (pins->is_array()) {
            for (std::size_t k = 0; k < pins->size(); ++k) {
                ObjectReader group((*pins)[k], file, fmt::format("pins[{}]", k));
                scene.pins.push_back(read_pin_group(group));
                scene.pins.back().key = fmt::format("pins[{}]", k);
                group.finish();
            }
        } else {
            ObjectReader group(*pins, file, "pins");
            scene.pins.push_back(read_pin_group(group));
            group.finish();
        }
    }
    if (const Json* seams = root.array("seams")) {
        for (std::size_t k = 0; k < seams->size(); ++k) {
            ObjectReader seam((*seams)[k], file, fmt::format("seams[{}]", k));
            scene.seams.push_back(read_seam(seam));
            scene.seams.back().key = fmt::format("seams[{}]", k);
            seam.finish();
        }
    }
    // "material": a preset's name, or an object (optionally starting from a "preset").
    if (const Json* material = root.find("material");
        material != nullptr && material->is_string()) {
        apply_preset(root, "material", material->get<std::string>(), scene);
    } else if (material != nullptr) {
        if (!material->is_object()) {
            root.fail("material", "a material preset name or an object", json_type_name(*material));
        }
        ObjectReader m(*material, file, "material");
        read_material(m, scene);
        m.finish();
    }
    if (const Json* obstacles = root.array("obstacles")) {
        for (std::size_t k = 0; k < obstacles->size(); ++k) {
            scene.obstacles.push_back(
                read_obstacle((*obstacles)[k], file, fmt::format("obstacles[{}]", k), base));
        }
    }
    resolve_attachments(scene, file);
    for (const auto& [key, flag] : {std::pair{"self_collision", &scene.self_collision},
                                    std::pair{"untangle", &scene.untangle}}) {
        if (const Json* value = root.find(key)) {
            if (!value->is_boolean()) {
                root.fail(key, "true or false", json_type_name(*value));
            }
            *flag = value->get<bool>();
        }
    }
    if (const Json* solver = root.find("solver")) {
        // "xpbd", "vbd", or {"type": "vbd", "iterations": N, "chebyshev_rho": r}.
        if (solver->is_object()) {
            root.object("solver", [&](ObjectReader& s) {
                if (s.text("type", "vbd", {"xpbd", "vbd"}) == "vbd") {
                    cloth::VBDOptions options;
                    options.iterations = s.integer("iterations", options.iterations, 1, 10'000);
                    options.chebyshev_rho =
                        s.number("chebyshev_rho", options.chebyshev_rho, 0.0, 0.999);
                    scene.vbd = options;
                }
            });
        } else if (root.text("solver", "xpbd", {"xpbd", "vbd"}) == "vbd") {
            scene.vbd = cloth::VBDOptions{};
        }
    }
    if (const Json* contact = root.find("contact")) {
        // "proximity" (the default), "ogc", or {"type": "ogc", "radius": r, "query_factor": q,
        // "bound_share": g, "wide_query_factor": w, "redetect_share": s, "stiffness": k,
        // "audit": b} (cloth/ogc_contact.hpp), for either solver.
        std::optional<cloth::OgcOptions> ogc;
        if (contact->is_object()) {
            root.object("contact", [&](ObjectReader& c) {
                if (c.text("type", "ogc", {"proximity", "ogc"}) == "ogc") {
                    cloth::OgcOptions o;
                    o.radius = c.number("radius", o.radius, 0.0, 1e3);
                    o.query_factor = c.number("query_factor", o.query_factor, 1.0, 100.0);
                    o.bound_share = c.number("bound_share", o.bound_share, 1e-3, 0.49);
                    o.wide_query_factor =
                        c.number("wide_query_factor", o.wide_query_factor, 0.0, 100.0);
                    o.redetect_share = c.number("redetect_share", o.redetect_share, 0.0, 1.0);
                    o.stiffness = c.number("stiffness", o.stiffness, 0.0, 1e15);
                    if (const Json* audit = c.find("audit")) {
                        if (!audit->is_boolean()) {
                            c.fail("contact.audit", "true or false", json_type_name(*audit));
                        }
                        o.audit = audit->get<bool>();
                    }
                    ogc = o;
                }
            });
        } else if (root.text("contact", "proximity", {"proximity", "ogc"}) == "ogc") {
            ogc = cloth::OgcOptions{};
        }
        if (ogc && scene.vbd) {
            scene.vbd->ogc = ogc;
        } else if (ogc) {
            scene.xpbd_ogc = ogc;
        }
    }
    scene.gravity = root.vector("gravity", scene.gravity);
    root.object("air", [&](ObjectReader& a) { scene.air = read_air(a); });
    scene.frames_per_second = root.number("fps", scene.frames_per_second, 1e-3, 1e6);
    scene.frames = root.integer("frames", scene.frames, 0, 1'000'000);
    scene.substeps = root.integer("substeps", scene.substeps, 1, 100'000);
    root.object("output", [&](ObjectReader& o) {
        scene.frame_format = o.text("format", scene.frame_format, {"obj", "ply"});
        if (const Json* cache = o.find("point_cache"); cache != nullptr && !cache->is_null()) {
            scene.point_cache = o.text("point_cache", "", {"pc2", "mdd"});
        }
    });
    root.finish();
    return scene;
}

cloth::ClothScene read_cloth_scene(const std::filesystem::path& path) {
    const std::string text = io::read_file(path);
    return parse_cloth_scene(text, path.string(),
                             path.has_parent_path() ? path.parent_path() : ".");
}

}  // namespace pliant::pipeline
