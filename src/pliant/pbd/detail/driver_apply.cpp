#include "pliant/pbd/detail/driver_apply.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <variant>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"

namespace pliant::pbd::detail {
namespace {

// The rotation of a rotate or twist driver at time t (its angle ramped); the other drivers get a
// zero matrix, never used.
std::array<double, 9> driver_rotation(const Driver& driver, double t) {
    if (const auto* r = std::get_if<RotateDriver>(&driver)) {
        return rotation(r->axis, r->angle * ramp(t, r->ramp_time));
    }
    if (const auto* tw = std::get_if<TwistDriver>(&driver)) {
        return rotation(tw->axis, tw->angle * ramp(t, tw->ramp_time));
    }
    return {};
}

// The target of a vertex at rest position `rest_f` held by a rotate or twist driver turning by
// `rotation`: about a rotate's centre or the box's; a twist turns only vertices beyond the centre
// along its axis.
Vec3f turned_target(const Driver& driver, const std::array<double, 9>& rotation, const BodyBox& box,
                    const Vec3f& rest_f) {
    const Vec3d rest = vec3_cast<double>(rest_f);
    const auto* rotate_driver = std::get_if<RotateDriver>(&driver);
    const Vec3d c =
        rotate_driver != nullptr && rotate_driver->centre ? *rotate_driver->centre : box.centre;
    bool turns = true;
    if (const auto* tw = std::get_if<TwistDriver>(&driver)) {
        const int a = static_cast<int>(tw->axis);
        turns = rest[a] > c[a];
    }
    return turns ? vec3_cast<float>(c + rotate(rotation, rest - c)) : rest_f;
}

// The target of a grabbed vertex: the grab translated by the fraction of the way to the target.
Vec3f dragged_target(const DragGrab& grab, std::int32_t vertex, float drag_fraction) {
    // The grab set is small; its offsets are found by a binary search of it.
    const auto it = std::lower_bound(grab.vertices.begin(), grab.vertices.end(), vertex);
    const Vec3f offset = grab.offsets[static_cast<std::size_t>(it - grab.vertices.begin())];
    return grab.from + (grab.drag->target - grab.from) * drag_fraction + offset;
}

// The product of the bubbles' rest-volume factors at rest point p, time t (1 for none).
double bubble_product(std::span<const BubbleDriver* const> bubbles, const BodyBox& box,
                      const Vec3d& p, double t) {
    double f = 1.0;
    for (const BubbleDriver* b : bubbles) {
        f *= bubble_factor(*b, box, p, t);
    }
    return f;
}

}  // namespace

void grab_vertices(const DragDriver& drag, std::span<const Vec3f> positions, DragGrab& grab) {
    grab.drag = drag;
    grab.vertices.clear();
    grab.offsets.clear();
    const Vec3f centre = positions[static_cast<std::size_t>(drag.vertex)];
    for (std::int64_t v = 0; v < std::ssize(positions); ++v) {
        const Vec3f offset = positions[static_cast<std::size_t>(v)] - centre;
        if (v == drag.vertex || squared_norm(offset) <= drag.radius * drag.radius) {
            grab.vertices.push_back(static_cast<std::int32_t>(v));
            grab.offsets.push_back(v == drag.vertex ? Vec3f{} : offset);
        }
    }
}

void assign_driven_vertices(std::span<const Driver> drivers, const BodyBox& box,
                            std::span<const Vec3f> rest, std::span<const std::uint8_t> pinned,
                            std::span<const std::int32_t> grabbed, DrivenVertices& driven) {
    const auto nv = static_cast<std::int64_t>(rest.size());
    std::vector<std::int32_t> by(static_cast<std::size_t>(nv), -1);
    for (std::size_t d = 0; d < drivers.size(); ++d) {
        const Driver& driver = drivers[d];
        if (std::holds_alternative<RotateDriver>(driver)) {
            std::fill(by.begin(), by.end(), static_cast<std::int32_t>(d));
        } else if (const auto* twist = std::get_if<TwistDriver>(&driver)) {
            const int a = static_cast<int>(twist->axis);
            const double reach = twist->grip * box.size + 1e-6 * box.size;
            for (std::int64_t v = 0; v < nv; ++v) {
                const double q = rest[static_cast<std::size_t>(v)][a];
                if (q <= box.lo[a] + reach || q >= box.hi[a] - reach) {
                    by[static_cast<std::size_t>(v)] = static_cast<std::int32_t>(d);
                }
            }
        }
    }
    for (const std::int32_t v : grabbed) {
        by[static_cast<std::size_t>(v)] = DRAG;
    }
    driven.vertices.clear();
    driven.driver.clear();
    for (std::int64_t v = 0; v < nv; ++v) {
        if (by[static_cast<std::size_t>(v)] != -1 && pinned[static_cast<std::size_t>(v)] == 0) {
            driven.vertices.push_back(static_cast<std::int32_t>(v));
            driven.driver.push_back(by[static_cast<std::size_t>(v)]);
        }
    }
}

void place_driven_vertices(Float4* x, std::span<const Driver> drivers, const BodyBox& box,
                           std::span<const Vec3f> rest, const DrivenVertices& driven,
                           const DragGrab& grab, double t_end, float drag_fraction) {
    std::vector<std::array<double, 9>> rotations(drivers.size());
    for (std::size_t d = 0; d < drivers.size(); ++d) {
        rotations[d] = driver_rotation(drivers[d], t_end);
    }
    parallel_for(
        static_cast<std::int64_t>(driven.vertices.size()),
        [&](std::int64_t k) {
            const std::int32_t v = driven.vertices[static_cast<std::size_t>(k)];
            const std::int32_t d = driven.driver[static_cast<std::size_t>(k)];
            const Vec3f target = d == DRAG ? dragged_target(grab, v, drag_fraction)
                                           : turned_target(drivers[static_cast<std::size_t>(d)],
                                                           rotations[static_cast<std::size_t>(d)],
                                                           box, rest[static_cast<std::size_t>(v)]);
            x[v] = {target.x, target.y, target.z, 0.0f};
        },
        VERTEX_GRAIN);
}

void apply_rest_drivers(std::span<const Driver> drivers, const BodyBox& box,
                        std::span<const Vec3f> rest, double t, EdgeConstraints& edges,
                        TetConstraints& tets, RestDriverCache& cache) {
    std::vector<const WaveDriver*> waves;
    std::vector<const BubbleDriver*> bubbles;
    for (const Driver& d : drivers) {
        if (const auto* w = std::get_if<WaveDriver>(&d)) {
            waves.push_back(w);
        } else if (const auto* b = std::get_if<BubbleDriver>(&d)) {
            bubbles.push_back(b);
        }
    }
    // Bubbles alone: t enters the rest state only through their ramps.
    std::vector<double> ramps;
    ramps.reserve(bubbles.size());
    for (const BubbleDriver* b : bubbles) {
        ramps.push_back(ramp(t, b->ramp_time));
    }
    const bool bubbles_only = waves.empty() && !bubbles.empty();
    if (bubbles_only && cache.is_valid && ramps.size() == cache.ramps.size() &&
        std::equal(ramps.begin(), ramps.end(), cache.ramps.begin(), [](double a, double b) {
            return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
        })) {
        return;
    }
    const bool reached_only = bubbles_only && cache.is_valid;
    const auto nv = static_cast<std::int64_t>(rest.size());
    if (!cache.is_valid) {
        // The waves' planes: a wave's displacement depends only on the rest coordinate along its
        // direction, which takes few distinct values (one per lattice plane on a grid).
        cache.wave_coordinates.assign(waves.size(), {});
        cache.wave_plane.assign(waves.size(), {});
        for (std::size_t w = 0; w < waves.size(); ++w) {
            // Distinct by bit pattern (so that −0 and +0 stay apart).
            const int d = static_cast<int>(waves[w]->direction);
            std::vector<std::uint32_t> bits;
            bits.reserve(rest.size());
            for (const Vec3f& p : rest) {
                bits.push_back(std::bit_cast<std::uint32_t>(p[d]));
            }
            std::vector<std::uint32_t> distinct = bits;
            std::sort(distinct.begin(), distinct.end());
            distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
            std::vector<double>& coordinates = cache.wave_coordinates[w];
            for (const std::uint32_t b : distinct) {
                coordinates.push_back(static_cast<double>(std::bit_cast<float>(b)));
            }
            std::vector<std::int32_t>& plane = cache.wave_plane[w];
            plane.reserve(rest.size());
            for (const std::uint32_t b : bits) {
                plane.push_back(static_cast<std::int32_t>(
                    std::lower_bound(distinct.begin(), distinct.end(), b) - distinct.begin()));
            }
        }
    }
    // Step 1: the displaced rest positions (double), only when a wave runs: each wave's
    // displacement once per plane (wave_displacement reads only the coordinate along its
    // direction), then added per vertex in the drivers' order.
    std::vector<Vec3d> shaped;
    if (!waves.empty()) {
        std::vector<std::vector<Vec3d>> displacement(waves.size());
        for (std::size_t w = 0; w < waves.size(); ++w) {
            const int d = static_cast<int>(waves[w]->direction);
            for (const double coordinate : cache.wave_coordinates[w]) {
                Vec3d at{};
                at[d] = coordinate;
                displacement[w].push_back(wave_displacement(*waves[w], box, at, t));
            }
        }
        shaped.resize(static_cast<std::size_t>(nv));
        parallel_for(
            nv,
            [&](std::int64_t i) {
                const auto v = static_cast<std::size_t>(i);
                Vec3d p = vec3_cast<double>(rest[v]);
                for (std::size_t w = 0; w < waves.size(); ++w) {
                    p += displacement[w][static_cast<std::size_t>(cache.wave_plane[w][v])];
                }
                shaped[v] = p;
            },
            VERTEX_GRAIN);
    }
    const auto rest_at = [&](std::int32_t v) {
        return vec3_cast<double>(rest[static_cast<std::size_t>(v)]);
    };
    const auto edge_midpoint = [&](std::int64_t k) {
        const auto& e = edges.vertices[static_cast<std::size_t>(k)];
        return (rest_at(e[0]) + rest_at(e[1])) * 0.5;
    };
    const auto tet_centroid = [&](std::int64_t k) {
        const geometry::Tet& tet = tets.vertices[static_cast<std::size_t>(k)];
        return (rest_at(tet[0]) + rest_at(tet[1]) + rest_at(tet[2]) + rest_at(tet[3])) * 0.25;
    };
    // Step 2: edge lengths.
    const auto write_edge_length = [&](std::int64_t k) {
        const auto& e = edges.vertices[static_cast<std::size_t>(k)];
        double length = shaped.empty() ? edges.rest_lengths0[static_cast<std::size_t>(k)]
                                       : norm(shaped[static_cast<std::size_t>(e[0])] -
                                              shaped[static_cast<std::size_t>(e[1])]);
        if (!bubbles.empty()) {
            length *= std::cbrt(bubble_product(bubbles, box, edge_midpoint(k), t));
        }
        edges.rest_lengths[static_cast<std::size_t>(k)] = static_cast<float>(length);
    };
    // Step 3: tet volumes.
    const auto write_tet_volume = [&](std::int64_t k) {
        const geometry::Tet& tet = tets.vertices[static_cast<std::size_t>(k)];
        double volume = tets.rest_volumes0[static_cast<std::size_t>(k)];
        if (!shaped.empty()) {
            volume = geometry::signed_volume(
                shaped[static_cast<std::size_t>(tet[0])], shaped[static_cast<std::size_t>(tet[1])],
                shaped[static_cast<std::size_t>(tet[2])], shaped[static_cast<std::size_t>(tet[3])]);
        }
        if (!bubbles.empty()) {
            volume *= bubble_product(bubbles, box, tet_centroid(k), t);
        }
        tets.rest_volumes[static_cast<std::size_t>(k)] = static_cast<float>(volume);
    };
    if (reached_only) {
        parallel_for(
            static_cast<std::int64_t>(cache.edges.size()),
            [&](std::int64_t i) { write_edge_length(cache.edges[static_cast<std::size_t>(i)]); },
            EDGE_GRAIN);
        parallel_for(
            static_cast<std::int64_t>(cache.tets.size()),
            [&](std::int64_t i) { write_tet_volume(cache.tets[static_cast<std::size_t>(i)]); },
            TET_GRAIN);
        cache.ramps = std::move(ramps);
        return;
    }
    parallel_for(static_cast<std::int64_t>(edges.vertices.size()), write_edge_length, EDGE_GRAIN);
    parallel_for(static_cast<std::int64_t>(tets.vertices.size()), write_tet_volume, TET_GRAIN);
    if (!bubbles_only) {
        cache.is_valid = true;
        return;
    }
    // Step 4: the constraints the bubbles reach, for the next calls.
    const auto reached = [&](const Vec3d& p) {
        return std::any_of(bubbles.begin(), bubbles.end(),
                           [&](const BubbleDriver* b) { return bubble_reaches(*b, box, p); });
    };
    cache.edges.clear();
    for (std::int64_t k = 0; k < std::ssize(edges.vertices); ++k) {
        if (reached(edge_midpoint(k))) {
            cache.edges.push_back(k);
        }
    }
    cache.tets.clear();
    for (std::int64_t k = 0; k < std::ssize(tets.vertices); ++k) {
        if (reached(tet_centroid(k))) {
            cache.tets.push_back(k);
        }
    }
    cache.ramps = std::move(ramps);
    cache.is_valid = true;
}

}  // namespace pliant::pbd::detail
