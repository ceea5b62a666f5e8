// libFuzzer harness: io::read_transfer_function (JSON), then validate + evaluate the result.
#include "fuzz_input.hpp"
#include "pliant/io/transfer_function_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path =
        pliant::fuzz::write_input("tf.json", {reinterpret_cast<const char*>(data), size});
    pliant::fuzz::expect_result_or_error([&] {
        const pliant::volume::TransferFunction tf = pliant::io::read_transfer_function(path);
        tf.validate();
        for (double v : {-1e30, -1.0, 0.0, 0.5, 1.0, 1e30}) {
            (void)tf.evaluate(v);
        }
    });
    return 0;
}
