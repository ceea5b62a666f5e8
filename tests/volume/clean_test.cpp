#include "pliant/volume/clean.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

Volume rgba8_alphas(std::initializer_list<int> alphas) {
    Volume v = Volume::allocate({static_cast<std::int64_t>(alphas.size()), 1, 1}, VoxelType::rgba8);
    auto c = v.values<VoxelType::rgba8>();
    std::size_t i = 0;
    for (const int a : alphas) {
        c[4 * i] = 200;  // colour is kept
        c[4 * i + 3] = static_cast<std::uint8_t>(a);
        ++i;
    }
    return v;
}

std::vector<int> alphas_of(const Volume& v) {
    std::vector<int> out;
    const auto c = v.values<VoxelType::rgba8>();
    for (std::size_t i = 3; i < c.size(); i += 4) {
        out.push_back(c[i]);
    }
    return out;
}

TEST(Clean, ThresholdOnTheByteScale) {
    Volume v = rgba8_alphas({0, 4, 5, 19, 20, 34, 35, 255});
    EXPECT_EQ(threshold_alpha(v, 20), 3);  // 4, 5, 19
    EXPECT_EQ(alphas_of(v), (std::vector<int>{0, 0, 0, 0, 20, 34, 35, 255}));
    EXPECT_EQ(v.values<VoxelType::rgba8>()[4], 200);  // colour of a zeroed voxel kept
    // T = 0 is the identity.
    Volume w = rgba8_alphas({0, 1, 128, 255});
    EXPECT_EQ(threshold_alpha(w, 0), 0);
    EXPECT_EQ(alphas_of(w), (std::vector<int>{0, 1, 128, 255}));
    // rgba32f: α = 0.0196 (255 α = 4.998) < 5 is zeroed, 0.02 (5.1) kept.
    Volume f = Volume::allocate({2, 1, 1}, VoxelType::rgba32f);
    f.values<VoxelType::rgba32f>()[3] = 0.0196f;
    f.values<VoxelType::rgba32f>()[7] = 0.02f;
    EXPECT_EQ(threshold_alpha(f, 5), 1);
    EXPECT_EQ(f.values<VoxelType::rgba32f>()[3], 0.0f);
    EXPECT_EQ(f.values<VoxelType::rgba32f>()[7], 0.02f);
}

TEST(Clean, NormalizeByMaximum) {
    Volume v = rgba8_alphas({0, 51, 102});  // α_max = 0.4
    EXPECT_DOUBLE_EQ(normalize_alpha(v), 0.4);
    EXPECT_EQ(alphas_of(v), (std::vector<int>{0, 128, 255}));  // round(127.5) = 128
    Volume f = Volume::allocate({3, 1, 1}, VoxelType::rgba32f);
    auto c = f.values<VoxelType::rgba32f>();
    c[3] = 0.1f;
    c[7] = 0.5f;
    c[11] = 0.25f;
    EXPECT_DOUBLE_EQ(normalize_alpha(f), 0.5);
    EXPECT_FLOAT_EQ(c[3], 0.2f);
    EXPECT_EQ(c[7], 1.0f);
    EXPECT_FLOAT_EQ(c[11], 0.5f);
    // All transparent: unchanged.
    Volume t = rgba8_alphas({0, 0, 0});
    EXPECT_EQ(normalize_alpha(t), 0.0);
    EXPECT_EQ(alphas_of(t), (std::vector<int>{0, 0, 0}));
}

TEST(Clean, NormalizeOverTheThresholdRange) {
    // t = 51/255 = 0.2: α' = (α − 0.2)/0.8.
    Volume v = rgba8_alphas({10, 51, 204, 255});
    normalize_alpha_range(v, 51);
    EXPECT_EQ(alphas_of(v), (std::vector<int>{0, 0, 191, 255}));  // (0.8−0.2)/0.8 · 255 = 191.25
    Volume w = rgba8_alphas({0, 7, 255});
    normalize_alpha_range(w, 0);  // identity
    EXPECT_EQ(alphas_of(w), (std::vector<int>{0, 7, 255}));
    Volume x = rgba8_alphas({254, 255});
    normalize_alpha_range(x, 255);
    EXPECT_EQ(alphas_of(x), (std::vector<int>{0, 255}));
}

TEST(Clean, PipelineAndErrors) {
    Volume v = rgba8_alphas({4, 20, 100});
    clean(v, {.threshold_255 = 5, .normalization = AlphaNormalization::max});
    EXPECT_EQ(alphas_of(v), (std::vector<int>{0, 51, 255}));
    Volume s = Volume::allocate({2, 2, 2}, VoxelType::f32);
    try {
        threshold_alpha(s, 5);
        ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("f32"), std::string::npos) << e.what();
    }
    EXPECT_THROW(threshold_alpha(v, -1), InvalidInput);
    EXPECT_THROW(clean(v, {.threshold_255 = 300}), InvalidInput);
    EXPECT_THROW(normalize_alpha(s), InvalidInput);
}

TEST(Clean, BitwiseIdenticalForOneAndTwoThreads) {
    const auto run = [](int threads) {
        set_num_threads(threads);
        Volume v = Volume::allocate({64, 64, 16}, VoxelType::rgba32f);
        auto c = v.values<VoxelType::rgba32f>();
        for (std::size_t i = 0; i < c.size(); ++i) {
            c[i] = static_cast<float>((i * 2654435761u) % 1000u) / 1500.0f;
        }
        clean(v, {.threshold_255 = 20, .normalization = AlphaNormalization::max});
        return v;
    };
    const Volume one = run(1);
    const Volume two = run(2);
    set_num_threads(0);
    EXPECT_EQ(std::memcmp(one.bytes().data(), two.bytes().data(), one.size_bytes()), 0);
}

// The threshold on a transfer function agrees with thresholding its classification value by
// value: on random curves (rising, falling, flat and step segments), sampled densely, everywhere
// except within rounding of a crossing.
TEST(Clean, TransferFunctionThresholdMatchesThresholdingEveryValue) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int trial = 0; trial < 50; ++trial) {
        TransferFunction tf;
        tf.name = "random";
        tf.color = {{0.0, {0.2f, 0.4f, 0.6f}}};
        double value = -1.0;
        for (int k = 0; k < 8; ++k) {
            value += unit(rng) < 0.15 ? 0.0 : unit(rng);  // some steps (equal values)
            tf.opacity.push_back({value, static_cast<float>(unit(rng) < 0.2 ? 0.0 : unit(rng))});
        }
        const double threshold = 255.0 * unit(rng);
        const TransferFunction cut = threshold_alpha(tf, threshold);
        ASSERT_NO_THROW(cut.validate());
        EXPECT_EQ(cut.color.size(), tf.color.size());
        const double t = threshold / 255.0;
        int checked = 0;
        for (int s = 0; s <= 4000; ++s) {
            const double v = -1.5 + (value + 2.0) * s / 4000.0;
            const float a = tf.evaluate(v)[3];
            if (std::fabs(a - t) < 1e-5) {
                continue;  // at a crossing
            }
            const float expected = 255.0 * a < threshold ? 0.0f : a;
            ASSERT_NEAR(cut.evaluate(v)[3], expected, 1e-5f)
                << "trial " << trial << " value " << v << " threshold " << threshold;
            ++checked;
        }
        EXPECT_GT(checked, 3900);
    }
}

TEST(Clean, TransferFunctionThresholdEdgeCases) {
    TransferFunction tf;
    tf.name = "ramp";
    tf.color = {{0.0, {1.0f, 1.0f, 1.0f}}};
    tf.opacity = {{0.0, 0.0f}, {100.0, 1.0f}};
    // T = 0: unchanged.
    const TransferFunction same = threshold_alpha(tf, 0.0);
    ASSERT_EQ(same.opacity.size(), 2u);
    EXPECT_EQ(same.opacity[1].alpha, 1.0f);
    // T = 51 (t = 0.2): a ramp crossing at value 20, a step there.
    const TransferFunction cut = threshold_alpha(tf, 51.0);
    EXPECT_EQ(cut.evaluate(19.9)[3], 0.0f);
    EXPECT_NEAR(cut.evaluate(20.0)[3], 0.2f, 1e-6f);
    EXPECT_NEAR(cut.evaluate(60.0)[3], 0.6f, 1e-6f);
    // T = 255: only full opacity stays.
    const TransferFunction top = threshold_alpha(tf, 255.0);
    EXPECT_EQ(top.evaluate(99.0)[3], 0.0f);
    EXPECT_EQ(top.evaluate(100.0)[3], 1.0f);
    EXPECT_THROW(threshold_alpha(tf, 256.0), InvalidInput);
    try {
        threshold_alpha(tf, -2.0);
        ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("-2"), std::string::npos) << e.what();
    }
    TransferFunction broken = tf;
    broken.opacity.clear();
    EXPECT_THROW(threshold_alpha(broken, 10.0), InvalidInput);
}

}  // namespace
}  // namespace pliant::volume
