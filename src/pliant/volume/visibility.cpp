#include "pliant/volume/visibility.hpp"

#include <cmath>
#include <limits>

#include "pliant/core/parallel.hpp"

namespace pliant::volume {
namespace {

// Writes visible[v] = is_visible(value of voxel v) (channel `channel` of `stride` per voxel).
template <typename Channel, typename Predicate>
void classify(std::span<const Channel> values, int stride, int channel, Predicate&& is_visible,
              std::vector<std::uint8_t>& visible) {
    parallel_for_chunks(static_cast<std::int64_t>(visible.size()), std::int64_t{1} << 16,
                        [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                            for (std::int64_t v = begin; v < end; ++v) {
                                visible[static_cast<std::size_t>(v)] = is_visible(
                                    values[static_cast<std::size_t>(v * stride + channel)]);
                            }
                        });
}

// Scalar integer volumes: one transfer-function evaluation per representable value.
template <VoxelType T>
void classify_integer(const Volume& volume, const TransferFunction* tf,
                      std::vector<std::uint8_t>& visible) {
    using Channel = channel_t<T>;
    if (tf == nullptr) {
        classify<Channel>(
            volume.values<T>(), 1, 0, [](Channel x) { return x != 0; }, visible);
        return;
    }
    constexpr std::int64_t LO = std::numeric_limits<Channel>::min();
    constexpr std::int64_t HI = std::numeric_limits<Channel>::max();
    std::vector<std::uint8_t> lut(static_cast<std::size_t>(HI - LO + 1));
    for (std::int64_t x = LO; x <= HI; ++x) {
        lut[static_cast<std::size_t>(x - LO)] = tf->evaluate(static_cast<double>(x))[3] > 0.0f;
    }
    classify<Channel>(
        volume.values<T>(), 1, 0,
        [&](Channel x) { return lut[static_cast<std::size_t>(static_cast<std::int64_t>(x) - LO)]; },
        visible);
}

}  // namespace

std::vector<std::uint8_t> visible_voxels(const Volume& volume, const TransferFunction* tf) {
    const bool is_rgba = channels(volume.type()) == 4;
    if (tf != nullptr && !is_rgba) {
        tf->validate();
    }
    std::vector<std::uint8_t> visible(static_cast<std::size_t>(volume.num_voxels()));
    switch (volume.type()) {
        case VoxelType::u8:
            classify_integer<VoxelType::u8>(volume, tf, visible);
            break;
        case VoxelType::i16:
            classify_integer<VoxelType::i16>(volume, tf, visible);
            break;
        case VoxelType::u16:
            classify_integer<VoxelType::u16>(volume, tf, visible);
            break;
        case VoxelType::f32:
            if (tf == nullptr) {
                // NaN != 0 is true: test for a finite or infinite non-zero number explicitly.
                classify<float>(
                    volume.values<VoxelType::f32>(), 1, 0,
                    [](float x) { return x < 0.0f || x > 0.0f; }, visible);
            } else {
                classify<float>(
                    volume.values<VoxelType::f32>(), 1, 0,
                    [&](float x) { return tf->evaluate(x)[3] > 0.0f; }, visible);
            }
            break;
        case VoxelType::rgba8:
            classify<std::uint8_t>(
                volume.values<VoxelType::rgba8>(), 4, 3, [](std::uint8_t a) { return a > 0; },
                visible);
            break;
        case VoxelType::rgba32f:
            classify<float>(
                volume.values<VoxelType::rgba32f>(), 4, 3, [](float a) { return a > 0.0f; },
                visible);
            break;
    }
    return visible;
}

}  // namespace pliant::volume
