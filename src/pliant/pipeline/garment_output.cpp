#include "pliant/pipeline/garment_output.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <span>
#include <string>
#include <system_error>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/mdd.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/pc2.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::pipeline {

int copy_material_libraries(const io::PolygonMesh& garment, const std::filesystem::path& source_dir,
                            const std::filesystem::path& frames_dir,
                            const std::string& scene_name) {
    int copied = 0;
    for (const std::string& line : garment.material_libraries) {
        for (const std::string& name : io::detail::words(line)) {
            const std::filesystem::path source = source_dir / name;
            const std::filesystem::path target =
                frames_dir / std::filesystem::path(name).filename();
            std::string bytes;
            try {
                bytes = io::read_file(source);
            } catch (const IoError& e) {
                log_warning(
                    "{}: the garment's material library {} is not copied beside the "
                    "frames: {}",
                    scene_name, name, e.what());
                continue;
            }
            std::error_code ec;
            if (std::filesystem::is_regular_file(target, ec)) {
                try {
                    if (io::read_file(target) == bytes) {
                        continue;
                    }
                } catch (const IoError&) {  // replaced below
                }
            }
            io::write_file_atomically(target, [&](std::ostream& out) {
                out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
            });
            ++copied;
        }
    }
    return copied;
}

std::string point_cache_file_name(const std::string& kind) {
    if (kind != "pc2" && kind != "mdd") {
        throw InvalidInput(
            fmt::format("point cache '{}': unknown kind, expected one of pc2, mdd", kind));
    }
    return "cloth." + kind;
}

void write_point_cache_from_frames(const std::filesystem::path& path, const std::string& kind,
                                   int last_frame, double frames_per_second,
                                   const std::function<std::filesystem::path(int)>& frame_file) {
    point_cache_file_name(kind);  // checks the kind
    const geometry::TriangleMeshD first = io::read_mesh(frame_file(0));
    const auto num_points = static_cast<std::int64_t>(first.positions.size());
    const auto sample = [&](std::int64_t s, std::span<Vec3f> out) {
        const geometry::TriangleMeshD frame =
            s == 0 ? first : io::read_mesh(frame_file(static_cast<int>(s)));
        if (frame.positions.size() != out.size()) {
            throw InvalidInput(fmt::format(
                "{}: {} vertices, expected {} (frame 0's) for the point cache",
                frame_file(static_cast<int>(s)).string(), frame.positions.size(), out.size()));
        }
        for (std::size_t v = 0; v < out.size(); ++v) {
            out[v] = vec3_cast<float>(frame.positions[v]);
        }
    };
    if (kind == "pc2") {
        io::write_pc2(path, num_points, last_frame + 1, 0.0, sample);
    } else {
        io::write_mdd(path, num_points, last_frame + 1, frames_per_second, sample);
    }
}

}  // namespace pliant::pipeline
