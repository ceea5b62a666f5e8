#include "pliant/pbd/detail/driver_apply.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <variant>

#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/pbd/detail/grains.hpp"
#include "pliant/pbd/detail/wave_rest.hpp"

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

// call(r0, r1) for ranges of runs (lattice_sweep.hpp; run_begins and run_offsets of one kind of
// constraint) that together cover every run once, layer by layer (every colour's runs of layer
// keys [z0, z1), LAYERS_PER_SLAB layers per chunk of a parallel loop), so that a chunk reads one
// slab of the vertices rather than the whole body per colour; without a blocking, all the runs in
// fixed chunks. A run never spans two layer keys (build_lattice_sweep).
template <typename Call>
void parallel_for_runs_by_layer(const LayerBlocking& blocking, const ConstraintColoring& coloring,
                                const std::vector<std::int64_t>& run_begins,
                                const std::vector<std::int64_t>& run_offsets, const Call& call) {
    if (blocking.num_layers == 0) {
        parallel_for_chunks(std::ssize(run_begins), RUN_GRAIN,
                            [&](std::int64_t, std::int64_t r0, std::int64_t r1) { call(r0, r1); });
        return;
    }
    const std::int64_t layers = blocking.num_layers;
    parallel_for_chunks(
        layers, LAYERS_PER_SLAB, [&](std::int64_t, std::int64_t z0, std::int64_t z1) {
            for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
                const auto colour = static_cast<std::size_t>(c);
                const std::int64_t* layer_begin =
                    blocking.layer_begin.data() + colour * static_cast<std::size_t>(layers + 1);
                const std::int64_t lo = coloring.offsets[colour] + layer_begin[z0];
                const std::int64_t hi = coloring.offsets[colour] + layer_begin[z1];
                const auto first = run_begins.begin() + run_offsets[colour];
                const auto last = run_begins.begin() + run_offsets[colour + 1];
                const auto r0 = std::lower_bound(first, last, lo) - run_begins.begin();
                const auto r1 = std::lower_bound(first, last, hi) - run_begins.begin();
                if (r0 < r1) {
                    call(r0, r1);
                }
            }
        });
}

// The waves' rest lengths and volumes over the lattice sweep's runs (AVX2): the rest positions
// (once per cache) and the displacements displacement_of(v) in the solver order, then every run.
template <typename DisplacementOf>
void wave_rest_on_runs(const LatticeSweep& lattice, std::span<const Vec3f> rest, int axes,
                       const DisplacementOf& displacement_of, EdgeConstraints& edges,
                       TetConstraints& tets, RestDriverCache& cache) {
    const auto nv = static_cast<std::int64_t>(lattice.vertex_of.size());
    const std::int32_t* vertex_of = lattice.vertex_of.data();
    // Every array with 8 floats of padding (wave_rest.hpp).
    const auto padded = static_cast<std::size_t>(nv + 8);
    if (cache.solver_rest_x.size() != padded) {
        cache.solver_rest_x.assign(padded, 0.0f);
        cache.solver_rest_y.assign(padded, 0.0f);
        cache.solver_rest_z.assign(padded, 0.0f);
        for (std::int64_t i = 0; i < nv; ++i) {
            const Vec3f& r = rest[static_cast<std::size_t>(vertex_of[i])];
            cache.solver_rest_x[static_cast<std::size_t>(i)] = r.x;
            cache.solver_rest_y[static_cast<std::size_t>(i)] = r.y;
            cache.solver_rest_z[static_cast<std::size_t>(i)] = r.z;
        }
    }
    cache.solver_u_x.resize(padded, 0.0f);
    cache.solver_u_y.resize(padded, 0.0f);
    cache.solver_u_z.resize(padded, 0.0f);
    parallel_for(
        nv,
        [&](std::int64_t i) {
            const Vec3f u = displacement_of(static_cast<std::size_t>(vertex_of[i]));
            cache.solver_u_x[static_cast<std::size_t>(i)] = u.x;
            cache.solver_u_y[static_cast<std::size_t>(i)] = u.y;
            cache.solver_u_z[static_cast<std::size_t>(i)] = u.z;
        },
        VERTEX_GRAIN);
    const SoaDisplaced p{cache.solver_rest_x.data(), cache.solver_rest_y.data(),
                         cache.solver_rest_z.data(), cache.solver_u_x.data(),
                         cache.solver_u_y.data(),    cache.solver_u_z.data()};
    parallel_for_runs_by_layer(edges.blocking, edges.coloring, lattice.edge_run_begins,
                               lattice.edge_run_offsets, [&](std::int64_t r0, std::int64_t r1) {
                                   displaced_lengths_runs_avx2(
                                       p, axes, lattice.edge_runs.data(), r0, r1,
                                       std::ssize(lattice.edge_runs), std::ssize(edges.vertices),
                                       edges.rest_lengths.data());
                               });
    parallel_for_runs_by_layer(tets.blocking, tets.coloring, lattice.tet_run_begins,
                               lattice.tet_run_offsets, [&](std::int64_t r0, std::int64_t r1) {
                                   displaced_volumes_runs_avx2(p, axes, lattice.tet_runs.data(), r0,
                                                               r1, std::ssize(lattice.tet_runs),
                                                               std::ssize(tets.vertices),
                                                               tets.rest_volumes.data());
                               });
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
                        TetConstraints& tets, RestDriverCache& cache, const LatticeSweep* lattice) {
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
    // Step 1, only when a wave runs: each wave's displacement once per plane (wave_displacement
    // reads only the coordinate along its direction), summed per vertex in the drivers' order and
    // rounded to float; then the edge lengths and tet volumes of the displaced positions
    // (wave_rest.hpp).
    const bool has_waves = !waves.empty();
    if (has_waves) {
        std::vector<std::vector<Vec3d>> displacement(waves.size());
        for (std::size_t w = 0; w < waves.size(); ++w) {
            const int d = static_cast<int>(waves[w]->direction);
            for (const double coordinate : cache.wave_coordinates[w]) {
                Vec3d at{};
                at[d] = coordinate;
                displacement[w].push_back(wave_displacement(*waves[w], box, at, t));
            }
        }
        // The axes the waves displace along (wave_rest.hpp): u is 0 along the others.
        int axes = 0;
        for (const WaveDriver* w : waves) {
            axes |= 1 << static_cast<int>(w->displacement);
        }
        const auto displacement_of = [&](std::size_t v) {
            Vec3d u{};
            for (std::size_t w = 0; w < waves.size(); ++w) {
                u += displacement[w][static_cast<std::size_t>(cache.wave_plane[w][v])];
            }
            return vec3_cast<float>(u);
        };
        if (lattice != nullptr && pliant::has_avx2() && !lattice->vertex_of.empty()) {
            wave_rest_on_runs(*lattice, rest, axes, displacement_of, edges, tets, cache);
        } else {
            std::vector<Vec3f> u(static_cast<std::size_t>(nv));
            parallel_for(
                nv,
                [&](std::int64_t v) {
                    u[static_cast<std::size_t>(v)] = displacement_of(static_cast<std::size_t>(v));
                },
                VERTEX_GRAIN);
            parallel_for(
                static_cast<std::int64_t>(edges.vertices.size()),
                [&](std::int64_t k) {
                    const auto a =
                        static_cast<std::size_t>(edges.vertices[static_cast<std::size_t>(k)][0]);
                    const auto b =
                        static_cast<std::size_t>(edges.vertices[static_cast<std::size_t>(k)][1]);
                    edges.rest_lengths[static_cast<std::size_t>(k)] =
                        displaced_length(rest[a], u[a], rest[b], u[b], axes);
                },
                EDGE_GRAIN);
            parallel_for(
                static_cast<std::int64_t>(tets.vertices.size()),
                [&](std::int64_t k) {
                    const geometry::Tet& tet = tets.vertices[static_cast<std::size_t>(k)];
                    std::array<Vec3f, 4> r{};
                    std::array<Vec3f, 4> d{};
                    for (std::size_t m = 0; m < 4; ++m) {
                        r[m] = rest[static_cast<std::size_t>(tet[m])];
                        d[m] = u[static_cast<std::size_t>(tet[m])];
                    }
                    tets.rest_volumes[static_cast<std::size_t>(k)] =
                        displaced_volume(r.data(), d.data(), axes);
                },
                TET_GRAIN);
        }
        if (bubbles.empty()) {
            cache.is_valid = true;
            return;
        }
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
    // Step 2: the bubbles' factors on the edge lengths (the waves' or the construction's).
    const auto write_edge_length = [&](std::int64_t k) {
        const auto q = static_cast<std::size_t>(k);
        double length = has_waves ? edges.rest_lengths[q] : edges.rest_lengths0[q];
        length *= std::cbrt(bubble_product(bubbles, box, edge_midpoint(k), t));
        edges.rest_lengths[q] = static_cast<float>(length);
    };
    // Step 3: and on the tet volumes.
    const auto write_tet_volume = [&](std::int64_t k) {
        const auto q = static_cast<std::size_t>(k);
        double volume = has_waves ? tets.rest_volumes[q] : tets.rest_volumes0[q];
        volume *= bubble_product(bubbles, box, tet_centroid(k), t);
        tets.rest_volumes[q] = static_cast<float>(volume);
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
