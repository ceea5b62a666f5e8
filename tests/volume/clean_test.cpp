#include "pliant/volume/clean.hpp"

#include <gtest/gtest.h>

#include <cstring>

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

}  // namespace
}  // namespace pliant::volume
