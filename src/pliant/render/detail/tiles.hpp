// The tiled parallel loop of the ray casters' render(): the image in TILE × TILE tiles
// (raycast_kernel.hpp), one task per tile on the thread pool, the samples summed in tile order
// (the same total for any number of threads).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"

namespace pliant::render::detail {

// tile(x0, y0, x1, y1) for the tiles [x0, x1) × [y0, y1) of a width × height image; it returns
// the samples its pixels marched. Returns their total.
template <class TileFn>
std::int64_t render_tiles(int width, int height, const TileFn& tile) {
    const int tiles_x = (width + TILE - 1) / TILE;
    const int tiles_y = (height + TILE - 1) / TILE;
    const std::int64_t num_tiles = static_cast<std::int64_t>(tiles_x) * tiles_y;
    std::vector<std::int64_t> tile_samples(static_cast<std::size_t>(num_tiles), 0);
    parallel_for(
        num_tiles,
        [&](std::int64_t t) {
            const int x0 = static_cast<int>(t % tiles_x) * TILE;
            const int y0 = static_cast<int>(t / tiles_x) * TILE;
            tile_samples[static_cast<std::size_t>(t)] =
                tile(x0, y0, std::min(x0 + TILE, width), std::min(y0 + TILE, height));
        },
        1);
    std::int64_t total = 0;
    for (const std::int64_t s : tile_samples) {
        total += s;
    }
    return total;
}

}  // namespace pliant::render::detail
