#include "pliant/io/colmap_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <ostream>
#include <unordered_map>
#include <unordered_set>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/output_directory.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the COLMAP binary reader assumes a little-endian host");

struct ModelInfo {
    std::string_view name;
    int num_params;
};
// COLMAP's camera models by id (src/colmap/sensor/models.h).
constexpr std::array<ModelInfo, 11> MODELS = {{
    {"SIMPLE_PINHOLE", 3},
    {"PINHOLE", 4},
    {"SIMPLE_RADIAL", 4},
    {"RADIAL", 5},
    {"OPENCV", 8},
    {"OPENCV_FISHEYE", 8},
    {"FULL_OPENCV", 12},
    {"FOV", 5},
    {"SIMPLE_RADIAL_FISHEYE", 4},
    {"RADIAL_FISHEYE", 5},
    {"THIN_PRISM_FISHEYE", 12},
}};

constexpr std::uint64_t MAX_SIDE = 65536;

std::string model_list() {
    std::string s;
    for (std::size_t i = 0; i < MODELS.size(); ++i) {
        s += fmt::format("{}{} {}", i == 0 ? "" : ", ", i, MODELS[i].name);
    }
    return s;
}

// ---- Binary -------------------------------------------------------------------------------

class Reader {
public:
    Reader(std::string_view data, std::string_view name) : m_data(data), m_name(name) {}

    std::size_t left() const { return m_data.size() - m_pos; }

    template <typename T>
    T get(std::string_view what) {
        if (left() < sizeof(T)) {
            throw IoError(fmt::format("{}: {}: truncated at byte {} (needs {} bytes, {} left)",
                                      m_name, what, m_pos, sizeof(T), left()));
        }
        T v;
        std::memcpy(&v, m_data.data() + m_pos, sizeof(T));
        m_pos += sizeof(T);
        return v;
    }
    double real(std::string_view what) {
        const double v = get<double>(what);
        if (!std::isfinite(v)) {
            throw IoError(fmt::format("{}: {}: not a finite number ({})", m_name, what, v));
        }
        return v;
    }
    // A count of records of at least `min_record` bytes each: refused when the bytes left
    // cannot hold that many.
    std::uint64_t count(std::string_view what, std::size_t min_record) {
        const std::uint64_t n = get<std::uint64_t>(what);
        if (n > left() / min_record) {
            throw IoError(
                fmt::format("{}: {} {} would need at least {} bytes each, only {} bytes are left",
                            m_name, n, what, min_record, left()));
        }
        return n;
    }
    std::string c_string(std::string_view what) {
        const std::size_t end = m_data.find('\0', m_pos);
        if (end == std::string_view::npos) {
            throw IoError(fmt::format("{}: {}: no terminating NUL byte", m_name, what));
        }
        std::string s(m_data.substr(m_pos, end - m_pos));
        m_pos = end + 1;
        return s;
    }
    void expect_end() const {
        if (left() != 0) {
            throw IoError(
                fmt::format("{}: {} unexpected bytes after the last record", m_name, left()));
        }
    }

private:
    std::string_view m_data;
    std::string_view m_name;
    std::size_t m_pos = 0;
};

// ---- Text ---------------------------------------------------------------------------------

class Lines {
public:
    Lines(std::string_view text, std::string_view name) : m_text(text), m_name(name) {}

    // The next line (without its end of line), nullopt at the end.
    std::optional<std::string_view> next() {
        if (m_pos >= m_text.size()) {
            return std::nullopt;
        }
        std::size_t end = m_text.find('\n', m_pos);
        if (end == std::string_view::npos) {
            end = m_text.size();
        }
        std::string_view line = m_text.substr(m_pos, end - m_pos);
        if (!line.empty() && line.back() == '\r') {
            line.remove_suffix(1);
        }
        m_pos = end + 1;
        ++m_line;
        return line;
    }
    // The next line that is neither empty nor a comment.
    std::optional<std::string_view> next_record() {
        while (const auto line = next()) {
            const std::string t = detail::trim(*line);
            if (!t.empty() && t[0] != '#') {
                return line;
            }
        }
        return std::nullopt;
    }
    std::size_t line() const { return m_line; }
    IoError error(const std::string& what) const {
        return IoError{fmt::format("{}: line {}: {}", m_name, m_line, what)};
    }

private:
    std::string_view m_text;
    std::string_view m_name;
    std::size_t m_pos = 0;
    std::size_t m_line = 0;
};

double text_real(const Lines& lines, const std::string& token, std::string_view what) {
    double v = 0.0;
    if (detail::parse_real(token, v) != detail::ParseStatus::ok || !std::isfinite(v)) {
        throw lines.error(
            fmt::format("{}: expected a finite number, got {}", what, detail::quote(token)));
    }
    return v;
}

std::int64_t text_integer(const Lines& lines, const std::string& token, std::string_view what,
                          std::int64_t lo, std::int64_t hi) {
    std::int64_t v = 0;
    if (detail::parse_integer(token, v) != detail::ParseStatus::ok || v < lo || v > hi) {
        throw lines.error(fmt::format("{}: expected an integer in [{}, {}], got {}", what, lo, hi,
                                      detail::quote(token)));
    }
    return v;
}

void check_camera(const ColmapCamera& c, const std::string& where) {
    if (c.model_id < 0 || c.model_id >= static_cast<int>(MODELS.size())) {
        throw IoError(fmt::format("{}: camera {}: unknown camera model id {}; known: {}", where,
                                  c.id, c.model_id, model_list()));
    }
    if (c.width < 1 || c.width > MAX_SIDE || c.height < 1 || c.height > MAX_SIDE) {
        throw IoError(fmt::format("{}: camera {}: size {} x {}, expected each in [1, {}]", where,
                                  c.id, c.width, c.height, MAX_SIDE));
    }
    const int n = MODELS[static_cast<std::size_t>(c.model_id)].num_params;
    if (static_cast<int>(c.params.size()) != n) {
        throw IoError(fmt::format("{}: camera {}: model {} has {} parameters, got {}", where, c.id,
                                  MODELS[static_cast<std::size_t>(c.model_id)].name, n,
                                  c.params.size()));
    }
}

void check_quaternion(const ColmapImage& im, const std::string& where) {
    const double n2 = im.qvec[0] * im.qvec[0] + im.qvec[1] * im.qvec[1] + im.qvec[2] * im.qvec[2] +
                      im.qvec[3] * im.qvec[3];
    if (!(n2 > 1e-12)) {
        throw IoError(
            fmt::format("{}: image {} ('{}'): quaternion ({}, {}, {}, {}) has no "
                        "rotation (norm ~0)",
                        where, im.id, im.name, im.qvec[0], im.qvec[1], im.qvec[2], im.qvec[3]));
    }
}

template <typename Id, typename T>
void check_unique(const std::vector<T>& items, std::string_view what, std::string_view where) {
    std::unordered_set<Id> seen;
    seen.reserve(items.size());
    for (const T& item : items) {
        if (!seen.insert(item.id).second) {
            throw IoError(fmt::format("{}: duplicate {} id {}", where, what, item.id));
        }
    }
}

std::filesystem::path file_of(const std::filesystem::path& dir, const char* stem,
                              ColmapFormat format) {
    return dir / (std::string(stem) + (format == ColmapFormat::binary ? ".bin" : ".txt"));
}

std::string fmt_real(double v) {
    return fmt::format("{:.17g}", v);
}

}  // namespace

const ColmapCamera* ColmapModel::find_camera(std::uint32_t id) const {
    for (const ColmapCamera& c : cameras) {
        if (c.id == id) {
            return &c;
        }
    }
    return nullptr;
}

std::optional<std::string_view> colmap_camera_model_name(int model_id) {
    if (model_id < 0 || model_id >= static_cast<int>(MODELS.size())) {
        return std::nullopt;
    }
    return MODELS[static_cast<std::size_t>(model_id)].name;
}

std::optional<int> colmap_camera_model_id(std::string_view name) {
    for (std::size_t i = 0; i < MODELS.size(); ++i) {
        if (MODELS[i].name == name) {
            return static_cast<int>(i);
        }
    }
    return std::nullopt;
}

int colmap_camera_model_num_params(int model_id) {
    if (model_id < 0 || model_id >= static_cast<int>(MODELS.size())) {
        return 0;
    }
    return MODELS[static_cast<std::size_t>(model_id)].num_params;
}

std::vector<ColmapCamera> parse_colmap_cameras(std::string_view content, ColmapFormat format,
                                               std::string_view name) {
    std::vector<ColmapCamera> cameras;
    if (format == ColmapFormat::binary) {
        Reader in(content, name);
        constexpr std::size_t MIN_RECORD = 4 + 4 + 8 + 8 + 3 * 8;
        const std::uint64_t n = in.count("cameras", MIN_RECORD);
        cameras.reserve(n);
        for (std::uint64_t i = 0; i < n; ++i) {
            const std::string what = fmt::format("camera record {}", i);
            ColmapCamera c;
            c.id = static_cast<std::uint32_t>(in.get<std::int32_t>(what));
            c.model_id = in.get<std::int32_t>(what);
            c.width = in.get<std::uint64_t>(what);
            c.height = in.get<std::uint64_t>(what);
            const int np = colmap_camera_model_num_params(c.model_id);
            if (np == 0) {
                throw IoError(
                    fmt::format("{}: {}: camera {}: unknown camera model id {}; known: {}", name,
                                what, c.id, c.model_id, model_list()));
            }
            for (int k = 0; k < np; ++k) {
                c.params.push_back(in.real(what));
            }
            check_camera(c, std::string(name));
            cameras.push_back(std::move(c));
        }
        in.expect_end();
        return cameras;
    }
    Lines lines(content, name);
    while (const auto line = lines.next_record()) {
        const std::vector<std::string> w = detail::words(*line);
        if (w.size() < 4) {
            throw lines.error(fmt::format("expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS..., got {}",
                                          detail::quote(*line)));
        }
        ColmapCamera c;
        c.id = static_cast<std::uint32_t>(
            text_integer(lines, w[0], "CAMERA_ID", 0, std::numeric_limits<std::uint32_t>::max()));
        const std::optional<int> model = colmap_camera_model_id(w[1]);
        if (!model) {
            throw lines.error(fmt::format("unknown camera model {}; known: {}", detail::quote(w[1]),
                                          model_list()));
        }
        c.model_id = *model;
        c.width = static_cast<std::uint64_t>(
            text_integer(lines, w[2], "WIDTH", 1, static_cast<std::int64_t>(MAX_SIDE)));
        c.height = static_cast<std::uint64_t>(
            text_integer(lines, w[3], "HEIGHT", 1, static_cast<std::int64_t>(MAX_SIDE)));
        for (std::size_t k = 4; k < w.size(); ++k) {
            c.params.push_back(text_real(lines, w[k], "camera parameter"));
        }
        check_camera(c, fmt::format("{}: line {}", name, lines.line()));
        cameras.push_back(std::move(c));
    }
    return cameras;
}

std::vector<ColmapImage> parse_colmap_images(std::string_view content, ColmapFormat format,
                                             std::string_view name) {
    std::vector<ColmapImage> images;
    if (format == ColmapFormat::binary) {
        Reader in(content, name);
        constexpr std::size_t MIN_RECORD = 4 + 7 * 8 + 4 + 1 + 8;
        const std::uint64_t n = in.count("images", MIN_RECORD);
        images.reserve(n);
        for (std::uint64_t i = 0; i < n; ++i) {
            const std::string what = fmt::format("image record {}", i);
            ColmapImage im;
            im.id = static_cast<std::uint32_t>(in.get<std::int32_t>(what));
            for (double& q : im.qvec) {
                q = in.real(what);
            }
            for (double& t : im.tvec) {
                t = in.real(what);
            }
            im.camera_id = static_cast<std::uint32_t>(in.get<std::int32_t>(what));
            im.name = in.c_string(what);
            const std::uint64_t np = in.count("2-D points of " + what, 2 * 8 + 8);
            im.points2d.resize(np);
            for (ColmapPoint2D& p : im.points2d) {
                p.x = in.real(what);
                p.y = in.real(what);
                p.point3d_id = in.get<std::int64_t>(what);
            }
            check_quaternion(im, std::string(name));
            images.push_back(std::move(im));
        }
        in.expect_end();
        return images;
    }
    Lines lines(content, name);
    while (const auto line = lines.next_record()) {
        const std::vector<std::string> w = detail::words(*line);
        if (w.size() != 10) {
            throw lines.error(
                fmt::format("expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 words), "
                            "got {} words: {}",
                            w.size(), detail::quote(*line)));
        }
        ColmapImage im;
        im.id = static_cast<std::uint32_t>(
            text_integer(lines, w[0], "IMAGE_ID", 0, std::numeric_limits<std::uint32_t>::max()));
        for (int k = 0; k < 4; ++k) {
            im.qvec[static_cast<std::size_t>(k)] = text_real(lines, w[1 + k], "quaternion");
        }
        for (int k = 0; k < 3; ++k) {
            im.tvec[static_cast<std::size_t>(k)] = text_real(lines, w[5 + k], "translation");
        }
        im.camera_id = static_cast<std::uint32_t>(
            text_integer(lines, w[8], "CAMERA_ID", 0, std::numeric_limits<std::uint32_t>::max()));
        im.name = w[9];
        check_quaternion(im, fmt::format("{}: line {}", name, lines.line()));
        // The points line follows unconditionally (empty when the image has none).
        const auto points = lines.next();
        if (points) {
            const std::vector<std::string> p = detail::words(*points);
            if (p.size() % 3 != 0) {
                throw lines.error(
                    fmt::format("image {}: POINTS2D must be X Y POINT3D_ID triples, got {} words",
                                im.id, p.size()));
            }
            for (std::size_t k = 0; k < p.size(); k += 3) {
                ColmapPoint2D q;
                q.x = text_real(lines, p[k], "2-D point x");
                q.y = text_real(lines, p[k + 1], "2-D point y");
                q.point3d_id = text_integer(lines, p[k + 2], "POINT3D_ID", -1,
                                            std::numeric_limits<std::int64_t>::max());
                im.points2d.push_back(q);
            }
        }
        images.push_back(std::move(im));
    }
    return images;
}

std::vector<ColmapPoint3D> parse_colmap_points(std::string_view content, ColmapFormat format,
                                               std::string_view name) {
    std::vector<ColmapPoint3D> points;
    if (format == ColmapFormat::binary) {
        Reader in(content, name);
        constexpr std::size_t MIN_RECORD = 8 + 3 * 8 + 3 + 8 + 8;
        const std::uint64_t n = in.count("points", MIN_RECORD);
        points.reserve(n);
        for (std::uint64_t i = 0; i < n; ++i) {
            const std::string what = fmt::format("point record {}", i);
            ColmapPoint3D p;
            p.id = in.get<std::uint64_t>(what);
            for (double& x : p.xyz) {
                x = in.real(what);
            }
            for (std::uint8_t& c : p.rgb) {
                c = in.get<std::uint8_t>(what);
            }
            p.error = in.real(what);
            const std::uint64_t nt = in.count("track elements of " + what, 8);
            p.track.resize(nt);
            for (ColmapTrackElement& t : p.track) {
                t.image_id = static_cast<std::uint32_t>(in.get<std::int32_t>(what));
                t.point2d_index = static_cast<std::uint32_t>(in.get<std::int32_t>(what));
            }
            points.push_back(std::move(p));
        }
        in.expect_end();
        return points;
    }
    Lines lines(content, name);
    while (const auto line = lines.next_record()) {
        const std::vector<std::string> w = detail::words(*line);
        if (w.size() < 8 || (w.size() - 8) % 2 != 0) {
            throw lines.error(fmt::format(
                "expected POINT3D_ID X Y Z R G B ERROR then IMAGE_ID POINT2D_IDX pairs, got {} "
                "words",
                w.size()));
        }
        ColmapPoint3D p;
        p.id = static_cast<std::uint64_t>(
            text_integer(lines, w[0], "POINT3D_ID", 0, std::numeric_limits<std::int64_t>::max()));
        for (int k = 0; k < 3; ++k) {
            p.xyz[static_cast<std::size_t>(k)] = text_real(lines, w[1 + k], "point coordinate");
        }
        for (int k = 0; k < 3; ++k) {
            p.rgb[static_cast<std::size_t>(k)] =
                static_cast<std::uint8_t>(text_integer(lines, w[4 + k], "colour", 0, 255));
        }
        p.error = text_real(lines, w[7], "ERROR");
        for (std::size_t k = 8; k < w.size(); k += 2) {
            ColmapTrackElement t;
            t.image_id = static_cast<std::uint32_t>(text_integer(
                lines, w[k], "IMAGE_ID", 0, std::numeric_limits<std::uint32_t>::max()));
            t.point2d_index = static_cast<std::uint32_t>(text_integer(
                lines, w[k + 1], "POINT2D_IDX", 0, std::numeric_limits<std::int32_t>::max()));
            p.track.push_back(t);
        }
        points.push_back(std::move(p));
    }
    return points;
}

void validate_colmap_model(const ColmapModel& model, std::string_view where) {
    check_unique<std::uint32_t>(model.cameras, "camera", where);
    check_unique<std::uint32_t>(model.images, "image", where);
    check_unique<std::uint64_t>(model.points, "3-D point", where);
    std::unordered_map<std::uint32_t, const ColmapImage*> images;
    for (const ColmapImage& im : model.images) {
        if (model.find_camera(im.camera_id) == nullptr) {
            throw IoError(
                fmt::format("{}: image {} ('{}') names camera {}, which the model does "
                            "not have",
                            where, im.id, im.name, im.camera_id));
        }
        images.emplace(im.id, &im);
    }
    if (model.points.empty()) {
        return;  // no points3D: the 2-D points' ids cannot be checked
    }
    std::unordered_set<std::uint64_t> point_ids;
    point_ids.reserve(model.points.size());
    for (const ColmapPoint3D& p : model.points) {
        point_ids.insert(p.id);
        for (const ColmapTrackElement& t : p.track) {
            const auto it = images.find(t.image_id);
            if (it == images.end()) {
                throw IoError(fmt::format(
                    "{}: 3-D point {}: its track names image {}, which the model does not have",
                    where, p.id, t.image_id));
            }
            if (t.point2d_index >= it->second->points2d.size()) {
                throw IoError(fmt::format(
                    "{}: 3-D point {}: its track names 2-D point {} of image "
                    "{}, which has {}",
                    where, p.id, t.point2d_index, t.image_id, it->second->points2d.size()));
            }
        }
    }
    for (const ColmapImage& im : model.images) {
        for (const ColmapPoint2D& q : im.points2d) {
            if (q.point3d_id >= 0 &&
                point_ids.count(static_cast<std::uint64_t>(q.point3d_id)) == 0) {
                throw IoError(
                    fmt::format("{}: image {} ('{}'): a 2-D point names 3-D point {}, "
                                "which the model does not have",
                                where, im.id, im.name, q.point3d_id));
            }
        }
    }
}

bool is_colmap_model_directory(const std::filesystem::path& dir) {
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        return false;
    }
    for (const ColmapFormat f : {ColmapFormat::binary, ColmapFormat::text}) {
        if (std::filesystem::is_regular_file(file_of(dir, "cameras", f), ec) &&
            std::filesystem::is_regular_file(file_of(dir, "images", f), ec)) {
            return true;
        }
    }
    return false;
}

ColmapModel read_colmap_model(const std::filesystem::path& dir) {
    std::error_code ec;
    const ColmapFormat format =
        std::filesystem::is_regular_file(file_of(dir, "cameras", ColmapFormat::binary), ec)
            ? ColmapFormat::binary
            : ColmapFormat::text;
    return read_colmap_model(dir, format);
}

ColmapModel read_colmap_model(const std::filesystem::path& dir, ColmapFormat format) {
    const std::filesystem::path cameras = file_of(dir, "cameras", format);
    const std::filesystem::path images = file_of(dir, "images", format);
    const std::filesystem::path points = file_of(dir, "points3D", format);
    std::error_code ec;
    for (const auto& p : {cameras, images}) {
        if (!std::filesystem::is_regular_file(p, ec)) {
            throw IoError(fmt::format(
                "{}: not a COLMAP model: no {} (expected cameras, images and points3D as .bin or "
                ".txt)",
                dir.string(), p.filename().string()));
        }
    }
    ColmapModel model;
    model.cameras = parse_colmap_cameras(read_file(cameras), format, cameras.string());
    model.images = parse_colmap_images(read_file(images), format, images.string());
    if (std::filesystem::is_regular_file(points, ec)) {
        model.points = parse_colmap_points(read_file(points), format, points.string());
    }
    validate_colmap_model(model, dir.string());
    return model;
}

void write_colmap_model(const std::filesystem::path& dir, const ColmapModel& model,
                        ColmapFormat format) {
    make_output_directory(dir);
    if (format == ColmapFormat::text) {
        write_file_atomically(file_of(dir, "cameras", format), [&](std::ostream& out) {
            out << "# Camera list with one line of data per camera:\n"
                   "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
            for (const ColmapCamera& c : model.cameras) {
                out << c.id << ' ' << colmap_camera_model_name(c.model_id).value_or("UNKNOWN")
                    << ' ' << c.width << ' ' << c.height;
                for (const double p : c.params) {
                    out << ' ' << fmt_real(p);
                }
                out << '\n';
            }
        });
        write_file_atomically(file_of(dir, "images", format), [&](std::ostream& out) {
            out << "# Image list with two lines of data per image:\n"
                   "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
                   "#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
            for (const ColmapImage& im : model.images) {
                out << im.id;
                for (const double q : im.qvec) {
                    out << ' ' << fmt_real(q);
                }
                for (const double t : im.tvec) {
                    out << ' ' << fmt_real(t);
                }
                out << ' ' << im.camera_id << ' ' << im.name << '\n';
                for (std::size_t k = 0; k < im.points2d.size(); ++k) {
                    const ColmapPoint2D& p = im.points2d[k];
                    out << (k == 0 ? "" : " ") << fmt_real(p.x) << ' ' << fmt_real(p.y) << ' '
                        << p.point3d_id;
                }
                out << '\n';
            }
        });
        write_file_atomically(file_of(dir, "points3D", format), [&](std::ostream& out) {
            out << "# 3D point list with one line of data per point:\n"
                   "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, "
                   "POINT2D_IDX)\n";
            for (const ColmapPoint3D& p : model.points) {
                out << p.id << ' ' << fmt_real(p.xyz[0]) << ' ' << fmt_real(p.xyz[1]) << ' '
                    << fmt_real(p.xyz[2]) << ' ' << int{p.rgb[0]} << ' ' << int{p.rgb[1]} << ' '
                    << int{p.rgb[2]} << ' ' << fmt_real(p.error);
                for (const ColmapTrackElement& t : p.track) {
                    out << ' ' << t.image_id << ' ' << t.point2d_index;
                }
                out << '\n';
            }
        });
        return;
    }
    const auto put = [](std::ostream& out, const auto& v) {
        out.write(reinterpret_cast<const char*>(&v), sizeof(v));
    };
    write_file_atomically(file_of(dir, "cameras", format), [&](std::ostream& out) {
        put(out, static_cast<std::uint64_t>(model.cameras.size()));
        for (const ColmapCamera& c : model.cameras) {
            put(out, static_cast<std::int32_t>(c.id));
            put(out, static_cast<std::int32_t>(c.model_id));
            put(out, c.width);
            put(out, c.height);
            for (const double p : c.params) {
                put(out, p);
            }
        }
    });
    write_file_atomically(file_of(dir, "images", format), [&](std::ostream& out) {
        put(out, static_cast<std::uint64_t>(model.images.size()));
        for (const ColmapImage& im : model.images) {
            put(out, static_cast<std::int32_t>(im.id));
            for (const double q : im.qvec) {
                put(out, q);
            }
            for (const double t : im.tvec) {
                put(out, t);
            }
            put(out, static_cast<std::int32_t>(im.camera_id));
            out.write(im.name.c_str(), static_cast<std::streamsize>(im.name.size() + 1));
            put(out, static_cast<std::uint64_t>(im.points2d.size()));
            for (const ColmapPoint2D& p : im.points2d) {
                put(out, p.x);
                put(out, p.y);
                put(out, p.point3d_id);
            }
        }
    });
    write_file_atomically(file_of(dir, "points3D", format), [&](std::ostream& out) {
        put(out, static_cast<std::uint64_t>(model.points.size()));
        for (const ColmapPoint3D& p : model.points) {
            put(out, p.id);
            for (const double x : p.xyz) {
                put(out, x);
            }
            for (const std::uint8_t c : p.rgb) {
                put(out, c);
            }
            put(out, p.error);
            put(out, static_cast<std::uint64_t>(p.track.size()));
            for (const ColmapTrackElement& t : p.track) {
                put(out, static_cast<std::int32_t>(t.image_id));
                put(out, static_cast<std::int32_t>(t.point2d_index));
            }
        }
    });
}

}  // namespace pliant::io
