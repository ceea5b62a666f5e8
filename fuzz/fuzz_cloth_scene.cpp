// libFuzzer harness: pipeline::read_cloth_scene (scene JSON; mesh files are not opened by the
// reader).
#include "fuzz_input.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("scene.json", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] { pliant::pipeline::read_cloth_scene(path); });
    return 0;
}
