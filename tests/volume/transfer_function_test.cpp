#include "pliant/volume/transfer_function.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/volume/generate.hpp"

namespace pliant::volume {
namespace {

TransferFunction ramp() {
    TransferFunction tf;
    tf.name = "ramp";
    tf.color = {{0.0, {0.0f, 0.0f, 1.0f}}, {10.0, {1.0f, 0.0f, 0.0f}}};
    tf.opacity = {{2.0, 0.0f}, {4.0, 0.5f}, {4.0, 0.8f}, {6.0, 1.0f}};
    return tf;
}

TEST(TransferFunction, InterpolatesAndClampsAtTheEnds) {
    const TransferFunction tf = ramp();
    EXPECT_NO_THROW(tf.validate());
    EXPECT_EQ(tf.evaluate(-5.0), (std::array<float, 4>{0.0f, 0.0f, 1.0f, 0.0f}));
    EXPECT_EQ(tf.evaluate(100.0), (std::array<float, 4>{1.0f, 0.0f, 0.0f, 1.0f}));
    const auto mid = tf.evaluate(2.5);
    EXPECT_FLOAT_EQ(mid[0], 0.25f);
    EXPECT_FLOAT_EQ(mid[2], 0.75f);
    EXPECT_FLOAT_EQ(mid[3], 0.125f);
    // A step at 4: just below interpolates towards 0.5, at and above it starts from 0.8.
    EXPECT_NEAR(tf.evaluate(4.0 - 1e-9)[3], 0.5f, 1e-6f);
    EXPECT_FLOAT_EQ(tf.evaluate(4.0)[3], 0.8f);
    EXPECT_FLOAT_EQ(tf.evaluate(5.0)[3], 0.9f);
    EXPECT_EQ(tf.evaluate(std::nan(""))[3], 0.0f);
    TransferFunction one;
    one.color = {{3.0, {0.5f, 0.5f, 0.5f}}};
    one.opacity = {{3.0, 0.25f}};
    EXPECT_EQ(one.evaluate(-1e30), (std::array<float, 4>{0.5f, 0.5f, 0.5f, 0.25f}));
    EXPECT_EQ(one.evaluate(3.0), one.evaluate(1e30));
}

void expect_invalid(const TransferFunction& tf, const std::string& needle) {
    try {
        tf.validate();
        ADD_FAILURE() << "no error for " << needle;
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

TEST(TransferFunction, ValidationNamesThePoint) {
    TransferFunction tf = ramp();
    tf.opacity[2].value = 3.0;
    expect_invalid(tf, "opacity[2]");
    tf = ramp();
    tf.color[1].rgb[1] = 1.5f;
    expect_invalid(tf, "color[1]: rgb[1]");
    tf = ramp();
    tf.opacity[0].alpha = std::numeric_limits<float>::quiet_NaN();
    expect_invalid(tf, "opacity[0]");
    tf = ramp();
    tf.color[0].value = std::numeric_limits<double>::infinity();
    expect_invalid(tf, "color[0]");
    tf = ramp();
    tf.opacity.clear();
    expect_invalid(tf, "opacity");
    tf = ramp();
    tf.opacity_unit = -1.0;
    expect_invalid(tf, "opacity_unit");
}

TEST(OpacityCorrection, HalfStepsComposeToAFullStep) {
    for (const double a : {1e-6, 0.01, 0.3, 0.5, 0.9, 0.999999}) {
        for (const double step : {1e-6, 0.01, 0.5, 1.0, 3.0}) {
            const double half = corrected_opacity(a, step / 2, 1.0);
            const double full = corrected_opacity(a, step, 1.0);
            EXPECT_NEAR(1.0 - (1.0 - half) * (1.0 - half), full, 1e-15 + 1e-12 * full)
                << a << " " << step;
        }
    }
    EXPECT_EQ(corrected_opacity(0.0, 0.5, 1.0), 0.0);
    EXPECT_EQ(corrected_opacity(1.0, 0.5, 1.0), 1.0);
    EXPECT_EQ(corrected_opacity(1.0, 1e-12, 1.0), 1.0);
    EXPECT_EQ(corrected_opacity(0.3, 0.0, 1.0), 0.0);
    EXPECT_EQ(corrected_opacity(0.3, 2.0, 2.0), 0.3);
    EXPECT_DOUBLE_EQ(corrected_opacity(0.5, 2.0, 1.0), 0.75);
    EXPECT_DOUBLE_EQ(corrected_opacity(0.75, 0.5, 1.0), 0.5);
    // Tiny steps: α_Δs = x − x²/2 + …, x = −ln(1 − α) Δs/u, with no cancellation.
    const double x = std::log(2.0) * 1e-10;
    EXPECT_NEAR(corrected_opacity(0.5, 1e-10, 1.0), x - x * x / 2, 1e-24);
}

TEST(TransferFunction, PresetsAreValid) {
    Volume ct = uniform_sphere({8, 8, 8}, 2.0, 1000.0f);
    for (const std::string& name : preset_names()) {
        const TransferFunction tf = preset(name, ct);
        EXPECT_NO_THROW(tf.validate()) << name;
        EXPECT_EQ(tf.name, name);
    }
    EXPECT_EQ(preset("ct-bone", ct).evaluate(-1000.0)[3], 0.0f);  // air
    EXPECT_GT(preset("ct-bone", ct).evaluate(1000.0)[3], 0.4f);   // bone
    EXPECT_GT(preset("ct-skin", ct).evaluate(0.0)[3], 0.0f);
    // grayscale spans the volume's own range, 0 … 1000.
    const TransferFunction gray = preset("grayscale", ct);
    EXPECT_EQ(gray.evaluate(0.0), (std::array<float, 4>{0.0f, 0.0f, 0.0f, 0.0f}));
    EXPECT_EQ(gray.evaluate(1000.0), (std::array<float, 4>{1.0f, 1.0f, 1.0f, 1.0f}));
    EXPECT_FLOAT_EQ(gray.evaluate(250.0)[1], 0.25f);
    EXPECT_EQ(value_range(ct), (std::array<double, 2>{0.0, 1000.0}));
    // A constant volume still gives a valid grayscale.
    EXPECT_NO_THROW(preset("grayscale", Volume::allocate({2, 2, 2}, VoxelType::u8)).validate());
    try {
        preset("bone", ct);
        ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("ct-bone, ct-skin"), std::string::npos) << e.what();
    }
    EXPECT_THROW(preset("grayscale", Volume::allocate({2, 2, 2}, VoxelType::rgba8)), InvalidInput);
}

TEST(TransferFunction, ApplyClassifiesAndConvertsOpacityUnits) {
    Volume s = Volume::allocate({3, 1, 1}, VoxelType::i16, {0.5, 1.0, 2.0});
    auto v = s.values<VoxelType::i16>();
    v[0] = -10;
    v[1] = 3;
    v[2] = 5;
    TransferFunction tf = ramp();
    const Volume rgba = apply(s, tf);  // tf unit = output unit = 0.5
    EXPECT_EQ(rgba.type(), VoxelType::rgba32f);
    EXPECT_DOUBLE_EQ(rgba.spacing().z, 2.0);
    const auto c = rgba.values<VoxelType::rgba32f>();
    EXPECT_EQ(c[3], 0.0f);
    EXPECT_EQ(c[4 + 3], 0.25f);
    EXPECT_FLOAT_EQ(c[4 + 0], 0.3f);
    EXPECT_EQ(c[8 + 3], 0.9f);
    // Opacity given per 1 world unit, stored per 0.5: 1 − (1 − 0.25)^0.5.
    tf.opacity_unit = 1.0;
    const Volume half = apply(s, tf);
    EXPECT_FLOAT_EQ(half.values<VoxelType::rgba32f>()[4 + 3],
                    static_cast<float>(1.0 - std::sqrt(0.75)));
    tf.opacity[1].alpha = 2.0f;
    EXPECT_THROW(apply(s, tf), InvalidInput);
    EXPECT_THROW(apply(Volume::allocate({1, 1, 1}, VoxelType::rgba32f), ramp()), InvalidInput);
}

TEST(TransferFunction, ApplyBitwiseIdenticalForOneAndTwoThreads) {
    const Volume phantom = shepp_logan_3d({32, 32, 32});
    const TransferFunction tf = preset("grayscale", phantom);
    set_num_threads(1);
    const Volume one = apply(phantom, tf, 0.01);
    set_num_threads(2);
    const Volume two = apply(phantom, tf, 0.01);
    set_num_threads(0);
    EXPECT_EQ(std::memcmp(one.bytes().data(), two.bytes().data(), one.size_bytes()), 0);
}

}  // namespace
}  // namespace pliant::volume
