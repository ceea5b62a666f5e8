// libFuzzer harness: io::read_mesh, the reader every command that needs a mesh uses (the
// extension dispatch and the rule that a mesh holds at least one triangle). The first byte picks
// the extension (even: .obj, odd: .ply); the rest is the file.
#include "fuzz_input.hpp"
#include "pliant/io/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) {
        return 0;
    }
    const char* name = (data[0] & 1U) == 0 ? "in.obj" : "in.ply";
    const auto path =
        pliant::fuzz::write_input(name, {reinterpret_cast<const char*>(data) + 1, size - 1});
    pliant::fuzz::expect_result_or_error([&] { pliant::io::read_mesh(path); });
    return 0;
}
