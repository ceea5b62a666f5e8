#include "pliant/io/transfer_function_json.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "pliant/core/error.hpp"

namespace pliant::io {
namespace {

constexpr const char* GOOD = R"({
  "name": "bone",
  "opacity_unit": 0.5,
  "color": [{"value": 150, "rgb": [0.8, 0.45, 0.3]}, {"value": 1500, "rgb": [1, 1, 1]}],
  "opacity": [{"value": 150, "alpha": 0}, {"value": 1500, "alpha": 0.8}]
})";

TEST(TransferFunctionJson, ReadsTheDocumentedFormat) {
    const volume::TransferFunction tf = parse_transfer_function(GOOD, "bone.json");
    EXPECT_EQ(tf.name, "bone");
    EXPECT_EQ(tf.opacity_unit, 0.5);
    ASSERT_EQ(tf.color.size(), 2u);
    EXPECT_EQ(tf.color[0].value, 150.0);
    EXPECT_EQ(tf.color[0].rgb[1], 0.45f);
    ASSERT_EQ(tf.opacity.size(), 2u);
    EXPECT_EQ(tf.opacity[1].alpha, 0.8f);
    EXPECT_FLOAT_EQ(tf.evaluate(825.0)[3], 0.4f);
    // Name and unit are optional: the file name, and 0 (the smallest voxel spacing).
    const volume::TransferFunction minimal = parse_transfer_function(
        R"({"color": [{"value": 0, "rgb": [0, 0, 0]}], "opacity": [{"value": 0, "alpha": 1}]})",
        "min.json");
    EXPECT_EQ(minimal.name, "min.json");
    EXPECT_EQ(minimal.opacity_unit, 0.0);
}

TEST(TransferFunctionJson, ReadsFiles) {
    const auto path = std::filesystem::temp_directory_path() / "pliant_tf_json_test.json";
    {
        std::ofstream out(path);
        out << GOOD;
    }
    EXPECT_EQ(read_transfer_function(path).color.size(), 2u);
    std::filesystem::remove(path);
    EXPECT_THROW(read_transfer_function(path), IoError);
}

void expect_error(const std::string& text, const std::string& needle) {
    try {
        parse_transfer_function(text, "tf.json");
        ADD_FAILURE() << "no error for " << text;
    } catch (const IoError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("tf.json: ", 0), 0u) << what;
        EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
}

TEST(TransferFunctionJson, BrokenInputsNameTheKeyPath) {
    const std::string color = R"("color": [{"value": 0, "rgb": [0, 0, 0]}])";
    const std::string opacity = R"("opacity": [{"value": 0, "alpha": 0.5}])";
    expect_error("{", "not valid JSON");
    expect_error("", "not valid JSON");
    expect_error("[1, 2]", "a JSON object");
    expect_error(R"({"color": [{"value": 1e999, "rgb": [0, 0, 0]}], )" + opacity + "}",
                 "not valid JSON");
    expect_error("{" + opacity + "}", "color: expected a required array");
    expect_error("{" + color + "}", "opacity: expected a required array");
    expect_error(R"({"color": [], )" + opacity + "}", "color: expected a non-empty array");
    expect_error(R"({"color": 3, )" + opacity + "}", "got an integer");
    expect_error("{" + color + ", " + opacity + R"(, "colour": 1})", "colour: expected one of");
    expect_error(R"({"color": [{"value": 0, "rgb": [0, 0, 0], "a": 1}], )" + opacity + "}",
                 "color[0].a");
    expect_error(R"({"color": [{"rgb": [0, 0, 0]}], )" + opacity + "}",
                 "color[0].value: expected a required number");
    expect_error(R"({"color": [{"value": "1", "rgb": [0, 0, 0]}], )" + opacity + "}",
                 "color[0].value: expected a finite number, got a JSON string");
    expect_error(R"({"color": [{"value": 0, "rgb": [0, 0]}], )" + opacity + "}",
                 "color[0].rgb: expected an array of 3 numbers");
    expect_error(R"({"color": [{"value": 0, "rgb": [0, 1.5, 0]}], )" + opacity + "}",
                 "color[0].rgb[1]: expected a number in [0, 1], got 1.5");
    expect_error("{" + color + R"(, "opacity": [{"value": 0, "alpha": -0.1}]})",
                 "opacity[0].alpha: expected a number in [0, 1]");
    expect_error("{" + color + R"(, "opacity": [{"value": 0}]})",
                 "opacity[0].alpha: expected a required number");
    expect_error(
        "{" + color + R"(, "opacity": [{"value": 5, "alpha": 0}, {"value": 1, "alpha": 0}]})",
        "opacity[1]: value 1 is less than the previous point's 5");
    expect_error("{" + color + ", " + opacity + R"(, "opacity_unit": 0})", "opacity_unit");
    expect_error("{" + color + ", " + opacity + R"(, "opacity_unit": "mm"})", "opacity_unit");
    expect_error("{" + color + ", " + opacity + R"(, "name": 7})", "name: expected a string");
}

}  // namespace
}  // namespace pliant::io
