// libFuzzer harness: io::read_colmap_model (text and binary) and nerf::transforms_from_colmap.
// Input: one byte choosing the format (even: .txt, odd: .bin), then the cameras, images and
// points3D files separated by the marker "\n@@@\n" (missing parts: empty files; a fourth part:
// no points3D file).
#include <filesystem>
#include <string>

#include "fuzz_input.hpp"
#include "pliant/io/colmap_model.hpp"
#include "pliant/nerf/colmap_poses.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) {
        return 0;
    }
    const bool binary = (data[0] & 1) != 0;
    std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
    constexpr std::string_view MARKER = "\n@@@\n";
    std::string_view parts[4];
    int num_parts = 0;
    while (num_parts < 3) {
        const std::size_t at = rest.find(MARKER);
        if (at == std::string_view::npos) {
            break;
        }
        parts[num_parts++] = rest.substr(0, at);
        rest.remove_prefix(at + MARKER.size());
    }
    parts[num_parts++] = rest;
    const std::filesystem::path dir = pliant::fuzz::scratch() / "model";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::string ext = binary ? ".bin" : ".txt";
    const char* names[3] = {"cameras", "images", "points3D"};
    for (int i = 0; i < 3; ++i) {
        if (i == 2 && num_parts == 4) {
            break;  // no points3D
        }
        pliant::fuzz::write_input("model/" + std::string(names[i]) + ext, parts[i]);
    }
    pliant::fuzz::expect_result_or_error([&] {
        const pliant::io::ColmapModel model = pliant::io::read_colmap_model(dir);
        (void)pliant::nerf::transforms_from_colmap(model);
    });
    return 0;
}
