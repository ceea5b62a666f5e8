#include "pliant/pipeline/photo_poses.hpp"

#include <fmt/format.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/child_process.hpp"
#include "pliant/io/ply.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::pipeline {
namespace fs = std::filesystem;
namespace {

using Mat3 = std::array<double, 9>;

const char* const HELP_REGISTER =
    "what usually helps: more overlap between neighbouring photos (a step of 10-15 degrees "
    "around the object), textured surfaces in view (plain white objects and tables give no "
    "features), sharp photos (less motion blur), and no zoom between photos";

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string join(const std::vector<std::string>& items, std::size_t max_items = 20) {
    std::string out;
    for (std::size_t i = 0; i < items.size() && i < max_items; ++i) {
        out += (i > 0 ? ", " : "") + items[i];
    }
    if (items.size() > max_items) {
        out += fmt::format(" and {} more", items.size() - max_items);
    }
    return out;
}

// The last `lines` lines of a text file ("" when it cannot be read).
std::string tail_of(const fs::path& path, int lines) {
    std::string text;
    try {
        text = io::read_file(path);
    } catch (const IoError&) {
        return "";
    }
    std::size_t pos = text.size();
    int seen = 0;
    while (pos > 0 && seen <= lines) {
        pos = text.rfind('\n', pos - 1);
        if (pos == std::string::npos) {
            pos = 0;
            break;
        }
        ++seen;
    }
    return text.substr(pos == 0 ? 0 : pos + 1);
}

// Step 1: decode every photo; all must have one size.
void check_photos(const std::vector<fs::path>& files, const fs::path& folder, int& width,
                  int& height) {
    std::vector<std::string> unreadable;
    std::string first_name;
    for (const fs::path& file : files) {
        int w = 0, h = 0, n = 0;
        const std::unique_ptr<stbi_uc, void (*)(void*)> pixels(
            stbi_load(file.c_str(), &w, &h, &n, 3), stbi_image_free);
        if (!pixels) {
            const char* reason = stbi_failure_reason();
            unreadable.push_back(fmt::format("{} ({})", file.filename().string(),
                                             reason != nullptr ? reason : "unknown"));
            continue;
        }
        if (first_name.empty()) {
            first_name = file.filename().string();
            width = w;
            height = h;
        } else if (w != width || h != height) {
            throw InvalidInput(fmt::format(
                "{}: photo {} is {} x {} but {} is {} x {}; one shared camera needs photos of "
                "one size (resize them, or leave out the odd ones)",
                folder.string(), file.filename().string(), w, h, first_name, width, height));
        }
    }
    if (!unreadable.empty()) {
        throw IoError(fmt::format("{}: {} of {} photos cannot be read as JPEG or PNG: {}",
                                  folder.string(), unreadable.size(), files.size(),
                                  join(unreadable)));
    }
}

// COLMAP's camera (one, OPENCV) and registered images of a text model.
struct ColmapImage {
    std::string name;
    std::array<double, 4> q{};  // world-to-camera rotation, (w, x, y, z)
    Vec3d t{};                  // world-to-camera translation
};
struct ColmapPoint {
    Vec3d position;
    std::array<std::uint8_t, 3> color{};
    double error = 0.0;
    int track_length = 0;
};
struct ColmapModel {
    std::string camera_model;
    int width = 0, height = 0;
    std::vector<double> params;
    std::vector<ColmapImage> images;
    std::vector<ColmapPoint> points;
};

std::vector<std::string> content_lines(const fs::path& path) {
    std::ifstream in(path);
    if (!in) {
        throw IoError(fmt::format("{}: cannot open COLMAP's model file", path.string()));
    }
    std::vector<std::string> lines;
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        if (line.empty() || line[0] != '#') {
            lines.push_back(line);
        }
    }
    return lines;
}

[[noreturn]] void bad_model(const fs::path& path, const std::string& what) {
    throw IoError(fmt::format("{}: unexpected COLMAP model content: {}", path.string(), what));
}

ColmapModel read_text_model(const fs::path& dir) {
    ColmapModel model;
    const fs::path cameras = dir / "cameras.txt";
    int num_cameras = 0;
    for (const std::string& line : content_lines(cameras)) {
        if (line.empty()) {
            continue;
        }
        std::istringstream s(line);
        int id = 0;
        s >> id >> model.camera_model >> model.width >> model.height;
        double p = 0.0;
        model.params.clear();
        while (s >> p) {
            model.params.push_back(p);
        }
        ++num_cameras;
    }
    if (num_cameras != 1 || model.camera_model != "OPENCV" || model.params.size() != 8) {
        bad_model(cameras, fmt::format("{} cameras, model {} with {} parameters, expected one "
                                       "OPENCV camera with 8",
                                       num_cameras, model.camera_model, model.params.size()));
    }
    const fs::path images = dir / "images.txt";
    const std::vector<std::string> image_lines = content_lines(images);
    for (std::size_t i = 0; i < image_lines.size(); i += 2) {
        if (image_lines[i].empty()) {
            break;  // a trailing blank line
        }
        std::istringstream s(image_lines[i]);
        int id = 0, camera = 0;
        ColmapImage im;
        s >> id >> im.q[0] >> im.q[1] >> im.q[2] >> im.q[3] >> im.t.x >> im.t.y >> im.t.z >>
            camera;
        std::getline(s >> std::ws, im.name);
        if (im.name.empty()) {
            bad_model(images, fmt::format("line \"{}\"", image_lines[i]));
        }
        model.images.push_back(im);
    }
    const fs::path points = dir / "points3D.txt";
    for (const std::string& line : content_lines(points)) {
        if (line.empty()) {
            continue;
        }
        std::istringstream s(line);
        std::int64_t id = 0;
        int r = 0, g = 0, b = 0;
        ColmapPoint p;
        s >> id >> p.position.x >> p.position.y >> p.position.z >> r >> g >> b >> p.error;
        if (!s) {
            bad_model(points, fmt::format("line \"{}\"", line.substr(0, 80)));
        }
        std::int64_t a = 0;
        int n = 0;
        while (s >> a) {
            ++n;
        }
        p.track_length = n / 2;
        p.color = {static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                   static_cast<std::uint8_t>(b)};
        model.points.push_back(p);
    }
    return model;
}

// The number of registered images of a binary model (images.bin starts with a uint64 count).
std::uint64_t registered_in(const fs::path& model_dir) {
    std::ifstream in(model_dir / "images.bin", std::ios::binary);
    std::uint64_t count = 0;
    if (!in.read(reinterpret_cast<char*>(&count), sizeof count)) {
        return 0;
    }
    return count;
}

Mat3 rotation_from_quaternion(const std::array<double, 4>& q) {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
            2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

Vec3d mul(const Mat3& m, Vec3d v) {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
}

Mat3 mul(const Mat3& a, const Mat3& b) {
    Mat3 m{};
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = 0; j < 3; ++j) {
            for (std::size_t k = 0; k < 3; ++k) {
                m[3 * i + j] += a[3 * i + k] * b[3 * k + j];
            }
        }
    }
    return m;
}

Mat3 transpose(const Mat3& a) {
    return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]};
}

double det(const Mat3& a) {
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

// The smallest rotation taking the unit vector u to +z (Rodrigues about u × z).
Mat3 rotation_to_z(Vec3d u) {
    const Vec3d z{0, 0, 1};
    const Vec3d axis = cross(u, z);
    const double s = norm(axis), c = dot(u, z);
    if (s < 1e-12) {
        return c > 0 ? Mat3{1, 0, 0, 0, 1, 0, 0, 0, 1} : Mat3{1, 0, 0, 0, -1, 0, 0, 0, -1};
    }
    const Vec3d k = axis / s;
    const Mat3 kx{0, -k.z, k.y, k.z, 0, -k.x, -k.y, k.x, 0};
    const Mat3 kx2 = mul(kx, kx);
    Mat3 r{1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (std::size_t i = 0; i < 9; ++i) {
        r[i] += s * kx[i] + (1 - c) * kx2[i];
    }
    return r;
}

struct CameraGL {
    Mat3 rotation;  // camera-to-world, columns x (right), y (up), z (backward)
    Vec3d eye;
};

CameraGL camera_to_world_gl(const ColmapImage& im) {
    const Mat3 r_wc = rotation_from_quaternion(im.q);
    Mat3 r = transpose(r_wc);  // camera-to-world, OpenCV axes
    const Vec3d eye = -1.0 * mul(r, im.t);
    for (std::size_t row = 0; row < 3; ++row) {  // OpenCV (y down, z forward) → OpenGL
        r[3 * row + 1] = -r[3 * row + 1];
        r[3 * row + 2] = -r[3 * row + 2];
    }
    return {r, eye};
}

// The point nearest (least squares) to the lines eye_i + s·dir_i: Σ (I − d dᵀ) c = Σ (I − d dᵀ) e.
Vec3d nearest_to_axes(const std::vector<CameraGL>& cameras) {
    Mat3 a{};
    Vec3d b{};
    for (const CameraGL& c : cameras) {
        const Vec3d d{-c.rotation[2], -c.rotation[5], -c.rotation[8]};
        const Mat3 p{1 - d.x * d.x, -d.x * d.y,    -d.x * d.z,   -d.y * d.x, 1 - d.y * d.y,
                     -d.y * d.z,    -d.z * d.x,    -d.z * d.y,   1 - d.z * d.z};
        for (std::size_t i = 0; i < 9; ++i) {
            a[i] += p[i];
        }
        b += mul(p, c.eye);
    }
    const double d = det(a);
    if (std::abs(d) < 1e-9 * static_cast<double>(cameras.size() * cameras.size() * cameras.size())) {
        throw InvalidInput(
            "the registered cameras' optical axes are (nearly) parallel: no point they look at "
            "(a capture should walk around the object)");
    }
    // Cramer's rule.
    auto with_column = [&](int col) {
        Mat3 m = a;
        for (std::size_t row = 0; row < 3; ++row) {
            m[3 * row + static_cast<std::size_t>(col)] = b[static_cast<int>(row)];
        }
        return m;
    };
    return {det(with_column(0)) / d, det(with_column(1)) / d, det(with_column(2)) / d};
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

nlohmann::ordered_json matrix_json(const Mat3& r, Vec3d t) {
    nlohmann::ordered_json m = nlohmann::ordered_json::array();
    for (std::size_t row = 0; row < 3; ++row) {
        m.push_back({r[3 * row], r[3 * row + 1], r[3 * row + 2], t[static_cast<int>(row)]});
    }
    m.push_back({0.0, 0.0, 0.0, 1.0});
    return m;
}

void write_json(const fs::path& path, const nlohmann::ordered_json& j) {
    const std::string text = j.dump(2) + "\n";
    io::write_file_atomically(path, [&](std::ostream& out) {
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
    });
}

// Progress from COLMAP's log while a stage runs: reads what was appended since the last call.
class LogWatcher {
public:
    LogWatcher(fs::path log, std::string marker, int total)
        : m_log(std::move(log)), m_marker(std::move(marker)), m_total(total) {
        std::error_code ec;
        m_offset = fs::exists(m_log, ec) ? fs::file_size(m_log, ec) : 0;
    }
    // The fraction done, or −1 when unknown.
    double fraction() {
        if (m_marker.empty() || m_total <= 0) {
            return -1.0;
        }
        std::error_code ec;
        const std::uintmax_t size = fs::file_size(m_log, ec);
        if (ec || size <= m_offset) {
            return std::min(1.0, static_cast<double>(m_count) / m_total);
        }
        std::ifstream in(m_log, std::ios::binary);
        in.seekg(static_cast<std::streamoff>(m_offset));
        std::string chunk(static_cast<std::size_t>(size - m_offset), '\0');
        in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        chunk.resize(static_cast<std::size_t>(in.gcount()));
        const std::size_t last_newline = chunk.rfind('\n');
        if (last_newline != std::string::npos) {
            chunk.resize(last_newline + 1);
            m_offset += chunk.size();
            for (std::size_t pos = chunk.find(m_marker); pos != std::string::npos;
                 pos = chunk.find(m_marker, pos + 1)) {
                ++m_count;
            }
        }
        return std::min(1.0, static_cast<double>(m_count) / m_total);
    }

private:
    fs::path m_log;
    std::string m_marker;
    int m_total;
    std::uintmax_t m_offset = 0;
    int m_count = 0;
};

}  // namespace

std::vector<fs::path> list_photos(const fs::path& photos) {
    std::error_code ec;
    if (!fs::is_directory(photos, ec)) {
        throw InvalidInput(fmt::format("{}: not a folder of photos{}", photos.string(),
                                       fs::exists(photos, ec) ? "" : " (it does not exist)"));
    }
    std::vector<fs::path> files;
    for (const fs::directory_entry& e : fs::directory_iterator(photos)) {
        const std::string ext = lower(e.path().extension().string());
        if (e.is_regular_file() && (ext == ".jpg" || ext == ".jpeg" || ext == ".png")) {
            files.push_back(e.path());
        }
    }
    std::sort(files.begin(), files.end());
    return files;
}

PhotoPosesResult recover_photo_poses(const fs::path& photos, const fs::path& out,
                                     const PhotoPosesOptions& options,
                                     const PhotoPosesStageFn& on_stage,
                                     const KeepGoingFn& keep_going) {
    if (options.test_every < 0) {
        throw InvalidInput(
            fmt::format("recover_photo_poses: test_every ({}) must be >= 0", options.test_every));
    }
    if (options.matcher != "auto" && options.matcher != "exhaustive" &&
        options.matcher != "sequential") {
        throw InvalidInput(fmt::format(
            "recover_photo_poses: matcher \"{}\", expected one of auto, exhaustive, sequential",
            options.matcher));
    }
    PhotoPosesResult result;
    constexpr int NUM_STAGES = 5;
    auto stage_start = [&](const std::string& name, int index) {
        if (on_stage) {
            on_stage(name, index, NUM_STAGES, -1.0);
        }
        return std::chrono::steady_clock::now();
    };
    auto stage_end = [&](const std::string& name, std::chrono::steady_clock::time_point start) {
        result.stages.push_back(
            {name,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
    };

    // Step 1: photos and COLMAP, before anything runs.
    auto t = stage_start("photos", 0);
    const std::vector<fs::path> files = list_photos(photos);
    if (files.empty()) {
        throw InvalidInput(fmt::format(
            "{}: no photos (files ending in .jpg, .jpeg or .png) in this folder", photos.string()));
    }
    if (files.size() < 3) {
        throw InvalidInput(fmt::format(
            "{}: {} photos, expected at least 3 (a few dozen around the object work best)",
            photos.string(), files.size()));
    }
    result.num_photos = static_cast<int>(files.size());
    int width = 0, height = 0;
    check_photos(files, photos, width, height);
    const fs::path colmap = options.colmap.empty() ? io::find_program("colmap") : options.colmap;
    if (colmap.empty()) {
        throw IoError(
            "COLMAP is not installed (no `colmap` on $PATH); install it with apt-get install "
            "colmap");
    }
    stage_end("photos", t);

    const fs::path work = out / "colmap";
    fs::create_directories(work);
    const fs::path database = work / "database.db";
    const fs::path sparse = work / "sparse";
    const fs::path log = work / "log.txt";
    fs::remove(database);
    fs::remove(work / "database.db-shm");
    fs::remove(work / "database.db-wal");
    fs::remove_all(sparse);
    fs::remove_all(work / "model");
    fs::create_directories(sparse);
    const std::string threads = std::to_string(options.threads > 0 ? options.threads : -1);
    const fs::path photo_dir = fs::absolute(photos);

    auto run = [&](const std::string& stage, int index, std::vector<std::string> args,
                   const std::string& marker) {
        const auto start = stage_start(stage, index);
        args.insert(args.begin(), colmap.string());
        {
            std::ofstream note(log, std::ios::app);
            note << "\n$";
            for (const std::string& a : args) {
                note << ' ' << a;
            }
            note << "\n";
        }
        LogWatcher watch(log, marker, result.num_photos);
        const io::ChildProcessResult r = io::run_child_process(args, log, [&] {
            if (keep_going && !keep_going()) {
                return false;
            }
            if (on_stage) {
                const double f = watch.fraction();
                if (f >= 0.0) {
                    on_stage(stage, index, NUM_STAGES, f);
                }
            }
            return true;
        });
        if (r.stopped) {
            throw Interrupted(fmt::format(
                "pose recovery stopped during {}; COLMAP's partial work is in {}, no dataset "
                "written",
                stage, work.string()));
        }
        if (r.signaled || r.exit_code != 0) {
            throw IoError(fmt::format(
                "COLMAP {} failed ({}); the end of its log {}:\n{}", args[1],
                r.signaled ? fmt::format("killed by signal {}", r.signal)
                           : fmt::format("exit code {}", r.exit_code),
                log.string(), tail_of(log, 12)));
        }
        stage_end(stage, start);
    };

    // Step 2: COLMAP.
    run("features", 1,
        {"feature_extractor", "--database_path", database.string(), "--image_path",
         photo_dir.string(), "--ImageReader.single_camera", "1", "--ImageReader.camera_model",
         "OPENCV", "--SiftExtraction.use_gpu", "0", "--SiftExtraction.num_threads", threads},
        "Processed file [");
    const bool sequential = options.matcher == "sequential" ||
                            (options.matcher == "auto" && result.num_photos > options.sequential_above);
    run("matching", 2,
        {sequential ? "sequential_matcher" : "exhaustive_matcher", "--database_path",
         database.string(), "--SiftMatching.use_gpu", "0", "--SiftMatching.num_threads", threads},
        "");
    run("mapping", 3,
        {"mapper", "--database_path", database.string(), "--image_path", photo_dir.string(),
         "--output_path", sparse.string(), "--Mapper.num_threads", threads,
         "--Mapper.ba_refine_principal_point", options.refine_principal_point ? "1" : "0"},
        "Registering image #");

    // Step 3: the largest model, as text, read and normalised.
    fs::path best;
    std::uint64_t best_count = 0;
    for (const fs::directory_entry& e : fs::directory_iterator(sparse)) {
        const std::uint64_t n = e.is_directory() ? registered_in(e.path()) : 0;
        if (n > best_count || (n == best_count && !best.empty() && e.path() < best)) {
            best = e.path();
            best_count = n;
        }
    }
    if (best.empty() || best_count == 0) {
        throw InvalidInput(fmt::format(
            "{}: COLMAP registered none of the {} photos (no model in {}); {}", photos.string(),
            result.num_photos, sparse.string(), HELP_REGISTER));
    }
    const fs::path model_dir = work / "model";
    fs::create_directories(model_dir);
    run("export", 4,
        {"model_converter", "--input_path", best.string(), "--output_path", model_dir.string(),
         "--output_type", "TXT"},
        "");
    const auto export_start = std::chrono::steady_clock::now();
    ColmapModel model = read_text_model(model_dir);
    std::sort(model.images.begin(), model.images.end(),
              [](const ColmapImage& a, const ColmapImage& b) { return a.name < b.name; });
    result.num_registered = static_cast<int>(model.images.size());
    {
        std::vector<std::string> registered;
        for (const ColmapImage& im : model.images) {
            registered.push_back(im.name);
        }
        for (const fs::path& f : files) {
            const std::string name = f.filename().string();
            if (!std::binary_search(registered.begin(), registered.end(), name)) {
                result.unregistered.push_back(name);
            }
        }
    }
    if (2 * result.num_registered < result.num_photos) {
        throw InvalidInput(fmt::format(
            "{}: COLMAP registered only {} of {} photos (fewer than half); left out: {}; {}",
            photos.string(), result.num_registered, result.num_photos, join(result.unregistered),
            HELP_REGISTER));
    }
    if (model.width != width || model.height != height) {
        bad_model(model_dir / "cameras.txt",
                  fmt::format("camera {} x {}, photos {} x {}", model.width, model.height, width,
                              height));
    }
    const std::vector<double>& p = model.params;
    result.intrinsics = {model.width, model.height, p[0], p[1], p[2], p[3]};
    result.distortion = {p[4], p[5], p[6], p[7]};
    double error_sum = 0.0;
    std::int64_t observations = 0;
    for (const ColmapPoint& pt : model.points) {
        error_sum += pt.error * pt.track_length;
        observations += pt.track_length;
    }
    result.mean_reprojection_error_px =
        observations > 0 ? error_sum / static_cast<double>(observations) : 0.0;
    result.num_points = static_cast<std::int64_t>(model.points.size());

    std::vector<CameraGL> cameras;
    Vec3d up_sum{};
    for (const ColmapImage& im : model.images) {
        cameras.push_back(camera_to_world_gl(im));
        const Mat3& r = cameras.back().rotation;
        up_sum += Vec3d{r[1], r[4], r[7]};
    }
    const Vec3d center = nearest_to_axes(cameras);
    if (norm(up_sum) < 1e-9) {
        up_sum = {0, 0, 1};
    }
    const Mat3 rotation = rotation_to_z(up_sum / norm(up_sum));
    std::vector<double> distances;
    distances.reserve(cameras.size());
    for (const CameraGL& c : cameras) {
        distances.push_back(norm(c.eye - center));
    }
    const double half_fov =
        std::atan(std::min(0.5 * model.width / p[0], 0.5 * model.height / p[1]));
    const double scale = 1.0 / (median(distances) * std::sin(half_fov));
    result.scale = scale;
    result.rotation = rotation;
    result.colmap_center = center;

    // Step 4: outputs.
    nlohmann::ordered_json base;
    base["camera_model"] = "OPENCV";
    base["fl_x"] = p[0];
    base["fl_y"] = p[1];
    base["cx"] = p[2];
    base["cy"] = p[3];
    base["w"] = model.width;
    base["h"] = model.height;
    base["k1"] = p[4];
    base["k2"] = p[5];
    base["p1"] = p[6];
    base["p2"] = p[7];
    nlohmann::ordered_json train = base, test = base;
    train["frames"] = nlohmann::ordered_json::array();
    test["frames"] = nlohmann::ordered_json::array();
    const fs::path out_abs = fs::absolute(out).lexically_normal();
    for (std::size_t i = 0; i < cameras.size(); ++i) {
        const fs::path photo = (photo_dir / model.images[i].name).lexically_normal();
        const fs::path relative = photo.lexically_relative(out_abs);
        nlohmann::ordered_json frame;
        frame["file_path"] = relative.empty() ? photo.string() : relative.string();
        frame["transform_matrix"] = matrix_json(mul(rotation, cameras[i].rotation),
                                                scale * mul(rotation, cameras[i].eye - center));
        const bool is_test = options.test_every > 0 && i % static_cast<std::size_t>(options.test_every) == 0;
        (is_test ? test : train)["frames"].push_back(frame);
        (is_test ? result.test : result.train).push_back(model.images[i].name);
    }
    std::vector<Vec3f> points;
    std::vector<std::array<std::uint8_t, 3>> colors;
    for (const ColmapPoint& pt : model.points) {
        points.push_back(vec3_cast<float>(scale * mul(rotation, pt.position - center)));
        colors.push_back(pt.color);
    }
    io::write_point_cloud_ply(out / "points.ply", points, colors);
    write_json(out / "transforms_test.json", test);
    write_json(out / "transforms_train.json", train);
    result.stages.back().seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - export_start).count();

    nlohmann::ordered_json& j = result.json;
    j["output"] = out.string();
    j["photos"] = result.num_photos;
    j["registered"] = result.num_registered;
    j["unregistered"] = result.unregistered;
    j["mean_reprojection_error_px"] = result.mean_reprojection_error_px;
    j["points"] = result.num_points;
    j["train"] = result.train.size();
    j["test"] = result.test.size();
    j["matcher"] = sequential ? "sequential" : "exhaustive";
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    double total = 0.0;
    for (const StageTime& s : result.stages) {
        stages[s.name] = s.seconds;
        total += s.seconds;
    }
    j["seconds"] = stages;
    j["total_seconds"] = total;
    nlohmann::ordered_json camera = base;
    j["camera"] = camera;
    nlohmann::ordered_json norm_json;
    norm_json["scale"] = scale;
    norm_json["rotation"] = {{rotation[0], rotation[1], rotation[2]},
                             {rotation[3], rotation[4], rotation[5]},
                             {rotation[6], rotation[7], rotation[8]}};
    norm_json["colmap_center"] = {center.x, center.y, center.z};
    j["dataset_from_colmap"] = norm_json;

    write_json(out / "poses.json", j);
    return result;
}

}  // namespace pliant::pipeline
