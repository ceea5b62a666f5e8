// libFuzzer harness: the checkpoint reader. The first byte picks the part under test, the rest is
// its input: even, io::decode_checkpoint (header, sizes, kind, CRC); odd, the cloth state a
// CRC-valid checkpoint carries (pipeline::ClothSimulation::load_state, core/bytes.hpp's
// bounds-checked reads) into a 4 × 4 sheet over a sphere with self-collision.
#include <span>

#include "fuzz_input.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/io/checkpoint.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) {
        return 0;
    }
    const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data) + 1, size - 1);
    if (data[0] % 2 == 0) {
        pliant::fuzz::expect_result_or_error(
            [&] { pliant::io::decode_checkpoint(bytes, "checkpoint.bin"); });
        return 0;
    }
    static const pliant::cloth::ClothScene scene = pliant::pipeline::parse_cloth_scene(
        R"({"cloth": {"grid": {"size": [1, 1], "quads": [4, 4]}, "translate": [0, 0, 0.6]},
            "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.3}}], "substeps": 12})",
        "fuzz.json", ".");
    pliant::fuzz::expect_result_or_error([&] {
        pliant::pipeline::ClothSimulation sim =
            pliant::pipeline::ClothSimulation::from_scene(scene, "fuzz.json");
        pliant::ByteReader in(bytes, "checkpoint.bin");
        sim.load_state(in);
    });
    return 0;
}
