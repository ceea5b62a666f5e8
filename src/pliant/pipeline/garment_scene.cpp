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
#include "pliant/pipeline/mannequin.hpp"

namespace pliant::pipeline {
namespace {

constexpr double PI = std::numbers::pi;

// The body: scripts/make-body's walking mannequin (mannequin.hpp), low poly, a walk cycle of
// BODY_FRAMES frames at BODY_FPS (1.5 s), interpolated by the solver in between.
constexpr MannequinOptions BODY{.segments = 10, .turn_degrees = 25.0, .swing_degrees = 20.0};
constexpr int BODY_FRAMES = 12;
constexpr double BODY_FPS = 8.0;

// The skirt: from the waistband (top), an ellipse just outside the torso's (0.17 m across,
// 0.1054 m deep), to the hem, a circle.
constexpr double SKIRT_TOP_Z = 1.04;
constexpr double SKIRT_TOP_A = 0.17 + 0.008;
constexpr double SKIRT_TOP_B = 0.17 * 0.62 + 0.008;
constexpr double SKIRT_BOTTOM_Z = 0.50;
constexpr double SKIRT_BOTTOM_RADIUS = 0.30;
// The panels are placed this far apart (m) at the side seams (at x = ±a), 1 mm more than the
// thickness the seams close to: the panels' rest lengths are their placed lengths, so a wider
// gap would leave the sewn skirt stretched around by it, all of it in the edges beside the seams.
constexpr double SEAM_OPENING = 0.006;
constexpr double SEW_SECONDS = 0.1;
constexpr double THICKNESS = 0.005;

void write_text(const std::filesystem::path& path, const std::string& text) {
    io::write_file_atomically(path, [&](std::ostream& out) {
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
    });
}

struct Skirt {
    std::string obj;
    std::vector<int> seam_a;  // 0-based vertex indices
    std::vector<int> seam_b;
    std::vector<int> waistband;  // the top rows, attached to the body
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
    // Row j: an ellipse of half-axes a (along x) and b (along y) at height z; each panel leaves
    // the angle gap(j) open at either side, SEAM_OPENING / 2 along the ellipse (whose speed at
    // x = ±a is b).
    const auto row = [&](int j) {
        const double v = static_cast<double>(j) / nv;
        return std::array<double, 3>{SKIRT_TOP_Z + (SKIRT_BOTTOM_Z - SKIRT_TOP_Z) * v,
                                     SKIRT_TOP_A + (SKIRT_BOTTOM_RADIUS - SKIRT_TOP_A) * v,
                                     SKIRT_TOP_B + (SKIRT_BOTTOM_RADIUS - SKIRT_TOP_B) * v};
    };
    const auto index = [&](int panel, int i, int j) {
        return panel * (nu + 1) * (nv + 1) + j * (nu + 1) + i;
    };
    for (int panel = 0; panel < 2; ++panel) {
        for (int j = 0; j <= nv; ++j) {
            const auto [z, a, b] = row(j);
            const double gap = 0.5 * SEAM_OPENING / b;
            const double first = (panel == 0 ? PI : 0.0) + gap;
            const double span = PI - 2.0 * gap;
            for (int i = 0; i <= nu; ++i) {
                const double phi = first + span * i / nu;
                fmt::format_to(out, "v {:.6f} {:.6f} {:.6f}\n", a * std::cos(phi),
                               b * std::sin(phi), z);
            }
        }
    }
    // The flat pattern, shared by both panels: the developed cone of the mean radius
    // (r = (a + b) / 2), at distance s = r · slant / (r_bottom - r_top) from the apex and angle
    // ψ = φ · (r_bottom - r_top) / slant.
    const double r_top = 0.5 * (SKIRT_TOP_A + SKIRT_TOP_B);
    const double slant = std::hypot(SKIRT_TOP_Z - SKIRT_BOTTOM_Z, SKIRT_BOTTOM_RADIUS - r_top);
    const double k = (SKIRT_BOTTOM_RADIUS - r_top) / slant;
    const double s_max = SKIRT_BOTTOM_RADIUS / k;
    for (int j = 0; j <= nv; ++j) {
        const double r = r_top + (SKIRT_BOTTOM_RADIUS - r_top) * j / nv;
        const double s = r / k;
        for (int i = 0; i <= nu; ++i) {
            const double psi = (PI * i / nu - 0.5 * PI) * k;
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
    for (int panel = 0; panel < 2; ++panel) {
        for (int i = 0; i <= nu; ++i) {
            skirt.waistband.push_back(index(panel, i, 0));
        }
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
    io::make_output_directory(dir / "body");
    for (int k = 0; k < BODY_FRAMES; ++k) {
        write_text(dir / "body" / fmt::format("frame_{:04d}.obj", k),
                   mesh_obj(mannequin_at(static_cast<double>(k) / BODY_FRAMES, BODY),
                            fmt::format("pliant's walking mannequin (scripts/make-body --frames {} "
                                        "--fps {} --segments {} --turn {} --swing {}), frame {}",
                                        BODY_FRAMES, BODY_FPS, BODY.segments, BODY.turn_degrees,
                                        BODY.swing_degrees, k)));
    }
    const std::string scene = fmt::format(
        R"({{
  "cloth": {{"mesh": "skirt.obj", "units": "m"}},
  "material": {{"preset": "cotton", "thickness": {}}},
  "seams": [{{"a": [{}], "b": [{}], "seconds": {}}}],
  "pins": {{"vertices": [{}], "attach": {{"obstacle": "body", "max_distance": 0.02}}}},
  "obstacles": [{{
    "name": "body",
    "mesh": {{"frames": "body/frame_%04d.obj", "fps": {}, "loop": true}}
  }}],
  "fps": 24, "frames": {}, "substeps": 40,
  "output": {{"format": "obj", "point_cache": "pc2"}}
}}
)",
        THICKNESS, int_list(skirt.seam_a), int_list(skirt.seam_b), SEW_SECONDS,
        int_list(skirt.waistband), BODY_FPS, options.frames);
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
