#include "pliant/collision/intersecting_pairs.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/bvh/traversal.hpp"
#include "pliant/collision/incidence.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/exact_predicates.hpp"
#include "pliant/geometry/triangle_intersection.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::collision {
namespace {

constexpr std::int64_t BOX_GRAIN = 1 << 13;

void validate(std::span<const Vec3d> positions, std::span<const geometry::Triangle> triangles,
              const char* function) {
    geometry::validate_triangles(triangles, positions.size(),
                                 fmt::format("{}: triangles", function));
    for (std::size_t v = 0; v < positions.size(); ++v) {
        for (int axis = 0; axis < 3; ++axis) {
            const double x = positions[v][axis];
            if (!geometry::in_exact_domain(x)) {
                throw InvalidInput(fmt::format(
                    "{}: positions[{}] coordinate {} is {}; expected 0 or a finite value with "
                    "{:g} <= |x| <= {:g} (the exact predicates' domain)",
                    function, v, "xyz"[axis], x, geometry::EXACT_MIN_MAGNITUDE,
                    geometry::EXACT_MAX_MAGNITUDE));
            }
        }
    }
}

// The candidate structure: exact double boxes of the triangles, and an LBVH over float boxes
// rounded outward from them, so that the float traversal loses no pair whose double boxes
// overlap.
struct Candidates {
    std::vector<AABBd> exact_boxes;
    bvh::LBVH tree;
};

const Vec3d& at(std::span<const Vec3d> positions, std::int32_t v) {
    return positions[static_cast<std::size_t>(v)];
}

void build_candidates(std::span<const Vec3d> positions,
                      std::span<const geometry::Triangle> triangles, Candidates& candidates) {
    candidates.exact_boxes.resize(triangles.size());
    std::vector<AABB> boxes(triangles.size());
    parallel_for(
        static_cast<std::int64_t>(triangles.size()),
        [&](std::int64_t t) {
            const auto k = static_cast<std::size_t>(t);
            const geometry::Triangle& tri = triangles[k];
            AABBd box = AABBd::of_point(at(positions, tri[0]));
            box.extend(at(positions, tri[1]));
            box.extend(at(positions, tri[2]));
            candidates.exact_boxes[k] = box;
            boxes[k] = outward_float(box);
        },
        BOX_GRAIN);
    candidates.tree.build(boxes);
}

// Calls on_pair(chunk, a, b) for every pair of triangles that share no vertex and intersect:
// candidates from the self traversal, then incidence, the double boxes and the exact test.
// `chunk` is the traversal chunk that found the pair (< bvh::num_overlap_chunks(tree); one chunk
// never runs on two threads at once). Preconditions: validated inputs, build_candidates done.
template <typename OnPair>
void for_each_intersecting_pair(std::span<const Vec3d> positions,
                                std::span<const geometry::Triangle> triangles,
                                const Candidates& candidates, OnPair&& on_pair) {
    const AABBd* exact_boxes = candidates.exact_boxes.data();
    bvh::for_each_self_overlap(
        candidates.tree, [&](std::int64_t chunk, std::uint32_t a, std::uint32_t b) {
            const geometry::Triangle& ta = triangles[a];
            const geometry::Triangle& tb = triangles[b];
            if (share_vertex(ta, tb) || !overlaps(exact_boxes[a], exact_boxes[b])) {
                return;
            }
            if (geometry::triangles_intersect(at(positions, ta[0]), at(positions, ta[1]),
                                              at(positions, ta[2]), at(positions, tb[0]),
                                              at(positions, tb[1]), at(positions, tb[2]))) {
                on_pair(chunk, static_cast<std::int32_t>(a), static_cast<std::int32_t>(b));
            }
        });
}

std::vector<Vec3d> to_double(std::span<const Vec3f> positions) {
    std::vector<Vec3d> out(positions.size());
    std::transform(positions.begin(), positions.end(), out.begin(),
                   [](const Vec3f& p) { return vec3_cast<double>(p); });
    return out;
}

}  // namespace

std::int64_t count_intersecting_pairs(std::span<const Vec3d> positions,
                                      std::span<const geometry::Triangle> triangles) {
    validate(positions, triangles, "count_intersecting_pairs");
    if (triangles.size() < 2) {
        return 0;
    }
    Candidates candidates;
    build_candidates(positions, triangles, candidates);
    // One counter per traversal chunk; chunks are summed in order (integers: exact anyway).
    std::vector<std::int64_t> counts(
        static_cast<std::size_t>(bvh::num_overlap_chunks(candidates.tree)), 0);
    for_each_intersecting_pair(positions, triangles, candidates,
                               [&](std::int64_t chunk, std::int32_t, std::int32_t) {
                                   ++counts[static_cast<std::size_t>(chunk)];
                               });
    std::int64_t total = 0;
    for (const std::int64_t c : counts) {
        total += c;
    }
    return total;
}

std::vector<std::array<std::int32_t, 2>> find_intersecting_pairs(
    std::span<const Vec3d> positions, std::span<const geometry::Triangle> triangles) {
    validate(positions, triangles, "find_intersecting_pairs");
    std::vector<std::array<std::int32_t, 2>> pairs;
    if (triangles.size() < 2) {
        return pairs;
    }
    Candidates candidates;
    build_candidates(positions, triangles, candidates);
    ChunkedBuffer<std::array<std::int32_t, 2>> buffer;
    buffer.reset(bvh::num_overlap_chunks(candidates.tree));
    for_each_intersecting_pair(positions, triangles, candidates,
                               [&](std::int64_t chunk, std::int32_t a, std::int32_t b) {
                                   buffer.chunk(chunk).push_back({std::min(a, b), std::max(a, b)});
                               });
    buffer.gather(pairs);
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

std::int64_t count_intersecting_pairs(std::span<const Vec3d> positions_a,
                                      std::span<const geometry::Triangle> triangles_a,
                                      std::span<const Vec3d> positions_b,
                                      std::span<const geometry::Triangle> triangles_b) {
    validate(positions_a, triangles_a, "count_intersecting_pairs: mesh a");
    validate(positions_b, triangles_b, "count_intersecting_pairs: mesh b");
    if (triangles_a.empty() || triangles_b.empty()) {
        return 0;
    }
    Candidates a;
    Candidates b;
    build_candidates(positions_a, triangles_a, a);
    build_candidates(positions_b, triangles_b, b);
    std::vector<std::int64_t> counts(static_cast<std::size_t>(bvh::num_overlap_chunks(a.tree)), 0);
    bvh::for_each_overlap(
        a.tree, b.tree, [&](std::int64_t chunk, std::uint32_t i, std::uint32_t j) {
            if (!overlaps(a.exact_boxes[i], b.exact_boxes[j])) {
                return;
            }
            const geometry::Triangle& ti = triangles_a[i];
            const geometry::Triangle& tj = triangles_b[j];
            if (geometry::triangles_intersect(at(positions_a, ti[0]), at(positions_a, ti[1]),
                                              at(positions_a, ti[2]), at(positions_b, tj[0]),
                                              at(positions_b, tj[1]), at(positions_b, tj[2]))) {
                ++counts[static_cast<std::size_t>(chunk)];
            }
        });
    std::int64_t total = 0;
    for (const std::int64_t c : counts) {
        total += c;
    }
    return total;
}

std::int64_t count_intersecting_pairs(std::span<const Vec3f> positions,
                                      std::span<const geometry::Triangle> triangles) {
    const std::vector<Vec3d> converted = to_double(positions);
    return count_intersecting_pairs(std::span<const Vec3d>(converted), triangles);
}

std::vector<std::array<std::int32_t, 2>> find_intersecting_pairs(
    std::span<const Vec3f> positions, std::span<const geometry::Triangle> triangles) {
    const std::vector<Vec3d> converted = to_double(positions);
    return find_intersecting_pairs(std::span<const Vec3d>(converted), triangles);
}

}  // namespace pliant::collision
