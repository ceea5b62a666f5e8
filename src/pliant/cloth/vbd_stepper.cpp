#include "pliant/cloth/vbd_stepper.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pliant/cloth/detail/ogc_step.hpp"
#include "pliant/cloth/detail/stepper_checks.hpp"
#include "pliant/cloth/detail/sym3.hpp"
#include "pliant/cloth/dihedral.hpp"
#include "pliant/cloth/isometric_bending.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t VERTEX_GRAIN = 1024;
// Stiffnesses of rigid (zero-compliance) springs and hinges: 1 / this compliance.
constexpr double MIN_COMPLIANCE = 1e-12;
// OGC: detections at most per substep to bring the prediction within the bounds.
constexpr int MAX_PREDICTION_DETECTIONS = 8;
// OGC: a round of detection for the obstacle corrections continues the rounds only when it
// moved some held-back vertex this share of the thickness.
constexpr double MIN_OBSTACLE_ROUND_PROGRESS = 0.01;
// OGC friction: the relative tangential speed (m/s) below which a contact sticks (IPC's ε_v;
// OgcContact::add_forces's slip is ε_v h).
constexpr double FRICTION_SLIP_SPEED = 0.01;

using detail::solve;
using detail::Sym3;

// Chebyshev's weight for sweep `k` (0-based; Chen et al. 2024, §3.5, after Wang 2015).
double chebyshev_omega(int k, double rho, double previous) {
    if (k == 0) {
        return 1.0;
    }
    if (k == 1) {
        return 2.0 / (2.0 - rho * rho);
    }
    return 4.0 / (4.0 - rho * rho * previous);
}

}  // namespace

VBDStepper::VBDStepper(const ClothModel& model, const VBDOptions& options)
    : m_options(options),
      m_num_vertices(model.num_vertices()),
      m_num_triangles(model.triangles().size()) {
    if (options.iterations < 1 || !(options.chebyshev_rho >= 0.0 && options.chebyshev_rho < 1.0)) {
        throw InvalidInput(fmt::format(
            "cloth: vbd: expected iterations >= 1 and 0 <= chebyshev_rho < 1, got {} and {}",
            options.iterations, options.chebyshev_rho));
    }
    if (options.ogc) {
        OgcContact::check_options(*options.ogc);
        // VBD detects again within a substep as its prediction needs (MAX_PREDICTION_DETECTIONS):
        // redetect()'s intervals would always be short and every detection wide (layers: 1.7
        // times the CPU time, docs/performance.md).
        if (options.ogc->wide_query_factor != 0.0) {
            throw InvalidInput(fmt::format(
                "cloth: vbd: ogc contact's wide_query_factor is for the xpbd solver; expected 0 "
                "(off), got {}",
                options.ogc->wide_query_factor));
        }
    }
    const std::size_t n = model.num_vertices();
    const std::span<const Vec3d> rest = model.rest_positions();
    const std::span<const geometry::Triangle> triangles = model.triangles();
    const geometry::MeshTopology& topology = model.topology();

    // Springs per vertex (CSR), both directions.
    m_spring_first.assign(n + 1, 0);
    for (const geometry::Edge& e : topology.edges) {
        ++m_spring_first[static_cast<std::size_t>(e[0]) + 1];
        ++m_spring_first[static_cast<std::size_t>(e[1]) + 1];
        m_rest_lengths.push_back(
            norm(rest[static_cast<std::size_t>(e[1])] - rest[static_cast<std::size_t>(e[0])]));
    }
    for (std::size_t v = 0; v < n; ++v) {
        m_spring_first[v + 1] += m_spring_first[v];
    }
    m_spring_other.resize(static_cast<std::size_t>(m_spring_first[n]));
    m_spring_rest.resize(m_spring_other.size());
    {
        std::vector<std::int32_t> fill(m_spring_first.begin(), m_spring_first.end() - 1);
        for (std::size_t k = 0; k < topology.edges.size(); ++k) {
            const geometry::Edge& e = topology.edges[k];
            for (int side = 0; side < 2; ++side) {
                const auto v = static_cast<std::size_t>(e[static_cast<std::size_t>(side)]);
                const auto slot = static_cast<std::size_t>(fill[v]++);
                m_spring_other[slot] = e[static_cast<std::size_t>(1 - side)];
                m_spring_rest[slot] = m_rest_lengths[k];
            }
        }
    }

    // Hinges (x0, x1, x2, x3) as in dihedral.hpp, x2-x3 the shared edge: isometric where flat at
    // rest, dihedral elsewhere.
    for (std::int32_t e = 0; e < static_cast<std::int32_t>(topology.num_edges()); ++e) {
        const std::span<const std::int32_t> faces = topology.triangles_of_edge(e);
        if (faces.size() != 2) {
            continue;  // boundary or non-manifold edge: no bending
        }
        const geometry::Edge& edge = topology.edges[static_cast<std::size_t>(e)];
        const geometry::Triangle& a = triangles[static_cast<std::size_t>(faces[0])];
        const geometry::Triangle& b = triangles[static_cast<std::size_t>(faces[1])];
        std::int32_t x2 = edge[0];
        std::int32_t x3 = edge[1];
        for (std::size_t k = 0; k < 3; ++k) {
            if (a[k] == edge[1] && a[(k + 1) % 3] == edge[0]) {
                std::swap(x2, x3);
            }
        }
        const auto opposite = [&](const geometry::Triangle& t) {
            for (const std::int32_t v : t) {
                if (v != edge[0] && v != edge[1]) {
                    return v;
                }
            }
            return t[0];
        };
        const std::array<std::int32_t, 4> vertices{opposite(a), opposite(b), x2, x3};
        if (vertices[0] == vertices[1]) {
            continue;
        }
        const auto at = [&](std::int32_t v) {
            return rest[static_cast<std::size_t>(v)];
        };
        Hinge hinge;
        if (const auto stencil = isometric_bending_stencil(at(vertices[0]), at(vertices[1]),
                                                           at(vertices[2]), at(vertices[3]))) {
            hinge.k = *stencil;
        } else {
            hinge.is_dihedral = true;
            hinge.rest_angle = dihedral_angle_value(at(vertices[0]), at(vertices[1]),
                                                    at(vertices[2]), at(vertices[3]));
        }
        m_hinge_vertices.push_back(vertices);
        m_hinges.push_back(hinge);
    }
    m_hinge_first.assign(n + 1, 0);
    for (const auto& h : m_hinge_vertices) {
        for (const std::int32_t v : h) {
            ++m_hinge_first[static_cast<std::size_t>(v) + 1];
        }
    }
    for (std::size_t v = 0; v < n; ++v) {
        m_hinge_first[v + 1] += m_hinge_first[v];
    }
    m_hinge_refs.resize(static_cast<std::size_t>(m_hinge_first[n]));
    m_hinge_ref_k.resize(m_hinge_refs.size());
    {
        std::vector<std::int32_t> fill(m_hinge_first.begin(), m_hinge_first.end() - 1);
        for (std::size_t h = 0; h < m_hinge_vertices.size(); ++h) {
            for (std::size_t k = 0; k < 4; ++k) {
                const auto v = static_cast<std::size_t>(m_hinge_vertices[h][k]);
                const auto slot = static_cast<std::size_t>(fill[v]++);
                m_hinge_refs[slot] = static_cast<std::int32_t>(h * 4 + k);
                m_hinge_ref_k[slot] = m_hinges[h].is_dihedral ? 0.0 : m_hinges[h].k[k];
            }
        }
    }

    // Colouring over edges and hinges (a hinge couples its two wing tips, which share no edge).
    std::vector<std::int32_t> element_vertices;
    std::vector<std::int32_t> element_offsets{0};
    for (const geometry::Edge& e : topology.edges) {
        element_vertices.push_back(e[0]);
        element_vertices.push_back(e[1]);
        element_offsets.push_back(static_cast<std::int32_t>(element_vertices.size()));
    }
    for (const auto& h : m_hinge_vertices) {
        element_vertices.push_back(h[0]);
        element_vertices.push_back(h[1]);
        element_offsets.push_back(static_cast<std::int32_t>(element_vertices.size()));
    }
    m_coloring = color_vertices(static_cast<std::int64_t>(n), element_vertices, element_offsets);

    m_start.resize(n);
    m_inertia.resize(n);
    m_hinge_state.resize(m_hinges.size());
}

void VBDStepper::enable_self_collision(const ClothModel& model, bool enabled) {
    if (!enabled) {
        m_self_collision.reset();
    } else if (!m_self_collision) {
        m_self_collision = detail::make_self_collision(model, m_rest_lengths);
        m_num_position_resets = model.num_position_resets();
        m_gather_end_time = -std::numeric_limits<double>::infinity();
    }
    m_ogc.reset();
    if (enabled && m_options.ogc) {
        m_ogc = detail::make_ogc_contact(
            model, *m_options.ogc,
            1.0 / std::max(model.material().stretch_compliance, MIN_COMPLIANCE));
    }
}

void VBDStepper::restart_self_collision(const ClothModel& model) {
    if (m_self_collision) {
        m_self_collision.reset();
        enable_self_collision(model, true);  // a new OGC contact too: it detects first
    }
}

ClothStepStats VBDStepper::step(ClothModel& model, double dt, int substeps) {
    detail::check_step(model, dt, substeps, m_num_vertices, m_num_triangles);
    if (m_self_collision && m_num_position_resets != model.num_position_resets()) {
        restart_self_collision(model);
    }
    Stopwatch watch;
    const double h = dt / substeps;
    ClothStepStats stats;
    const double start_time = model.time();
    if (m_self_collision) {
        m_self_collision->reset_stats();
    }
    // With self-collision every substep is a fail-safe window (the motion of a VBD substep is
    // already as long as several of XPBD's); candidates are gathered for one window or, while
    // contact is sparse, two.
    model.begin_step(dt);
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<Vec3d> velocities = model.mutable_velocities();
    detail::OgcStepStart ogc_start;
    if (m_ogc) {
        ogc_start =
            detail::begin_ogc_step(*m_ogc, positions, model.inverse_masses(), m_audit, m_num_free);
        m_step_truncated = 0;
    }
    m_step_swept = 0;
    m_step_edges = 0;
    m_step_faces = 0;
    m_step_carried = 0;
    m_step_pushes_undone = 0;
    m_step_max_lag = 0.0;
    for (int s = 0; s < substeps; ++s) {
        const double window_start = start_time + s * h;
        if (m_self_collision && !m_ogc) {
            const double window_end = start_time + (s + 1) * h;
            const double slop = 1e-6 * h;
            if (window_start < m_gather_start_time - slop ||
                window_end > m_gather_end_time + slop) {
                const int windows = m_self_collision->windows_for_next_gather();
                const double span = windows * h;
                m_self_collision->prepare(positions, velocities, window_start, span);
                m_gather_start_time = window_start;
                m_gather_end_time = window_start + span;
            }
        }
        stats.obstacle_contacts = substep(model, h, start_time + (s + 1) * h, stats.solve_ms);
        stats.obstacles_lagging = m_substep_lagging;
        stats.obstacle_max_step = std::max(stats.obstacle_max_step, model.obstacle_step());
        stats.solver_sweeps += m_options.iterations;
    }
    stats.obstacle_swept_contacts = m_step_swept;
    stats.obstacle_edge_contacts = m_step_edges;
    stats.obstacle_face_contacts = m_step_faces;
    stats.obstacle_carried = m_step_carried;
    stats.obstacle_pushes_undone = m_step_pushes_undone;
    stats.obstacle_max_lag = m_step_max_lag;
    if (m_ogc) {
        // The audit's last window ends with the step; vertices it put back left their sets.
        if (m_options.ogc->audit && audit(positions, velocities)) {
            m_ogc->invalidate();
        }
        detail::ogc_step_stats(*m_ogc, ogc_start, m_step_truncated, m_audit, stats);
    }
    model.end_step();
    if (m_self_collision) {
        stats.has_self_collision = true;
        stats.self = m_self_collision->stats();
    }
    stats.ms = watch.elapsed_ms();
    return stats;
}

void VBDStepper::resolve_mesh_obstacles(const ClothModel& model, std::span<Vec3d> positions,
                                        double h) {
    const std::span<const MovingMeshObstacle> meshes = model.mesh_obstacles();
    const std::span<const double> inverse_masses = model.inverse_masses();
    const double thickness = model.material().thickness;
    // The bounds of the XPBD stepper (xpbd_stepper.cpp, resolve_obstacles): with self-collision a
    // jumping surface pushes cloth out at a bounded speed instead of through the cloth.
    const double max_push = detail::catch_up_step(m_self_collision != nullptr, thickness);
    const double max_settle = max_push;
    m_before_mesh_contacts.assign(positions.begin(), positions.end());
    m_mesh_contacts.assign(positions.size(), MeshContact{});
    struct Tally {
        std::int64_t swept = 0;
        std::int64_t lagging = 0;
        double max_lag = 0.0;
    };
    const Tally tally = parallel_reduce(
        static_cast<std::int64_t>(positions.size()), Tally{},
        [&](std::int64_t begin, std::int64_t end) {
            Tally part;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                if (!(inverse_masses[v] > 0.0)) {
                    continue;
                }
                double lag = 0.0;
                for (const MovingMeshObstacle& mesh : meshes) {
                    const MeshContact contact =
                        resolve_mesh_contact(mesh, positions[v], m_start[v], thickness, h,
                                             max_settle, max_push, m_obstacle_lag);
                    part.swept += contact.swept ? 1 : 0;
                    lag = std::max(lag, contact.lag);
                    if (contact.depth > m_mesh_contacts[v].depth) {
                        m_mesh_contacts[v] = contact;
                    }
                }
                part.lagging += lag > 0.0 ? 1 : 0;
                part.max_lag = std::max(part.max_lag, lag);
            }
            return part;
        },
        [](const Tally& a, const Tally& b) {
            return Tally{a.swept + b.swept, a.lagging + b.lagging, std::max(a.max_lag, b.max_lag)};
        },
        VERTEX_GRAIN);
    for (const MovingMeshObstacle& mesh : meshes) {
        m_step_edges += resolve_mesh_edge_contacts(mesh, positions, m_start, m_before_mesh_contacts,
                                                   inverse_masses, model.topology().edges,
                                                   thickness, max_push, m_mesh_feature_contacts);
    }
    for (const MovingMeshObstacle& mesh : meshes) {
        m_step_faces += resolve_mesh_face_contacts(mesh, positions, m_start, m_before_mesh_contacts,
                                                   inverse_masses, model.triangles(), thickness,
                                                   max_push, m_mesh_feature_contacts);
    }
    m_step_swept += tally.swept;
    m_substep_lagging = tally.lagging;
    m_step_max_lag = std::max(m_step_max_lag, tally.max_lag);
    // Vertices left behind the surface are found there next substep.
    m_obstacle_lag = tally.max_lag;
}

bool VBDStepper::push_out_of_obstacles(const ClothModel& model, Vec3d& x, const Vec3d& start,
                                       double h, Vec3d* normal, Vec3d* surface_velocity) const {
    const double thickness = model.material().thickness;
    double deepest = 0.0;
    bool touched = false;
    for (const MovingObstacle& obstacle : model.obstacles()) {
        const ContactCorrection contact = push_out(obstacle.current, x, thickness);
        // Touching: moved now, or (for the contact report) already at the thickness.
        if (contact.depth > 0.0 ||
            (normal != nullptr &&
             surface_distance(obstacle.current, x).distance <= thickness * (1.0 + 1e-9))) {
            if (!touched || contact.depth > deepest) {
                deepest = contact.depth;
                if (normal != nullptr) {
                    *normal = contact.depth > 0.0 ? contact.normal
                                                  : surface_distance(obstacle.current, x).normal;
                    *surface_velocity = obstacle.state.surface_displacement(x) * (1.0 / h);
                }
            }
            touched = true;
        }
    }
    for (const MovingMeshObstacle& mesh : model.mesh_obstacles()) {
        const Vec3d swept_by_surface = mesh.state.surface_displacement(x);
        const double max_depth = norm(x - start) + norm(swept_by_surface) + 2.0 * thickness;
        const Pose& pose = mesh.state.pose;
        Vec3d x_rest = pose.apply_inverse(x);
        const ContactCorrection contact = push_out(*mesh.mesh, x_rest, thickness, max_depth);
        if (!(contact.depth > 0.0)) {
            continue;
        }
        x = pose.apply(x_rest);
        if (!touched || contact.depth > deepest) {
            deepest = contact.depth;
            if (normal != nullptr) {
                *normal = pose.rotation.apply(contact.normal);
                *surface_velocity = swept_by_surface * (1.0 / h);
            }
        }
        touched = true;
    }
    return touched;
}

void VBDStepper::solve_vertex(const ClothModel& model, std::size_t v, double h,
                              std::span<Vec3d> x) const {
    const ClothMaterial& material = model.material();
    const double mass = 1.0 / model.inverse_masses()[v];
    const double k_stretch = 1.0 / std::max(material.stretch_compliance, MIN_COMPLIANCE);
    const double k_bend = 1.0 / std::max(material.bend_compliance, MIN_COMPLIANCE);
    const Vec3d xi = x[v];
    // Inertia.
    const double m_h2 = mass / (h * h);
    Vec3d f = (m_inertia[v] - xi) * m_h2;
    Sym3 hessian;
    hessian.add_diagonal(m_h2);
    // Springs: E = ½ k (l − L)², ∂E/∂x_i = k (l − L) n, ∂²E/∂x_i² = k (n nᵀ + (1 − L/l)(I − n nᵀ)),
    // the second term clamped at 0 for compressed springs (positive semi-definite).
    for (auto s = m_spring_first[v]; s < m_spring_first[v + 1]; ++s) {
        const Vec3d d =
            xi - x[static_cast<std::size_t>(m_spring_other[static_cast<std::size_t>(s)])];
        const double l = norm(d);
        if (!(l > 0.0)) {
            continue;
        }
        const double rest = m_spring_rest[static_cast<std::size_t>(s)];
        const Vec3d u = d * (1.0 / l);
        f -= u * (k_stretch * (l - rest));
        const double perpendicular = std::max(0.0, 1.0 - rest / l);
        hessian.add_diagonal(k_stretch * perpendicular);
        hessian.add_outer(u, k_stretch * (1.0 - perpendicular));
    }
    // Hinges: E = ½ k_b C², Gauss-Newton: ∂E/∂x_i = k_b C ∇C, ∂²E/∂x_i² ≈ k_b ∇C ∇Cᵀ.
    for (auto r = m_hinge_first[v]; r < m_hinge_first[v + 1]; ++r) {
        const auto ref = static_cast<std::size_t>(m_hinge_refs[static_cast<std::size_t>(r)]);
        const std::size_t hinge_index = ref / 4;
        const std::size_t k = ref % 4;
        double c = 0.0;
        Vec3d gradient;
        const double k_weight = m_hinge_ref_k[static_cast<std::size_t>(r)];
        if (k_weight == 0.0) {
            const Hinge& hinge = m_hinges[hinge_index];
            if (!hinge.is_dihedral) {
                continue;  // an isometric hinge with no weight on this vertex
            }
            const std::array<std::int32_t, 4>& hv = m_hinge_vertices[hinge_index];
            const DihedralAngle angle = dihedral_angle(
                x[static_cast<std::size_t>(hv[0])], x[static_cast<std::size_t>(hv[1])],
                x[static_cast<std::size_t>(hv[2])], x[static_cast<std::size_t>(hv[3])]);
            if (!angle.is_valid) {
                continue;
            }
            c = angle.angle - hinge.rest_angle;
            gradient = angle.gradient[k];
        } else {
            // C = n̂ · b, b = Σ K_k x_k kept up to date as the hinge's vertices move, n = K_0 n_A
            // + K_1 n_B (isometric_bending.hpp) as at the sweep's start.
            const HingeState& state = m_hinge_state[hinge_index];
            c = dot(state.normal, state.b);
            gradient = state.normal * k_weight;
        }
        f -= gradient * (k_bend * c);
        hessian.add_outer(gradient, k_bend);
    }
    if (m_ogc) {
        // Friction between layers, sticking below a relative tangential speed of
        // FRICTION_SLIP_SPEED over the substep (the sliding coefficient: the smoothed law has one).
        m_ogc->add_forces(v, xi, m_start, model.material().self_kinetic_friction,
                          FRICTION_SLIP_SPEED * h, f, hessian);
    }
    Vec3d step;
    if (solve(hessian, f, step)) {
        x[v] = xi + step;
    }
}

void VBDStepper::update_vertex(const ClothModel& model, std::size_t v, double h,
                               std::span<Vec3d> x) {
    const Vec3d before = x[v];
    solve_vertex(model, v, h, x);
    if (model.has_obstacles()) {
        push_out_of_obstacles(model, x[v], m_start[v], h, nullptr, nullptr);
    }
    if (m_ogc && m_ogc->truncate(v, before, x[v])) {
        count_truncated(v, x[v]);
    }
    // No other vertex of this colour shares a hinge with v: b is updated without races.
    const Vec3d moved = x[v] - before;
    for (auto r = m_hinge_first[v]; r < m_hinge_first[v + 1]; ++r) {
        const auto ref = static_cast<std::size_t>(m_hinge_refs[static_cast<std::size_t>(r)]);
        const double k_weight = m_hinge_ref_k[static_cast<std::size_t>(r)];
        if (k_weight != 0.0) {
            m_hinge_state[ref / 4].b += moved * k_weight;
        }
    }
}

void VBDStepper::truncate_mesh_contacts(std::span<Vec3d> x, std::span<const double> inverse_masses,
                                        double thickness) {
    // The passes' corrections are the targets. Each round after the first starts from a
    // detection where the last round stopped, so that every vertex may go up to its new bound;
    // the rounds end when none is held back, or when the held ones no longer get anywhere
    // (cloth caught between the obstacle and other cloth: the put-back handles what is left).
    m_mesh_contact_targets.assign(x.begin(), x.end());
    std::copy(m_before_mesh_contacts.begin(), m_before_mesh_contacts.end(), x.begin());
    const double min_progress = MIN_OBSTACLE_ROUND_PROGRESS * thickness;
    struct Round {
        std::int64_t held = 0;
        double max_held_move = 0.0;  // m
    };
    for (int round = 0; round <= MAX_PREDICTION_DETECTIONS; ++round) {
        if (round > 0) {
            detect(x);
        }
        const Round done = parallel_reduce(
            static_cast<std::int64_t>(x.size()), Round{},
            [&](std::int64_t begin, std::int64_t end) {
                Round part;
                for (std::int64_t i = begin; i < end; ++i) {
                    const auto v = static_cast<std::size_t>(i);
                    if (inverse_masses[v] > 0.0) {
                        Vec3d target = m_mesh_contact_targets[v];
                        if (m_ogc->truncate(v, x[v], target)) {
                            ++part.held;
                            part.max_held_move = std::max(part.max_held_move, norm(target - x[v]));
                        }
                        x[v] = target;
                    }
                }
                return part;
            },
            [](const Round& a, const Round& b) {
                return Round{a.held + b.held, std::max(a.max_held_move, b.max_held_move)};
            },
            VERTEX_GRAIN);
        m_step_truncated += done.held;
        if (done.held == 0 || (round > 0 && done.max_held_move < min_progress)) {
            break;
        }
    }
}

void VBDStepper::truncate_all(std::span<const Vec3d> from, std::span<Vec3d> x,
                              std::span<const double> inverse_masses) {
    std::int64_t ball_held = 0;
    m_sweep_truncated.fetch_add(detail::truncate_moves(*m_ogc, from, x, inverse_masses, &ball_held),
                                std::memory_order_relaxed);
    m_sweep_ball_held.fetch_add(ball_held, std::memory_order_relaxed);
}

bool VBDStepper::audit(std::span<Vec3d> x, std::span<Vec3d> velocities) {
    return detail::audit_ogc_window(*m_self_collision, *m_ogc, m_audit, x, velocities);
}

void VBDStepper::detect(std::span<Vec3d> x) {
    if (m_options.ogc->audit) {
        // The window since the last detection (or the step's start) ends here; the velocities
        // of vertices it puts back are set at the substep's end, from their positions.
        m_audit_velocities.assign(x.size(), Vec3d{0.0, 0.0, 0.0});
        audit(x, m_audit_velocities);
    }
    m_ogc->detect(x);
}

void VBDStepper::count_truncated(std::size_t v, const Vec3d& x) {
    m_sweep_truncated.fetch_add(1, std::memory_order_relaxed);
    if (m_ogc->at_ball(v, x)) {
        m_sweep_ball_held.fetch_add(1, std::memory_order_relaxed);
    }
}

bool VBDStepper::redetect_if_needed(std::span<Vec3d> x) {
    const std::int64_t truncated = m_sweep_truncated.exchange(0);
    const std::int64_t ball_held = m_sweep_ball_held.exchange(0);
    m_step_truncated += truncated;
    // Also when a ball held back any vertex in a substep whose pins left their sets: the pins
    // drive the cloth faster than the detections follow, and too few vertices beside them are
    // held back for the share.
    if ((m_pins_left_sets && ball_held > 0) ||
        static_cast<double>(truncated) >
            m_options.ogc->redetect_share * static_cast<double>(m_num_free)) {
        detect(x);
        return true;
    }
    return false;
}

void VBDStepper::update_hinge_normals(std::span<const Vec3d> x) {
    parallel_for(
        static_cast<std::int64_t>(m_hinges.size()),
        [&](std::int64_t i) {
            const auto h = static_cast<std::size_t>(i);
            const Hinge& hinge = m_hinges[h];
            if (hinge.is_dihedral) {
                return;
            }
            const std::array<std::int32_t, 4>& hv = m_hinge_vertices[h];
            const Vec3d& x0 = x[static_cast<std::size_t>(hv[0])];
            const Vec3d& x1 = x[static_cast<std::size_t>(hv[1])];
            const Vec3d& x2 = x[static_cast<std::size_t>(hv[2])];
            const Vec3d& x3 = x[static_cast<std::size_t>(hv[3])];
            const Vec3d n =
                cross(x2 - x0, x3 - x0) * hinge.k[0] + cross(x3 - x1, x2 - x1) * hinge.k[1];
            const double length = norm(n);
            m_hinge_state[h].normal = length > 0.0 ? n * (1.0 / length) : Vec3d{0.0, 0.0, 0.0};
            m_hinge_state[h].b =
                (x0 - x2) * hinge.k[0] + (x1 - x2) * hinge.k[1] + (x3 - x2) * hinge.k[3];
        },
        VERTEX_GRAIN);
}

std::int64_t VBDStepper::substep(ClothModel& model, double h, double t_end, double& solve_ms) {
    Stopwatch watch;
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<Vec3d> velocities = model.mutable_velocities();
    const std::span<const double> inverse_masses = model.inverse_masses();
    const ClothMaterial& material = model.material();
    const auto n = static_cast<std::int64_t>(positions.size());
    if (m_ogc && !m_ogc->has_detection()) {
        detect(positions);  // x_t, intersection-free
    }
    model.apply_air(h, t_end - h);
    const Vec3d gravity = model.gravity();
    // Inertia y = x + h v + h² g, also the first iterate.
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_start[v] = positions[v];
            if (inverse_masses[v] > 0.0) {
                m_inertia[v] = positions[v] + velocities[v] * h + gravity * (h * h);
                positions[v] = m_inertia[v];
            } else {
                m_inertia[v] = positions[v];
            }
        },
        VERTEX_GRAIN);
    model.move_pins(t_end, detail::catch_up_step(m_self_collision != nullptr, material.thickness));
    model.move_obstacles(t_end);
    const bool has_obstacles = model.has_obstacles();
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            if (has_obstacles && inverse_masses[v] > 0.0) {
                push_out_of_obstacles(model, positions[v], m_start[v], h, nullptr, nullptr);
            }
        },
        VERTEX_GRAIN);
    if (m_ogc) {
        // The frame shift from the prediction; a detection where pins left their sets (with the
        // pins where they moved, the free vertices where the substep started); then every vertex
        // within its bound.
        m_ogc->set_shift(positions, inverse_masses);
        m_pins_left_sets = detail::pins_left_sets(*m_ogc, positions, inverse_masses);
        if (m_pins_left_sets) {
            detail::pin_detection_positions(m_start, positions, inverse_masses, m_previous);
            detect(m_previous);
            m_ogc->set_shift(positions, inverse_masses);
        }
        m_sweep_truncated = 0;
        m_sweep_ball_held = 0;
        truncate_all(m_start, positions, inverse_masses);
        // Where many were held back, detect again and move toward the prediction once more: each
        // detection lets every vertex go up to its bound further (the block descent alone would
        // need many sweeps to translate a sheet against its bending).
        for (int round = 0; round < MAX_PREDICTION_DETECTIONS && redetect_if_needed(positions);
             ++round) {
            parallel_for(
                n,
                [&](std::int64_t i) {
                    const auto v = static_cast<std::size_t>(i);
                    if (inverse_masses[v] > 0.0) {
                        Vec3d x = m_inertia[v];
                        if (has_obstacles) {
                            push_out_of_obstacles(model, x, m_start[v], h, nullptr, nullptr);
                        }
                        if (m_ogc->truncate(v, positions[v], x)) {
                            count_truncated(v, x);
                        }
                        positions[v] = x;
                    }
                },
                VERTEX_GRAIN);
        }
    }
    const bool chebyshev = m_options.chebyshev_rho > 0.0;
    if (chebyshev) {
        m_previous.assign(positions.begin(), positions.end());
        m_current.assign(positions.begin(), positions.end());
    }
    double omega = 1.0;
    for (int k = 0; k < m_options.iterations; ++k) {
        update_hinge_normals(positions);
        if (m_ogc) {
            m_ogc->snapshot(positions);
        }
        for (std::int32_t c = 0; c < m_coloring.num_colors(); ++c) {
            const std::span<const std::int32_t> color = m_coloring.color(c);
            parallel_for(
                static_cast<std::int64_t>(color.size()),
                [&](std::int64_t i) {
                    const auto v = static_cast<std::size_t>(color[static_cast<std::size_t>(i)]);
                    if (inverse_masses[v] > 0.0) {
                        update_vertex(model, v, h, positions);
                    }
                },
                VERTEX_GRAIN);
        }
        if (chebyshev) {
            omega = chebyshev_omega(k, m_options.chebyshev_rho, omega);
            parallel_for(
                n,
                [&](std::int64_t i) {
                    const auto v = static_cast<std::size_t>(i);
                    if (inverse_masses[v] > 0.0 && k > 0) {
                        const Vec3d from = positions[v];
                        positions[v] = m_previous[v] + (positions[v] - m_previous[v]) * omega;
                        if (has_obstacles) {
                            push_out_of_obstacles(model, positions[v], m_start[v], h, nullptr,
                                                  nullptr);
                        }
                        if (m_ogc && m_ogc->truncate(v, from, positions[v])) {
                            count_truncated(v, positions[v]);
                        }
                    }
                    m_previous[v] = m_current[v];
                    m_current[v] = positions[v];
                },
                VERTEX_GRAIN);
        }
        if (m_ogc) {
            redetect_if_needed(positions);
        }
    }
    // Seams are hard constraints, projected after the block descent as the XPBD stepper does.
    if (m_ogc && !model.seams().empty()) {
        m_previous.assign(positions.begin(), positions.end());  // where the seams move them from
    }
    model.seams().project(positions, inverse_masses, t_end);  // seams.hpp
    if (m_ogc && !model.seams().empty()) {
        truncate_all(m_previous, positions, inverse_masses);
        redetect_if_needed(positions);
    }
    m_substep_lagging = 0;
    if (!model.mesh_obstacles().empty()) {
        resolve_mesh_obstacles(model, positions, h);
        m_put_back.seed(positions, m_before_mesh_contacts);
        if (m_ogc) {
            truncate_mesh_contacts(positions, inverse_masses, material.thickness);
        }
        // What the passes left in an obstacle (or OGC's truncation took back into one) goes back
        // to where it was, carried along.
        // As far as the passes may push (resolve_mesh_obstacles' max_push, beyond the thickness).
        const double max_carry =
            material.thickness +
            detail::catch_up_step(m_self_collision != nullptr, material.thickness);
        m_step_carried +=
            m_put_back.run(model, m_start, ObstaclePutBack::Fallback::carried, max_carry);
        for (const std::int32_t v : m_put_back.moved()) {
            m_mesh_contacts[static_cast<std::size_t>(v)] = MeshContact{};  // moves with it
        }
        // Carried vertices left their OGC sets: a detection there (its audit checks their move).
        if (m_ogc && !redetect_if_needed(positions) && !m_put_back.moved().empty()) {
            detect(positions);
        }
    }
    solve_ms += watch.elapsed_ms();
    if (m_self_collision && !m_ogc) {
        if (has_obstacles) {
            m_before_self.assign(positions.begin(), positions.end());
        }
        m_self_collision->project(positions, m_start, inverse_masses, material, t_end, h);
        if (has_obstacles) {
            // A push that took a triangle into an obstacle is undone.
            m_put_back.seed(positions, m_before_self);
            m_step_pushes_undone +=
                m_put_back.run(model, m_before_self, ObstaclePutBack::Fallback::reference);
        }
    }
    watch.restart();
    const double keep = std::max(0.0, 1.0 - material.damping * h);
    const std::int64_t contacts = parallel_reduce(
        n, std::int64_t{0},
        [&](std::int64_t begin, std::int64_t end) {
            std::int64_t touching = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                Vec3d velocity = (positions[v] - m_start[v]) * (1.0 / h);
                if (inverse_masses[v] > 0.0 && has_obstacles) {
                    Vec3d normal;
                    Vec3d surface_velocity;
                    Vec3d x = positions[v];
                    bool touched =
                        push_out_of_obstacles(model, x, m_start[v], h, &normal, &surface_velocity);
                    if (!touched && !m_mesh_contacts.empty() && m_mesh_contacts[v].depth > 0.0) {
                        normal = m_mesh_contacts[v].normal;
                        surface_velocity = m_mesh_contacts[v].surface_velocity;
                        touched = true;
                    }
                    if (touched) {
                        // The normal speed the contact took from the inertial motion bounds the
                        // friction; the outward relative normal velocity is dropped (inelastic).
                        const double normal_speed =
                            std::max(0.0, dot(positions[v] - m_inertia[v], normal)) / h;
                        Vec3d relative = velocity - surface_velocity;
                        const double outward = dot(relative, normal);
                        if (outward > 0.0) {
                            relative -= normal * outward;
                        }
                        velocity = surface_velocity + apply_friction(relative, normal, normal_speed,
                                                                     material.static_friction,
                                                                     material.kinetic_friction);
                        ++touching;
                    }
                }
                velocities[v] = velocity * keep;
            }
            return touching;
        },
        [](std::int64_t a, std::int64_t b) { return a + b; }, VERTEX_GRAIN);
    if (m_ogc) {
        m_ogc->remove_separating_velocity(positions, velocities, inverse_masses);
    }
    if (m_self_collision && !m_ogc) {
        // The window (this substep) ends with the fail-safe over its motion.
        m_self_collision->enforce(m_start, positions, velocities, t_end - h, t_end);
    }
    solve_ms += watch.elapsed_ms();
    return contacts;
}

void VBDStepper::save_state(ByteWriter& out) const {
    out.put(static_cast<std::uint64_t>(m_num_vertices));
    out.put(static_cast<std::uint64_t>(m_num_triangles));
    out.put(m_num_position_resets);
    out.put(m_gather_start_time);
    out.put(m_gather_end_time);
    out.put(m_self_collision != nullptr);
    if (m_self_collision) {
        m_self_collision->save_state(out);
    }
    out.put(m_ogc != nullptr);
    if (m_ogc) {
        m_ogc->save_state(out);
    }
    out.put(m_obstacle_lag);
}

void VBDStepper::load_state(const ClothModel& model, ByteReader& in) {
    const auto num_vertices = in.get<std::uint64_t>("vbd.num_vertices");
    const auto num_triangles = in.get<std::uint64_t>("vbd.num_triangles");
    if (num_vertices != m_num_vertices || num_triangles != m_num_triangles) {
        throw InvalidInput(fmt::format(
            "{}: cloth vbd stepper: a state of {} vertices and {} triangles, the cloth has {} and "
            "{}",
            in.source(), num_vertices, num_triangles, m_num_vertices, m_num_triangles));
    }
    m_num_position_resets = in.get<std::int64_t>("vbd.num_position_resets");
    m_gather_start_time = in.get<double>("vbd.gather_start_time");
    m_gather_end_time = in.get<double>("vbd.gather_end_time");
    const bool has_self_collision = in.get_bool("vbd.has_self_collision");
    if (has_self_collision != (m_self_collision != nullptr)) {
        throw InvalidInput(fmt::format(
            "{}: cloth vbd stepper: self-collision {} in the state, {} here", in.source(),
            has_self_collision ? "on" : "off", m_self_collision ? "on" : "off"));
    }
    if (m_self_collision) {
        m_self_collision = std::make_unique<SelfCollision>(model.triangles(), model.num_vertices(),
                                                           model.material().thickness);
        m_self_collision->load_state(in);
    }
    const bool has_ogc = in.get_bool("vbd.has_ogc");
    if (has_ogc != (m_ogc != nullptr)) {
        throw InvalidInput(
            fmt::format("{}: cloth vbd stepper: ogc contact {} in the state, {} here", in.source(),
                        has_ogc ? "on" : "off", m_ogc ? "on" : "off"));
    }
    if (m_ogc) {
        enable_self_collision(model, true);  // a fresh OGC contact
        m_ogc->load_state(in);
    }
    m_obstacle_lag = in.get<double>("vbd.obstacle_lag");
}

}  // namespace pliant::cloth
