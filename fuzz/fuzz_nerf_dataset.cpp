// libFuzzer harness: pipeline::read_nerf_dataset (transforms.json + its images), then the dataset's
// scene box; the input is the JSON, a NUL byte, then an image file the JSON may name as
// "file_path": "img" (or "img.png"). Decoded images are limited to MAX_BYTES.
#include "fuzz_input.hpp"
#include "pliant/pipeline/nerf_dataset_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto [json, image] =
        pliant::fuzz::split_at_nul({reinterpret_cast<const char*>(data), size});
    pliant::fuzz::write_input("img.png", image);
    const auto path = pliant::fuzz::write_input("transforms.json", json);
    pliant::fuzz::expect_result_or_error([&] {
        pliant::pipeline::ReadNerfDatasetOptions options;
        options.max_bytes = pliant::fuzz::MAX_BYTES;
        const pliant::nerf::Dataset ds = pliant::pipeline::read_nerf_dataset(path, options);
        (void)pliant::nerf::scene_box(ds);
    });
    return 0;
}
