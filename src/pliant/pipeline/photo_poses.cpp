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
#include "pliant/io/colmap_model.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/ply.hpp"
#include "pliant/io/read_file.hpp"
#include "pliant/nerf/colmap_poses.hpp"

namespace pliant::pipeline {
namespace fs = std::filesystem;
namespace {

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

nlohmann::ordered_json matrix_json(const nerf::Pose& pose) {
    nlohmann::ordered_json m = nlohmann::ordered_json::array();
    for (std::size_t row = 0; row < 3; ++row) {
        m.push_back(
            {pose.m[4 * row], pose.m[4 * row + 1], pose.m[4 * row + 2], pose.m[4 * row + 3]});
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
    io::make_output_directory(out);
    io::make_output_directory(work);
    const fs::path database = work / "database.db";
    const fs::path sparse = work / "sparse";
    const fs::path log = work / "log.txt";
    fs::remove(database);
    fs::remove(work / "database.db-shm");
    fs::remove(work / "database.db-wal");
    fs::remove_all(sparse);
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
            throw IoError(fmt::format("COLMAP {} failed ({}); the end of its log {}:\n{}", args[1],
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
    const bool sequential =
        options.matcher == "sequential" ||
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

    // Step 3: the model registering the most photos, read (io/colmap_model) and normalised
    // (nerf/colmap_poses).
    const auto export_start = stage_start("export", 4);
    io::ColmapModel model;
    fs::path best;
    for (const fs::directory_entry& e : fs::directory_iterator(sparse)) {
        if (!e.is_directory() || !io::is_colmap_model_directory(e.path())) {
            continue;
        }
        io::ColmapModel m = io::read_colmap_model(e.path());
        if (m.images.size() > model.images.size() ||
            (m.images.size() == model.images.size() && !best.empty() && e.path() < best)) {
            model = std::move(m);
            best = e.path();
        }
    }
    if (model.images.empty()) {
        throw InvalidInput(
            fmt::format("{}: COLMAP registered none of the {} photos (no model in {}); {}",
                        photos.string(), result.num_photos, sparse.string(), HELP_REGISTER));
    }
    result.num_registered = static_cast<int>(model.images.size());
    {
        std::vector<std::string> registered;
        registered.reserve(model.images.size());
        for (const io::ColmapImage& im : model.images) {
            registered.push_back(im.name);
        }
        std::sort(registered.begin(), registered.end());
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
    double error_sum = 0.0;
    std::int64_t observations = 0;
    for (const io::ColmapPoint3D& pt : model.points) {
        const auto n = static_cast<std::int64_t>(pt.track.size());
        error_sum += pt.error * static_cast<double>(n);
        observations += n;
    }
    result.mean_reprojection_error_px =
        observations > 0 ? error_sum / static_cast<double>(observations) : 0.0;
    result.num_points = static_cast<std::int64_t>(model.points.size());

    nerf::ColmapConversionOptions conversion;
    conversion.orient_up = true;
    const nerf::ColmapTransforms transforms = nerf::transforms_from_colmap(model, conversion);
    const nerf::Intrinsics& in = transforms.frames.front().intrinsics;
    if (in.width != width || in.height != height) {
        throw IoError(fmt::format("{}: COLMAP's camera is {} x {}, the photos {} x {}",
                                  best.string(), in.width, in.height, width, height));
    }
    result.intrinsics = in;
    result.world_from_colmap = transforms.world_from_colmap;
    result.scale = transforms.scale;

    // Step 4: outputs.
    nlohmann::ordered_json base;
    base["camera_model"] = "OPENCV";
    base["fl_x"] = in.fx;
    base["fl_y"] = in.fy;
    base["cx"] = in.cx;
    base["cy"] = in.cy;
    base["w"] = in.width;
    base["h"] = in.height;
    base["k1"] = in.lens.k1;
    base["k2"] = in.lens.k2;
    base["p1"] = in.lens.p1;
    base["p2"] = in.lens.p2;
    // The scene box `nerf train` reconstructs: the unit box the normalization fills with the
    // sparse points; rays leaving it see the background (--environment).
    base["aabb"] = {{-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0}};
    nlohmann::ordered_json train = base, test = base;
    train["frames"] = nlohmann::ordered_json::array();
    test["frames"] = nlohmann::ordered_json::array();
    const fs::path out_abs = fs::absolute(out).lexically_normal();
    for (std::size_t i = 0; i < transforms.frames.size(); ++i) {
        const nerf::ColmapFrame& frame = transforms.frames[i];
        const fs::path photo = (photo_dir / frame.file_path).lexically_normal();
        const fs::path relative = photo.lexically_relative(out_abs);
        nlohmann::ordered_json f;
        f["file_path"] = relative.empty() ? photo.string() : relative.string();
        f["transform_matrix"] = matrix_json(frame.camera_to_world);
        const bool is_test =
            options.test_every > 0 && i % static_cast<std::size_t>(options.test_every) == 0;
        (is_test ? test : train)["frames"].push_back(f);
        (is_test ? result.test : result.train).push_back(frame.file_path);
    }
    std::vector<Vec3f> points;
    points.reserve(transforms.points.size());
    for (const Vec3d& pt : transforms.points) {
        points.push_back(vec3_cast<float>(pt));
    }
    io::write_point_cloud_ply(out / "points.ply", points, transforms.point_colors);
    write_json(out / "transforms_test.json", test);
    write_json(out / "transforms_train.json", train);
    stage_end("export", export_start);

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
    const std::array<double, 12>& w = result.world_from_colmap;
    j["dataset_from_colmap"] = {{w[0], w[1], w[2], w[3]},
                                {w[4], w[5], w[6], w[7]},
                                {w[8], w[9], w[10], w[11]},
                                {0.0, 0.0, 0.0, 1.0}};

    write_json(out / "poses.json", j);
    return result;
}

}  // namespace pliant::pipeline
