#include "pliant/pipeline/garment_scene.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/pipeline/cloth_run.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"

namespace pliant::pipeline {
namespace {

constexpr double PI = std::numbers::pi;

// The body's profile: (height m, radius m), bottom to top.
constexpr std::array<std::array<double, 2>, 9> BODY_PROFILE{{
    {0.30, 0.150},
    {0.60, 0.165},
    {0.80, 0.180},  // hips
    {0.92, 0.165},
    {1.02, 0.130},  // waist
    {1.15, 0.135},
    {1.30, 0.160},  // chest
    {1.42, 0.140},
    {1.48, 0.090},
}};
constexpr int BODY_SEGMENTS = 48;

// The skirt: a cone's frustum from the waistband (top) to the hem.
constexpr double SKIRT_TOP_Z = 1.04;
constexpr double SKIRT_TOP_RADIUS = 0.15;
constexpr double SKIRT_BOTTOM_Z = 0.45;
constexpr double SKIRT_BOTTOM_RADIUS = 0.30;
// Each panel leaves this angle (radians) open at either side: the seams close it.
constexpr double SEAM_GAP_ANGLE = 0.04;
constexpr double SEW_SECONDS = 0.1;

void write_text(const std::filesystem::path& path, const std::string& text) {
    io::write_file_atomically(path, [&](std::ostream& out) {
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
    });
}

std::string body_obj() {
    std::string obj = "# pliant's built-in mannequin: a closed surface of revolution (metres)\n";
    auto out = std::back_inserter(obj);
    for (const auto& [z, r] : BODY_PROFILE) {
        for (int s = 0; s < BODY_SEGMENTS; ++s) {
            const double phi = 2.0 * PI * s / BODY_SEGMENTS;
            fmt::format_to(out, "v {:.6f} {:.6f} {:.6f}\n", r * std::cos(phi), r * std::sin(phi),
                           z);
        }
    }
    const int rings = static_cast<int>(BODY_PROFILE.size());
    fmt::format_to(out, "v 0 0 {}\nv 0 0 {}\n", BODY_PROFILE.front()[0], BODY_PROFILE.back()[0]);
    const int bottom = rings * BODY_SEGMENTS + 1;  // 1-based
    const int top = bottom + 1;
    const auto at = [](int ring, int s) {
        return ring * BODY_SEGMENTS + (s % BODY_SEGMENTS) + 1;
    };
    for (int ring = 0; ring + 1 < rings; ++ring) {
        for (int s = 0; s < BODY_SEGMENTS; ++s) {  // outward: counter-clockwise from outside
            fmt::format_to(out, "f {} {} {} {}\n", at(ring, s), at(ring, s + 1),
                           at(ring + 1, s + 1), at(ring + 1, s));
        }
    }
    for (int s = 0; s < BODY_SEGMENTS; ++s) {
        fmt::format_to(out, "f {} {} {}\n", bottom, at(0, s + 1), at(0, s));
        fmt::format_to(out, "f {} {} {}\n", top, at(rings - 1, s), at(rings - 1, s + 1));
    }
    return obj;
}

struct Skirt {
    std::string obj;
    std::vector<int> seam_a;  // 0-based vertex indices
    std::vector<int> seam_b;
};

// Front panel (y < 0) and back panel (y > 0), vertex (i, j) at angle step i around and step j
// down; their side columns sewn: the front's last column to the back's first (x > 0 side) and
// the front's first to the back's last (x < 0 side).
Skirt skirt_obj(const SkirtOptions& o) {
    Skirt skirt;
    auto out = std::back_inserter(skirt.obj);
    fmt::format_to(out,
                   "# pliant's built-in A-line skirt: two panels (metres)\nmtllib skirt.mtl\n"
                   "o skirt\n");
    const int nu = o.quads_around;
    const int nv = o.quads_down;
    const double span = PI - 2.0 * SEAM_GAP_ANGLE;
    const double slant =
        std::hypot(SKIRT_TOP_Z - SKIRT_BOTTOM_Z, SKIRT_BOTTOM_RADIUS - SKIRT_TOP_RADIUS);
    // The developed cone: distance from the apex s = r · slant / (r_bottom - r_top), angle
    // ψ = φ · (r_bottom - r_top) / slant.
    const double k = (SKIRT_BOTTOM_RADIUS - SKIRT_TOP_RADIUS) / slant;
    const double s_max = SKIRT_BOTTOM_RADIUS / k;
    const auto index = [&](int panel, int i, int j) {
        return panel * (nu + 1) * (nv + 1) + j * (nu + 1) + i;
    };
    for (int panel = 0; panel < 2; ++panel) {
        const double first = panel == 0 ? PI + SEAM_GAP_ANGLE : SEAM_GAP_ANGLE;
        for (int j = 0; j <= nv; ++j) {
            const double v = static_cast<double>(j) / nv;
            const double z = SKIRT_TOP_Z + (SKIRT_BOTTOM_Z - SKIRT_TOP_Z) * v;
            const double r = SKIRT_TOP_RADIUS + (SKIRT_BOTTOM_RADIUS - SKIRT_TOP_RADIUS) * v;
            for (int i = 0; i <= nu; ++i) {
                const double phi = first + span * i / nu;
                fmt::format_to(out, "v {:.6f} {:.6f} {:.6f}\n", r * std::cos(phi),
                               r * std::sin(phi), z);
            }
        }
    }
    for (int j = 0; j <= nv; ++j) {  // the flat pattern, shared by both panels
        const double r = SKIRT_TOP_RADIUS + (SKIRT_BOTTOM_RADIUS - SKIRT_TOP_RADIUS) * j / nv;
        const double s = r / k;
        for (int i = 0; i <= nu; ++i) {
            const double psi = (span * i / nu - 0.5 * span) * k;
            fmt::format_to(out, "vt {:.6f} {:.6f}\n", 0.5 + 0.5 * s * std::sin(psi) / s_max,
                           1.0 - s * std::cos(psi) / s_max);
        }
    }
    for (int panel = 0; panel < 2; ++panel) {
        fmt::format_to(out, "g {}\nusemtl {}\ns 1\n", panel == 0 ? "front" : "back",
                       panel == 0 ? "cotton_front" : "cotton_back");
        for (int j = 0; j < nv; ++j) {
            for (int i = 0; i < nu; ++i) {
                // Outward normals: (i, j) → (i, j + 1) → (i + 1, j + 1) → (i + 1, j).
                const std::array<std::array<int, 2>, 4> c{
                    {{i, j}, {i, j + 1}, {i + 1, j + 1}, {i + 1, j}}};
                fmt::format_to(out, "f");
                for (const auto& [ci, cj] : c) {
                    fmt::format_to(out, " {}/{}", index(panel, ci, cj) + 1, cj * (nu + 1) + ci + 1);
                }
                fmt::format_to(out, "\n");
            }
        }
    }
    for (int j = 0; j <= nv; ++j) {
        skirt.seam_a.push_back(index(0, nu, j));
        skirt.seam_b.push_back(index(1, 0, j));
    }
    for (int j = 0; j <= nv; ++j) {
        skirt.seam_a.push_back(index(0, 0, j));
        skirt.seam_b.push_back(index(1, nu, j));
    }
    return skirt;
}

std::string int_list(const std::vector<int>& v) {
    std::string s;
    for (std::size_t k = 0; k < v.size(); ++k) {
        s += fmt::format("{}{}", k ? ", " : "", v[k]);
    }
    return s;
}

}  // namespace

std::filesystem::path write_skirt_scene(const std::filesystem::path& dir,
                                        const SkirtOptions& options) {
    io::make_output_directory(dir);
    const Skirt skirt = skirt_obj(options);
    write_text(dir / "skirt.obj", skirt.obj);
    write_text(dir / "skirt.mtl",
               "newmtl cotton_front\nKd 0.70 0.20 0.25\n"
               "newmtl cotton_back\nKd 0.60 0.15 0.20\n");
    write_text(dir / "body.obj", body_obj());
    const std::string scene = fmt::format(
        R"({{
  "cloth": {{"mesh": "skirt.obj", "units": "m"}},
  "material": {{"preset": "cotton", "thickness": 0.005}},
  "seams": [{{"a": [{}], "b": [{}], "seconds": {}}}],
  "obstacles": [{{
    "mesh": {{"file": "body.obj"}},
    "motion": {{"pivot": [0, 0, 0], "keyframes": [
      {{"time": 1.0, "rotate_degrees": [0, 0, 0]}},
      {{"time": 2.0, "rotate_degrees": [0, 0, 40]}},
      {{"time": 3.0, "rotate_degrees": [0, 0, -40]}},
      {{"time": 4.0, "rotate_degrees": [0, 0, 0]}}]}}
  }}],
  "fps": 24, "frames": {}, "substeps": 40,
  "output": {{"format": "obj", "point_cache": "pc2"}}
}}
)",
        int_list(skirt.seam_a), int_list(skirt.seam_b), SEW_SECONDS, options.frames);
    write_text(dir / "scene.json", scene);
    return dir / "scene.json";
}

nlohmann::ordered_json garment_demo(const std::filesystem::path& dir, int frames,
                                    const ProgressFn& progress) {
    const std::filesystem::path path = write_skirt_scene(dir);
    const cloth::ClothScene scene = read_cloth_scene(path);
    ClothRunOptions run;
    run.frames = frames;
    run.progress = progress;
    run.checkpoint_every = 0;  // a demo's short runs are not resumed
    return run_cloth_scene(scene, path.string(), dir, run);
}

}  // namespace pliant::pipeline
