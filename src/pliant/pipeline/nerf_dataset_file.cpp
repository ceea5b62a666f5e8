#include "pliant/pipeline/nerf_dataset_file.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <stb_image.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/colmap_model.hpp"
#include "pliant/io/json_text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::pipeline {

namespace {

using nlohmann::json;

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
    for (const char* ext : {".png", ".jpg", ".jpeg", ".JPG", ".PNG"}) {
        std::filesystem::path with = p;
        with += ext;
        if (std::filesystem::is_regular_file(with)) {
            return with;
        }
    }
    return p;
}

// Keys of the intrinsics, valid in the file and in each frame.
constexpr std::array<std::string_view, 16> INTRINSIC_KEYS = {
    "w",  "h",  "fl_x", "fl_y", "cx", "cy", "camera_angle_x", "camera_angle_y", "camera_model",
    "k1", "k2", "k3",   "k4",   "p1", "p2", "is_fisheye"};
constexpr std::array<std::string_view, 7> FILE_KEYS = {
    "frames", "aabb", "aabb_scale", "scale", "offset", "applied_transform", "orientation_override"};
constexpr std::array<std::string_view, 5> FRAME_KEYS = {"file_path", "transform_matrix",
                                                        "mask_path", "colmap_im_id", "sharpness"};
constexpr std::array<std::string_view, 6> COEFFICIENTS = {"k1", "k2", "k3", "k4", "p1", "p2"};

template <std::size_t N>
bool is_one_of(const std::string& key, const std::array<std::string_view, N>& keys) {
    return std::find(keys.begin(), keys.end(), key) != keys.end();
}

// The intrinsic keys of a frame, falling back to the file's.
struct IntrinsicKeys {
    const json& file;
    const json* frame = nullptr;

    const json* find(const char* key) const {
        if (frame != nullptr && frame->contains(key)) {
            return &(*frame)[key];
        }
        return file.contains(key) ? &file[key] : nullptr;
    }
    bool any_in_frame() const {
        if (frame == nullptr) {
            return false;
        }
        return std::any_of(INTRINSIC_KEYS.begin(), INTRINSIC_KEYS.end(),
                           [&](std::string_view k) { return frame->contains(std::string(k)); });
    }
};

double number_at(const json* v, const char* key, const std::string& where) {
    if (!v->is_number()) {
        throw IoError(fmt::format("{}: `{}` must be a number, got {}", where, key, v->dump()));
    }
    const double x = v->get<double>();
    if (!std::isfinite(x)) {
        throw IoError(fmt::format("{}: `{}` must be finite, got {}", where, key, v->dump()));
    }
    return x;
}

// The intrinsics named by `keys` for an image of width × height (see the header comment).
nerf::Intrinsics resolve_intrinsics(const IntrinsicKeys& keys, int width, int height,
                                    const std::string& where) {
    nerf::Intrinsics in;
    in.width = width;
    in.height = height;
    if (const json* v = keys.find("fl_x")) {
        in.fx = number_at(v, "fl_x", where);
    } else if (const json* a = keys.find("camera_angle_x")) {
        in.fx = 0.5 * width / std::tan(0.5 * number_at(a, "camera_angle_x", where));
    } else {
        throw IoError(fmt::format(
            "{}: no focal length: expected `camera_angle_x` or `fl_x` (in the file or in every "
            "frame)",
            where));
    }
    if (const json* v = keys.find("fl_y")) {
        in.fy = number_at(v, "fl_y", where);
    } else if (const json* a = keys.find("camera_angle_y")) {
        in.fy = 0.5 * height / std::tan(0.5 * number_at(a, "camera_angle_y", where));
    } else {
        in.fy = in.fx;
    }
    const json* cx = keys.find("cx");
    const json* cy = keys.find("cy");
    in.cx = cx != nullptr ? number_at(cx, "cx", where) : 0.5 * width;
    in.cy = cy != nullptr ? number_at(cy, "cy", where) : 0.5 * height;

    bool fisheye = false;
    if (const json* f = keys.find("is_fisheye")) {
        if (!f->is_boolean()) {
            throw IoError(
                fmt::format("{}: `is_fisheye` must be true or false, got {}", where, f->dump()));
        }
        fisheye = f->get<bool>();
    }
    bool has_coefficient = false;
    std::array<double, 6> k{};
    for (std::size_t i = 0; i < COEFFICIENTS.size(); ++i) {
        const std::string key(COEFFICIENTS[i]);
        if (const json* v = keys.find(key.c_str())) {
            k[i] = number_at(v, key.c_str(), where);
            has_coefficient = true;
        }
    }
    if (const json* m = keys.find("camera_model")) {
        const std::optional<nerf::LensModel> model =
            m->is_string() ? nerf::lens_model_from_name(m->get<std::string>()) : std::nullopt;
        if (!model) {
            throw IoError(fmt::format("{}: `camera_model` {} is not supported; expected one of {}",
                                      where, m->dump(), nerf::lens_model_names()));
        }
        if (fisheye && *model != nerf::LensModel::opencv_fisheye) {
            throw IoError(
                fmt::format("{}: `is_fisheye` is true but `camera_model` is {}", where, m->dump()));
        }
        in.lens.model = *model;
    } else if (fisheye) {
        in.lens.model = nerf::LensModel::opencv_fisheye;
    } else if (has_coefficient) {
        in.lens.model = nerf::LensModel::opencv;
    }
    in.lens.k1 = k[0];
    in.lens.k2 = k[1];
    in.lens.k3 = k[2];
    in.lens.k4 = k[3];
    in.lens.p1 = k[4];
    in.lens.p2 = k[5];
    nerf::validate(in.lens, where);
    return in;
}

bool same_intrinsics(const nerf::Intrinsics& a, const nerf::Intrinsics& b) {
    return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
           a.cx == b.cx && a.cy == b.cy && a.lens.model == b.lens.model && a.lens.k1 == b.lens.k1 &&
           a.lens.k2 == b.lens.k2 && a.lens.k3 == b.lens.k3 && a.lens.k4 == b.lens.k4 &&
           a.lens.p1 == b.lens.p1 && a.lens.p2 == b.lens.p2;
}

// A row-major matrix of `rows` × 4 finite numbers (3 or 4 rows).
void check_matrix(const json& m, const std::string& what) {
    bool ok = m.is_array() && (m.size() == 3 || m.size() == 4);
    for (std::size_t r = 0; ok && r < m.size(); ++r) {
        ok = m[r].is_array() && m[r].size() == 4;
        for (std::size_t c = 0; ok && c < 4; ++c) {
            ok = m[r][c].is_number() && std::isfinite(m[r][c].get<double>());
        }
    }
    if (!ok) {
        throw IoError(fmt::format("{}: expected a 3 x 4 or 4 x 4 matrix of finite numbers, got {}",
                                  what, m.dump()));
    }
}

// Decodes `file` (expected width × height) into rgb (composited over the background) and, with
// alpha_mask or a mask image, `mask`.
void load_view(nerf::View& view, const std::filesystem::path& image,
               const std::filesystem::path& mask_image, int width, int height,
               const ReadNerfDatasetOptions& options, const std::string& where) {
    const std::string file = image.string();
    if (!std::filesystem::is_regular_file(image)) {
        throw IoError(fmt::format("{} ('{}'): {}: no such file", where, view.name, file));
    }
    int w = 0, h = 0, n = 0;
    const auto check = [&](bool decoded, const std::string& f) {
        if (!decoded) {
            throw IoError(fmt::format("{}: {}: cannot decode the image ({})", where, f,
                                      stbi_failure_reason()));
        }
        if (w != width || h != height) {
            throw IoError(fmt::format("{}: {}: image is {} x {}, expected {} x {} like the dataset",
                                      where, f, w, h, width, height));
        }
    };
    // The size from the header first: an image that claims another size is refused before stb
    // allocates for it.
    check(stbi_info(file.c_str(), &w, &h, &n) != 0, file);
    const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
        stbi_load(file.c_str(), &w, &h, &n, 4), stbi_image_free);
    check(pixels != nullptr, file);
    const render::Color bg = options.background;
    const std::size_t count = static_cast<std::size_t>(w) * h;
    std::vector<float>& rgb = view.rgb;
    rgb.resize(3 * count);
    const unsigned char* p = pixels.get();
    for (std::size_t q = 0; q < count; ++q) {
        const float a = p[4 * q + 3] / 255.0f;
        rgb[3 * q] = p[4 * q] / 255.0f * a + bg.r * (1.0f - a);
        rgb[3 * q + 1] = p[4 * q + 1] / 255.0f * a + bg.g * (1.0f - a);
        rgb[3 * q + 2] = p[4 * q + 2] / 255.0f * a + bg.b * (1.0f - a);
    }
    if (options.alpha_mask) {
        view.mask.resize(count);
        for (std::size_t q = 0; q < count; ++q) {
            view.mask[q] = p[4 * q + 3] != 0 ? 1 : 0;
        }
    }
    if (!mask_image.empty()) {
        const std::string mfile = mask_image.string();
        if (!std::filesystem::is_regular_file(mask_image)) {
            throw IoError(fmt::format("{}: mask_path: {}: no such file", where, mfile));
        }
        check(stbi_info(mfile.c_str(), &w, &h, &n) != 0, mfile);
        const std::unique_ptr<unsigned char, void (*)(void*)> m(
            stbi_load(mfile.c_str(), &w, &h, &n, 1), stbi_image_free);
        check(m != nullptr, mfile);
        view.mask.resize(count, 1);
        for (std::size_t q = 0; q < count; ++q) {
            view.mask[q] = view.mask[q] != 0 && m.get()[q] != 0 ? 1 : 0;
        }
    }
}

// Box filter by n × n (see the header comment).
void downscale_view(nerf::View& view, int width, int height, int n) {
    const int w = width / n, h = height / n;
    std::vector<float> rgb(3 * static_cast<std::size_t>(w) * h);
    std::vector<std::uint8_t> mask(view.mask.empty() ? 0 : static_cast<std::size_t>(w) * h);
    const float inv = 1.0f / static_cast<float>(n * n);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            float sum[3] = {0.0f, 0.0f, 0.0f};
            bool keep = true;
            for (int dy = 0; dy < n; ++dy) {
                for (int dx = 0; dx < n; ++dx) {
                    const std::size_t q = static_cast<std::size_t>(y * n + dy) * width +
                                          static_cast<std::size_t>(x * n + dx);
                    for (int c = 0; c < 3; ++c) {
                        sum[c] += view.rgb[3 * q + c];
                    }
                    keep = keep && (view.mask.empty() || view.mask[q] != 0);
                }
            }
            const std::size_t o = static_cast<std::size_t>(y) * w + x;
            for (int c = 0; c < 3; ++c) {
                rgb[3 * o + c] = sum[c] * inv;
            }
            if (!mask.empty()) {
                mask[o] = keep ? 1 : 0;
            }
        }
    }
    view.rgb = std::move(rgb);
    view.mask = std::move(mask);
}

nerf::Intrinsics downscaled(nerf::Intrinsics in, int n) {
    const double s = static_cast<double>(n);
    in.width /= n;
    in.height /= n;
    in.fx /= s;
    in.fy /= s;
    in.cx /= s;
    in.cy /= s;
    return in;
}

void check_memory(const nerf::Dataset& ds, const ReadNerfDatasetOptions& options,
                  const std::string& where) {
    const nerf::Intrinsics& intr = ds.intrinsics;
    const double bytes = 12.0 * static_cast<double>(intr.width) * static_cast<double>(intr.height) *
                         static_cast<double>(ds.views.size());
    if (bytes > static_cast<double>(options.max_bytes)) {
        throw InvalidInput(fmt::format(
            "{}: {} images of {} x {} need {:.0f} MiB decoded (12 bytes per pixel), more than "
            "the memory limit of {:.0f} MiB",
            where, ds.views.size(), intr.width, intr.height, bytes / 1048576.0,
            options.max_bytes / 1048576.0));
    }
}

void check_downscale(const nerf::Intrinsics& in, int n, const std::string& where) {
    if (n < 1 || n > in.width || n > in.height) {
        throw InvalidInput(fmt::format("{}: downscale {} must be in [1, {}] for {} x {} images",
                                       where, n, std::min(in.width, in.height), in.width,
                                       in.height));
    }
}

// Decodes every view's image (and mask), downscales, validates.
void load_views(nerf::Dataset& ds, const std::vector<std::filesystem::path>& images,
                const std::vector<std::filesystem::path>& masks,
                const ReadNerfDatasetOptions& options, const std::string& where) {
    const int n = options.downscale;
    check_downscale(ds.intrinsics, n, where);
    if (options.load_images) {
        check_memory(ds, options, where);
        for (std::size_t i = 0; i < ds.views.size(); ++i) {
            load_view(ds.views[i], images[i], masks[i], ds.intrinsics.width, ds.intrinsics.height,
                      options, fmt::format("{}: frames[{}]", where, i));
            if (n > 1) {
                downscale_view(ds.views[i], ds.intrinsics.width, ds.intrinsics.height, n);
            }
        }
    }
    if (n > 1) {
        ds.intrinsics = downscaled(ds.intrinsics, n);
        for (nerf::View& v : ds.views) {
            if (v.intrinsics) {
                v.intrinsics = downscaled(*v.intrinsics, n);
            }
        }
    }
    if (options.load_images) {
        nerf::validate(ds);
    }
}

}  // namespace

nerf::Dataset read_nerf_dataset(const std::filesystem::path& path,
                                const ReadNerfDatasetOptions& options) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        if (io::is_colmap_model_directory(path)) {
            return read_colmap_dataset(path, options);
        }
        if (std::filesystem::is_regular_file(path / "transforms.json", ec)) {
            return read_nerf_dataset(path / "transforms.json", options);
        }
        throw IoError(fmt::format(
            "{}: expected a regular file, got a directory that holds neither transforms.json nor "
            "a COLMAP model (cameras, images, points3D as .bin or .txt)",
            path.string()));
    }
    const std::string text = io::read_file(path);  // a missing file: IoError
    const json j = io::parse_json(text, path.string());
    if (!j.is_object()) {
        throw IoError(fmt::format("{}: expected a JSON object", path.string()));
    }
    const std::string where = path.string();
    if (!j.contains("frames") || !j["frames"].is_array() || j["frames"].empty()) {
        throw IoError(fmt::format("{}: `frames` must be a non-empty array", where));
    }
    if ((j.contains("scale") && j["scale"].is_number() && j["scale"].get<double>() != 1.0) ||
        (j.contains("offset") && j["offset"] != json::array({0, 0, 0}) &&
         j["offset"] != json::array({0.0, 0.0, 0.0}))) {
        throw Unsupported(fmt::format(
            "{}: instant-ngp `scale` / `offset` are not applied by pliant; remove them or bake "
            "them into the transform matrices",
            where));
    }
    // Keys: every one is understood, or named in a warning.
    for (const auto& [key, value] : j.items()) {
        if (!is_one_of(key, INTRINSIC_KEYS) && !is_one_of(key, FILE_KEYS)) {
            log_warning("{}: key `{}` is not understood by pliant and is ignored", where, key);
        }
    }
    if (j.contains("applied_transform")) {
        check_matrix(j["applied_transform"], where + ": `applied_transform`");
    }
    if (j.contains("orientation_override")) {
        const json& o = j["orientation_override"];
        if (!o.is_string()) {
            throw IoError(fmt::format("{}: `orientation_override` must be a string, got {}", where,
                                      o.dump()));
        }
        if (o.get<std::string>() != "none") {
            log_warning(
                "{}: `orientation_override` {} is not applied: pliant uses the poses as written "
                "(nerfstudio re-orients them at load time)",
                where, o.dump());
        }
    }
    const json& frames = j["frames"];

    nerf::Dataset ds;
    ds.background = options.background;
    // Image paths, masks and poses.
    std::vector<std::filesystem::path> images, masks;
    std::map<std::string, std::size_t> unknown_frame_keys;  // key → first frame
    const std::filesystem::path dir = path.parent_path();
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const json& f = frames[i];
        if (!f.is_object() || !f.contains("file_path") || !f["file_path"].is_string()) {
            throw IoError(fmt::format("{}: frames[{}]: missing string `file_path`", where, i));
        }
        if (!f.contains("transform_matrix")) {
            throw IoError(fmt::format("{}: frames[{}]: missing `transform_matrix`", where, i));
        }
        for (const auto& [key, value] : f.items()) {
            if (!is_one_of(key, INTRINSIC_KEYS) && !is_one_of(key, FRAME_KEYS)) {
                unknown_frame_keys.emplace(key, i);
            }
        }
        nerf::View v;
        v.name = f["file_path"].get<std::string>();
        v.camera_to_world = read_pose(f["transform_matrix"], path, i);
        images.push_back(resolve_image(dir, v.name));
        if (f.contains("mask_path")) {
            if (!f["mask_path"].is_string()) {
                throw IoError(fmt::format("{}: frames[{}]: `mask_path` must be a string, got {}",
                                          where, i, f["mask_path"].dump()));
            }
            masks.push_back(resolve_image(dir, f["mask_path"].get<std::string>()));
        } else {
            masks.emplace_back();
        }
        ds.views.push_back(std::move(v));
    }
    for (const auto& [key, frame] : unknown_frame_keys) {
        log_warning("{}: frames[{}]: key `{}` is not understood by pliant and is ignored", where,
                    frame, key);
    }

    // Image size: w, h (the file's, else the first frame's), else the first image.
    const IntrinsicKeys file_keys{j, nullptr};
    const IntrinsicKeys first_keys{j, &frames[0]};
    int width = 0, height = 0;
    if (first_keys.find("w") != nullptr && first_keys.find("h") != nullptr) {
        constexpr double MAX_SIDE = 65536.0;
        for (const char* key : {"w", "h"}) {
            const json* v = first_keys.find(key);
            const double x = v->is_number() ? v->get<double>() : -1.0;
            if (!(x >= 1.0 && x <= MAX_SIDE) || x != std::floor(x)) {
                throw IoError(
                    fmt::format("{}: `{}` must be a whole number of pixels in [1, {}], got {}",
                                where, key, MAX_SIDE, v->dump()));
            }
        }
        width = static_cast<int>(first_keys.find("w")->get<double>());
        height = static_cast<int>(first_keys.find("h")->get<double>());
    } else {
        int n = 0;
        if (stbi_info(images[0].string().c_str(), &width, &height, &n) == 0) {
            throw IoError(fmt::format(
                "{}: frames[0]: {}: {}", where, images[0].string(),
                std::filesystem::exists(images[0]) ? "not a decodable image" : "no such file"));
        }
    }
    // Intrinsics: the file's when it has a focal length, else the first frame's; a frame with
    // intrinsic keys of its own gets its own when they differ.
    const bool file_has_focal = j.contains("fl_x") || j.contains("camera_angle_x");
    ds.intrinsics = resolve_intrinsics(file_has_focal ? file_keys : first_keys, width, height,
                                       file_has_focal ? where : where + ": frames[0]");
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const IntrinsicKeys keys{j, &frames[i]};
        if (!keys.any_in_frame()) {
            continue;
        }
        const std::string fw = fmt::format("{}: frames[{}]", where, i);
        for (const char* key : {"w", "h"}) {
            if (frames[i].contains(key) &&
                (!frames[i][key].is_number() ||
                 frames[i][key].get<double>() != (key[0] == 'w' ? width : height))) {
                throw Unsupported(fmt::format(
                    "{}: `{}` = {} differs from the dataset's {} x {}: images of different sizes "
                    "in one dataset are not supported",
                    fw, key, frames[i][key].dump(), width, height));
            }
        }
        const nerf::Intrinsics in = resolve_intrinsics(keys, width, height, fw);
        if (!same_intrinsics(in, ds.intrinsics)) {
            ds.views[i].intrinsics = in;
        }
    }

    if (j.contains("aabb")) {
        const json& a = j["aabb"];
        const auto corner = [&](std::size_t r) {
            if (!a.is_array() || a.size() != 2 || !a[r].is_array() || a[r].size() != 3 ||
                !a[r][0].is_number() || !a[r][1].is_number() || !a[r][2].is_number()) {
                throw IoError(fmt::format(
                    "{}: `aabb` must be [[xmin, ymin, zmin], [xmax, ymax, zmax]], got {}", where,
                    a.dump()));
            }
            return Vec3d{a[r][0].get<double>(), a[r][1].get<double>(), a[r][2].get<double>()};
        };
        ds.box = AABBd{corner(0), corner(1)};
    }
    if (j.contains("aabb_scale")) {
        const json& a = j["aabb_scale"];
        const double v = a.is_number() ? a.get<double>() : 0.0;
        if (!(v >= 1.0 && v <= 128.0) || std::exp2(std::round(std::log2(v))) != v) {
            throw IoError(fmt::format("{}: `aabb_scale` must be a power of two in [1, 128], got {}",
                                      where, a.dump()));
        }
        if (v > 1.0) {
            log_warning(
                "{}: `aabb_scale` {} (instant-ngp's background region beyond the unit cube) is "
                "not used: pliant reconstructs only the scene box ({})",
                where, a.dump(), ds.box ? "the file's `aabb`" : "derived from the cameras");
        }
    }

    load_views(ds, images, masks, options, where);
    return ds;
}

nerf::Dataset read_colmap_dataset(const std::filesystem::path& model_dir,
                                  const ReadNerfDatasetOptions& options) {
    const io::ColmapModel model = io::read_colmap_model(model_dir);
    const nerf::ColmapTransforms t = nerf::transforms_from_colmap(model, options.colmap);
    const std::string where = model_dir.string();
    std::filesystem::path images_dir = options.images_dir;
    if (images_dir.empty()) {
        images_dir =
            (std::filesystem::absolute(model_dir) / ".." / ".." / "images").lexically_normal();
    }
    std::error_code ec;
    if (!std::filesystem::is_directory(images_dir, ec)) {
        throw IoError(fmt::format(
            "{}: the photos' directory {} does not exist; name it with --images DIR (the "
            "directory COLMAP's feature extraction read)",
            where, images_dir.string()));
    }
    nerf::Dataset ds;
    ds.background = options.background;
    ds.intrinsics = t.frames.front().intrinsics;
    std::vector<std::filesystem::path> images, masks;
    for (const nerf::ColmapFrame& f : t.frames) {
        if (f.intrinsics.width != ds.intrinsics.width ||
            f.intrinsics.height != ds.intrinsics.height) {
            throw Unsupported(fmt::format(
                "{}: image '{}' is {} x {}, '{}' {} x {}: images of different sizes in one "
                "dataset are not supported",
                where, f.file_path, f.intrinsics.width, f.intrinsics.height,
                t.frames.front().file_path, ds.intrinsics.width, ds.intrinsics.height));
        }
        nerf::View v;
        v.name = f.file_path;
        v.camera_to_world = f.camera_to_world;
        if (!same_intrinsics(f.intrinsics, ds.intrinsics)) {
            v.intrinsics = f.intrinsics;
        }
        ds.views.push_back(std::move(v));
        images.push_back(images_dir / f.file_path);
        masks.emplace_back();
    }
    nerf::validate(ds.intrinsics, where);
    if (t.scale_used == nerf::ColmapScale::points) {
        ds.box = AABBd{{-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0}};  // the sparse points' 95 % extent
    }
    load_views(ds, images, masks, options, where);
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
    if (!in.lens.is_identity()) {
        j["camera_model"] = std::string(nerf::lens_model_name(in.lens.model));
        const std::array<std::pair<const char*, double>, 6> k = {{{"k1", in.lens.k1},
                                                                  {"k2", in.lens.k2},
                                                                  {"k3", in.lens.k3},
                                                                  {"k4", in.lens.k4},
                                                                  {"p1", in.lens.p1},
                                                                  {"p2", in.lens.p2}}};
        for (const auto& [key, value] : k) {
            if (nerf::lens_model_uses(in.lens.model, key)) {
                j[key] = value;
            }
        }
    }
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
