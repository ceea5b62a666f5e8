// The traversal layout of the LBVH: a 4-wide tree collapsed from the binary hierarchy, children's
// boxes stored as structure of arrays so one SIMD compare tests all four against a query box
// (the layout Embree uses; Wald et al. 2008, "Getting Rid of Packets").
//
// WideNode: 128 bytes, two cache lines. Slot k holds a child subtree: child[k] ≥ 0 is a WideNode,
// child[k] < 0 the leaf at position ~child[k]; last[k] is the last leaf position under slot k, so
// a self query from leaves at positions ≥ f skips slots with last[k] ≤ f. Unused slots
// (child = EMPTY_SLOT) have an empty box
// (lo = +inf, hi = -inf) and last = -1, so they never pass a test. Slots are in leaf order.
// Nodes are stored breadth first: root at 0, children after parents, each depth contiguous.
#pragma once

#include <cstdint>
#include <type_traits>

#include "pliant/core/aabb.hpp"
#include "pliant/core/host_device.hpp"

namespace pliant::bvh {

inline constexpr int WIDTH = 4;

struct alignas(64) WideNode {
    float lo_x[WIDTH], lo_y[WIDTH], lo_z[WIDTH];
    float hi_x[WIDTH], hi_y[WIDTH], hi_z[WIDTH];
    std::int32_t child[WIDTH];
    std::int32_t last[WIDTH];

    PLIANT_HOST_DEVICE AABB box(int k) const {
        return {{lo_x[k], lo_y[k], lo_z[k]}, {hi_x[k], hi_y[k], hi_z[k]}};
    }
    PLIANT_HOST_DEVICE void set_box(int k, const AABB& b) {
        lo_x[k] = b.lo.x;
        lo_y[k] = b.lo.y;
        lo_z[k] = b.lo.z;
        hi_x[k] = b.hi.x;
        hi_y[k] = b.hi.y;
        hi_z[k] = b.hi.z;
    }
    // Box of all four slots (unused slots are empty and do not count).
    PLIANT_HOST_DEVICE AABB bounds() const {
        AABB b = box(0);
        for (int k = 1; k < WIDTH; ++k) {
            b.extend(box(k));
        }
        return b;
    }
};
static_assert(sizeof(WideNode) == 128 && std::is_trivially_copyable_v<WideNode>);

inline constexpr std::int32_t EMPTY_SLOT = INT32_MIN;

}  // namespace pliant::bvh
