#include "pliant/pipeline/nerf_dataset_file.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <stb_image.h>

#include <cmath>
#include <fstream>
#include <memory>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::pipeline {

namespace {

using nlohmann::json;

double number(const json& j, const char* key, const std::filesystem::path& path) {
    const json& v = j.at(key);
    if (!v.is_number()) {
        throw IoError(
            fmt::format("{}: `{}` must be a number, got {}", path.string(), key, v.dump()));
    }
    return v.get<double>();
}

nerf::Pose read_pose(const json& m, const std::filesystem::path& path, std::size_t frame) {
    const auto bad = [&](const std::string& what) {
        return IoError(
            fmt::format("{}: frames[{}].transform_matrix: {}", path.string(), frame, what));
    };
    if (!m.is_array() || (m.size() != 4 && m.size() != 3)) {
        throw bad("expected a 4 x 4 (or 3 x 4) array of numbers");
    }
    nerf::Pose pose;
    for (std::size_t r = 0; r < m.size(); ++r) {
        if (!m[r].is_array() || m[r].size() != 4) {
            throw bad(fmt::format("row {} is not 4 numbers", r));
        }
        for (std::size_t c = 0; c < 4; ++c) {
            if (!m[r][c].is_number()) {
                throw bad(fmt::format("entry [{}][{}] is not a number", r, c));
            }
            const double v = m[r][c].get<double>();
            if (!std::isfinite(v)) {
                throw bad(fmt::format("entry [{}][{}] is not finite", r, c));
            }
            if (r < 3) {
                pose.m[4 * r + c] = v;
            } else if (std::fabs(v - (c == 3 ? 1.0 : 0.0)) > 1e-6) {
                throw bad(fmt::format("last row must be [0, 0, 0, 1], got {}", m[r].dump()));
            }
        }
    }
    return pose;
}

std::filesystem::path resolve_image(const std::filesystem::path& dir, const std::string& file) {
    std::filesystem::path p = dir / file;
    if (std::filesystem::is_regular_file(p)) {
        return p;
    }
    std::filesystem::path with_png = p;
    with_png += ".png";
    if (std::filesystem::is_regular_file(with_png)) {
        return with_png;
    }
    return p;
}

}  // namespace

nerf::Dataset read_nerf_dataset(const std::filesystem::path& path,
                                const ReadNerfDatasetOptions& options) {
    const std::string text = io::read_file(path);  // a directory or a missing file: IoError
    json j;
    try {
        j = json::parse(text);
    } catch (const json::exception& e) {
        throw IoError(fmt::format("{}: not valid JSON: {}", path.string(), e.what()));
    }
    if (!j.is_object()) {
        throw IoError(fmt::format("{}: expected a JSON object", path.string()));
    }
    if (!j.contains("frames") || !j["frames"].is_array() || j["frames"].empty()) {
        throw IoError(fmt::format("{}: `frames` must be a non-empty array", path.string()));
    }
    if ((j.contains("scale") && j["scale"].is_number() && j["scale"].get<double>() != 1.0) ||
        (j.contains("offset") && j["offset"] != json::array({0, 0, 0}) &&
         j["offset"] != json::array({0.0, 0.0, 0.0}))) {
        throw Unsupported(fmt::format(
            "{}: instant-ngp `scale` / `offset` are not applied by pliant; remove them or bake "
            "them into the transform matrices",
            path.string()));
    }
    const std::filesystem::path dir = path.parent_path();
    const json& frames = j["frames"];

    nerf::Dataset ds;
    ds.background = options.background;
    // Image paths and poses.
    std::vector<std::filesystem::path> images;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const json& f = frames[i];
        if (!f.is_object() || !f.contains("file_path") || !f["file_path"].is_string()) {
            throw IoError(
                fmt::format("{}: frames[{}]: missing string `file_path`", path.string(), i));
        }
        if (!f.contains("transform_matrix")) {
            throw IoError(
                fmt::format("{}: frames[{}]: missing `transform_matrix`", path.string(), i));
        }
        nerf::View v;
        v.name = f["file_path"].get<std::string>();
        v.camera_to_world = read_pose(f["transform_matrix"], path, i);
        images.push_back(resolve_image(dir, v.name));
        ds.views.push_back(std::move(v));
    }

    // Image size: w, h, else the first image.
    nerf::Intrinsics& intr = ds.intrinsics;
    if (j.contains("w") && j.contains("h")) {
        constexpr double MAX_SIDE = 65536.0;
        for (const char* key : {"w", "h"}) {
            const double v = number(j, key, path);
            if (!(v >= 1.0 && v <= MAX_SIDE) || v != std::floor(v)) {
                throw IoError(
                    fmt::format("{}: `{}` must be a whole number of pixels in [1, {}], "
                                "got {}",
                                path.string(), key, MAX_SIDE, j[key].dump()));
            }
        }
        intr.width = static_cast<int>(number(j, "w", path));
        intr.height = static_cast<int>(number(j, "h", path));
    } else {
        int w = 0, h = 0, n = 0;
        if (stbi_info(images[0].string().c_str(), &w, &h, &n) == 0) {
            throw IoError(fmt::format(
                "{}: frames[0]: {}: {}", path.string(), images[0].string(),
                std::filesystem::exists(images[0]) ? "not a decodable image" : "no such file"));
        }
        intr.width = w;
        intr.height = h;
    }
    if (intr.width < 1 || intr.height < 1) {
        throw IoError(fmt::format("{}: image size {} x {} must be positive", path.string(),
                                  intr.width, intr.height));
    }
    if (j.contains("fl_x")) {
        intr.fx = number(j, "fl_x", path);
        intr.fy = j.contains("fl_y") ? number(j, "fl_y", path) : intr.fx;
    } else if (j.contains("camera_angle_x")) {
        const double ax = number(j, "camera_angle_x", path);
        intr.fx = 0.5 * intr.width / std::tan(0.5 * ax);
        intr.fy = j.contains("camera_angle_y")
                      ? 0.5 * intr.height / std::tan(0.5 * number(j, "camera_angle_y", path))
                      : intr.fx;
    } else {
        throw IoError(
            fmt::format("{}: no focal length: expected `camera_angle_x` or `fl_x`", path.string()));
    }
    intr.cx = j.contains("cx") ? number(j, "cx", path) : 0.5 * intr.width;
    intr.cy = j.contains("cy") ? number(j, "cy", path) : 0.5 * intr.height;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        for (const auto& [key, value] : {std::pair{"fl_x", intr.fx}, std::pair{"fl_y", intr.fy},
                                         std::pair{"cx", intr.cx}, std::pair{"cy", intr.cy}}) {
            if (frames[i].contains(key) &&
                (!frames[i][key].is_number() ||
                 std::fabs(frames[i][key].get<double>() - value) > 1e-6 * std::fabs(value))) {
                throw Unsupported(fmt::format(
                    "{}: frames[{}].{} = {} differs from the dataset's {}: per-frame intrinsics "
                    "are not supported",
                    path.string(), i, key, frames[i][key].dump(), value));
            }
        }
    }

    if (j.contains("aabb")) {
        const json& a = j["aabb"];
        const auto corner = [&](std::size_t r) {
            if (!a.is_array() || a.size() != 2 || !a[r].is_array() || a[r].size() != 3 ||
                !a[r][0].is_number() || !a[r][1].is_number() || !a[r][2].is_number()) {
                throw IoError(fmt::format(
                    "{}: `aabb` must be [[xmin, ymin, zmin], [xmax, ymax, zmax]], got {}",
                    path.string(), a.dump()));
            }
            return Vec3d{a[r][0].get<double>(), a[r][1].get<double>(), a[r][2].get<double>()};
        };
        ds.box = AABBd{corner(0), corner(1)};
    }

    if (options.load_images) {
        const double bytes = 12.0 * static_cast<double>(intr.width) *
                             static_cast<double>(intr.height) *
                             static_cast<double>(ds.views.size());
        if (bytes > static_cast<double>(options.max_bytes)) {
            throw InvalidInput(fmt::format(
                "{}: {} images of {} x {} need {:.0f} MiB decoded (12 bytes per pixel), more than "
                "the memory limit of {:.0f} MiB",
                path.string(), ds.views.size(), intr.width, intr.height, bytes / 1048576.0,
                options.max_bytes / 1048576.0));
        }
        const render::Color bg = options.background;
        for (std::size_t i = 0; i < ds.views.size(); ++i) {
            const std::string file = images[i].string();
            if (!std::filesystem::is_regular_file(images[i])) {
                throw IoError(fmt::format("{}: frames[{}] ('{}'): {}: no such file", path.string(),
                                          i, ds.views[i].name, file));
            }
            int w = 0, h = 0, n = 0;
            const auto check = [&](bool decoded) {
                if (!decoded) {
                    throw IoError(fmt::format("{}: frames[{}]: {}: cannot decode the image ({})",
                                              path.string(), i, file, stbi_failure_reason()));
                }
                if (w != intr.width || h != intr.height) {
                    throw IoError(fmt::format(
                        "{}: frames[{}]: {}: image is {} x {}, expected {} x {} like the dataset",
                        path.string(), i, file, w, h, intr.width, intr.height));
                }
            };
            // The size from the header first: an image that claims another size is refused
            // before stb allocates for it.
            check(stbi_info(file.c_str(), &w, &h, &n) != 0);
            const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
                stbi_load(file.c_str(), &w, &h, &n, 4), stbi_image_free);
            check(pixels != nullptr);
            std::vector<float>& rgb = ds.views[i].rgb;
            rgb.resize(3 * static_cast<std::size_t>(w) * h);
            const unsigned char* p = pixels.get();
            for (std::size_t q = 0; q < static_cast<std::size_t>(w) * h; ++q) {
                const float a = p[4 * q + 3] / 255.0f;
                rgb[3 * q] = p[4 * q] / 255.0f * a + bg.r * (1.0f - a);
                rgb[3 * q + 1] = p[4 * q + 1] / 255.0f * a + bg.g * (1.0f - a);
                rgb[3 * q + 2] = p[4 * q + 2] / 255.0f * a + bg.b * (1.0f - a);
            }
        }
        nerf::validate(ds);
    }
    return ds;
}

void write_transforms(const std::filesystem::path& path, const nerf::Intrinsics& in,
                      std::span<const std::string> file_paths, std::span<const nerf::Pose> poses,
                      const std::optional<AABBd>& box) {
    if (file_paths.size() != poses.size()) {
        throw InvalidInput(fmt::format("pipeline::write_transforms: {} file paths but {} poses",
                                       file_paths.size(), poses.size()));
    }
    nlohmann::ordered_json j;
    j["camera_angle_x"] = 2.0 * std::atan(0.5 * in.width / in.fx);
    j["camera_angle_y"] = 2.0 * std::atan(0.5 * in.height / in.fy);
    j["fl_x"] = in.fx;
    j["fl_y"] = in.fy;
    j["cx"] = in.cx;
    j["cy"] = in.cy;
    j["w"] = in.width;
    j["h"] = in.height;
    if (box) {
        j["aabb"] = {{box->lo.x, box->lo.y, box->lo.z}, {box->hi.x, box->hi.y, box->hi.z}};
    }
    j["frames"] = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const auto& m = poses[i].m;
        nlohmann::ordered_json f;
        f["file_path"] = file_paths[i];
        f["transform_matrix"] = {{m[0], m[1], m[2], m[3]},
                                 {m[4], m[5], m[6], m[7]},
                                 {m[8], m[9], m[10], m[11]},
                                 {0.0, 0.0, 0.0, 1.0}};
        j["frames"].push_back(f);
    }
    const std::string text = j.dump(2) + "\n";
    io::write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace pliant::pipeline
