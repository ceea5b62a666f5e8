// COLMAP sparse reconstructions ("models": a directory such as sparse/0 holding `cameras`,
// `images` and `points3D`, as .bin or .txt), read and written as COLMAP 3.x does
// (https://colmap.github.io/format.html; docs/formats.md, "COLMAP sparse models").
//
// Text: '#' lines are comments.
//   cameras.txt   CAMERA_ID MODEL WIDTH HEIGHT PARAMS…
//   images.txt    IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then ONE line (possibly empty)
//                 of POINTS2D as X Y POINT3D_ID triples (POINT3D_ID −1: no 3-D point)
//   points3D.txt  POINT3D_ID X Y Z R G B ERROR TRACK… as IMAGE_ID POINT2D_IDX pairs
// Binary (little-endian, packed):
//   cameras.bin   uint64 count; per camera: int32 camera_id, int32 model_id, uint64 width,
//                 uint64 height, double params[num_params(model_id)]
//   images.bin    uint64 count; per image: int32 image_id, double qvec[4] (w, x, y, z),
//                 double tvec[3], int32 camera_id, NAME as NUL-terminated bytes, uint64
//                 num_points2D, per point: double x, double y, int64 point3D_id
//   points3D.bin  uint64 count; per point: uint64 point3D_id, double xyz[3], uint8 rgb[3],
//                 double error, uint64 track_length, per element: int32 image_id, int32
//                 point2D_idx
//
// Pose convention: the image's world-to-camera transform x_cam = R(q) x_world + t, camera axes
// x right, y down, z forward (nerf/colmap_poses.hpp converts to camera-to-world OpenGL axes).
// Camera models are COLMAP's ids 0–10 with their parameter counts (colmap_camera_model_*);
// nerf/lens.hpp implements the ones a radiance field can use.
//
// Errors (IoError "<file>: <line N | record i>: …"): a missing cameras or images file (points3D
// is optional: an empty point list), counts larger than the bytes left can hold, truncated
// records, unknown model ids or names, a parameter count that does not match the model, non-finite
// numbers, a zero quaternion, sizes outside [1, 65536], duplicate ids, an image naming a missing
// camera, a track naming a missing image or 2-D point, a 2-D point naming a missing 3-D point.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::io {

struct ColmapCamera {
    std::uint32_t id = 0;
    int model_id = 0;  // COLMAP's id: 0 SIMPLE_PINHOLE, 1 PINHOLE, … 4 OPENCV, 5 OPENCV_FISHEYE
    std::uint64_t width = 0;  // pixels
    std::uint64_t height = 0;
    std::vector<double> params;  // in COLMAP's order for the model (f, cx, cy, k …)
};

struct ColmapPoint2D {
    double x = 0.0, y = 0.0;       // pixels, COLMAP's convention (top-left pixel's centre at 0.5)
    std::int64_t point3d_id = -1;  // −1: not triangulated
};

struct ColmapImage {
    std::uint32_t id = 0;
    std::array<double, 4> qvec{1.0, 0.0, 0.0, 0.0};  // world-to-camera rotation (w, x, y, z)
    std::array<double, 3> tvec{0.0, 0.0, 0.0};       // world-to-camera translation
    std::uint32_t camera_id = 0;
    std::string name;  // the photo's path relative to the image directory
    std::vector<ColmapPoint2D> points2d;
};

struct ColmapTrackElement {
    std::uint32_t image_id = 0;
    std::uint32_t point2d_index = 0;
};

struct ColmapPoint3D {
    std::uint64_t id = 0;
    std::array<double, 3> xyz{0.0, 0.0, 0.0};
    std::array<std::uint8_t, 3> rgb{0, 0, 0};
    double error = 0.0;  // mean reprojection error, pixels
    std::vector<ColmapTrackElement> track;
};

struct ColmapModel {
    std::vector<ColmapCamera> cameras;  // in file order
    std::vector<ColmapImage> images;
    std::vector<ColmapPoint3D> points;

    const ColmapCamera* find_camera(std::uint32_t id) const;  // nullptr when absent
};

// COLMAP's model name for an id ("OPENCV"), nullopt for an unknown id; and back.
std::optional<std::string_view> colmap_camera_model_name(int model_id);
std::optional<int> colmap_camera_model_id(std::string_view name);
// Number of parameters of a known model id (0 for an unknown one).
int colmap_camera_model_num_params(int model_id);

enum class ColmapFormat { text, binary };

// Reads `dir`/cameras, images, points3D: binary when cameras.bin exists, else text. The result
// passes the cross-reference checks above.
ColmapModel read_colmap_model(const std::filesystem::path& dir);
ColmapModel read_colmap_model(const std::filesystem::path& dir, ColmapFormat format);

// Whether `dir` holds a COLMAP model (cameras.bin or cameras.txt, and images of the same kind).
bool is_colmap_model_directory(const std::filesystem::path& dir);

// Parsers of one file's content, `name` used in messages (for tests and fuzzing); they check the
// records, not the cross references (validate_colmap_model does).
std::vector<ColmapCamera> parse_colmap_cameras(std::string_view content, ColmapFormat format,
                                               std::string_view name);
std::vector<ColmapImage> parse_colmap_images(std::string_view content, ColmapFormat format,
                                             std::string_view name);
std::vector<ColmapPoint3D> parse_colmap_points(std::string_view content, ColmapFormat format,
                                               std::string_view name);
// The cross-reference checks; IoError naming `where`.
void validate_colmap_model(const ColmapModel& model, std::string_view where);

// Writes cameras, images and points3D in `format` into `dir` (created if missing), each file
// atomically; numbers with 17 significant digits so that text round-trips exactly.
void write_colmap_model(const std::filesystem::path& dir, const ColmapModel& model,
                        ColmapFormat format);

}  // namespace pliant::io
