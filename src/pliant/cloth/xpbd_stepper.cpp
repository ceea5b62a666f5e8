#include "pliant/cloth/xpbd_stepper.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/cloth/detail/ogc_step.hpp"
#include "pliant/cloth/detail/stepper_checks.hpp"
#include "pliant/cloth/dihedral.hpp"
#include "pliant/cloth/isometric_bending.hpp"
#include "pliant/cloth/mesh_contact.hpp"
#include "pliant/cloth/obstacle_intersections.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t CONSTRAINT_GRAIN = 1024;
constexpr std::int64_t VERTEX_GRAIN = 2048;
constexpr std::int64_t CHAIN_PACKET_GRAIN = 2;
// The self-collision fail-safe checks the motion of every this many substeps (a window); the
// candidate pairs are gathered for one or two windows (SelfCollision::windows_for_next_gather).
constexpr int FAIL_SAFE_WINDOW = 4;
// A strain limit moves its two vertices by at most this fraction of the thickness per substep
// (per limit: a vertex in several limits can move several times that; strain_hierarchy.hpp).
// Larger moves outrun the self-collision's proximity constraints, which act once per substep
// (docs/journal/2026-11-25-strain-limiting.md).
constexpr double STRAIN_LIMIT_MOVE = 0.1;
// OGC: the contact stiffness OgcContact asks for is not used by XPBD's hard contact constraint.
constexpr double OGC_UNUSED_STIFFNESS = 1.0;

// Coordinates below 2^-200 m (6e-61 m: nothing cloth has is that short) become 0: the exact
// predicates of the self-collision and of the intersection count take 0 or magnitudes from
// 2^-300 up (geometry/exact_predicates.hpp; differences of coordinates of 2^-200 or more are
// multiples of 2^-252), and a chain solve spreads corrections that small along its chain (a
// vertex on a grid's symmetry line got x = 1.5e-98 in the pile scene).
void flush_tiny(Vec3d& x) {
    constexpr double TINY = 0x1p-200;
    x.x = std::abs(x.x) < TINY ? 0.0 : x.x;
    x.y = std::abs(x.y) < TINY ? 0.0 : x.y;
    x.z = std::abs(x.z) < TINY ? 0.0 : x.z;
}

}  // namespace

XPBDStepper::XPBDStepper(const ClothModel& model)
    : m_num_vertices(model.num_vertices()),
      m_num_triangles(model.triangles().size()),
      m_previous_positions(model.rest_positions().begin(), model.rest_positions().end()),
      m_contact_depths(model.num_vertices(), 0.0),
      m_contact_settled(model.num_vertices(), 0.0),
      m_contact_normals(model.num_vertices(), Vec3d{0.0, 0.0, 1.0}),
      m_contact_velocities(model.num_vertices(), Vec3d{0.0, 0.0, 0.0}) {
    const std::size_t num_vertices = model.num_vertices();
    const std::span<const Vec3d> rest = model.rest_positions();
    const std::span<const geometry::Triangle> triangles = model.triangles();
    const ClothMaterial& material = model.material();

    // Constraints from the topology.
    const geometry::MeshTopology& topology = model.topology();
    for (const geometry::Edge& e : topology.edges) {
        m_stretch_vertices.push_back({e[0], e[1]});
        m_rest_lengths.push_back(
            norm(rest[static_cast<std::size_t>(e[1])] - rest[static_cast<std::size_t>(e[0])]));
    }
    // Hinges (x0, x1, x2, x3) as in dihedral.hpp, x2-x3 the shared edge, with their rest angles
    // (dihedral) or stencils (isometric).
    std::vector<std::array<std::int32_t, 4>> dihedral_hinges;
    std::vector<double> rest_angles;
    std::vector<std::array<std::int32_t, 4>> isometric_hinges;
    std::vector<std::array<double, 4>> stencils;
    for (std::int32_t e = 0; e < static_cast<std::int32_t>(topology.num_edges()); ++e) {
        const std::span<const std::int32_t> faces = topology.triangles_of_edge(e);
        if (faces.size() != 2) {
            continue;  // boundary or non-manifold edge: no bending
        }
        const geometry::Edge& edge = topology.edges[static_cast<std::size_t>(e)];
        // Orient the shared edge as triangle A traverses it: A = (x0, x2, x3).
        const geometry::Triangle& a = triangles[static_cast<std::size_t>(faces[0])];
        const geometry::Triangle& b = triangles[static_cast<std::size_t>(faces[1])];
        std::int32_t x2 = edge[0];
        std::int32_t x3 = edge[1];
        for (int k = 0; k < 3; ++k) {
            if (a[static_cast<std::size_t>(k)] == edge[1] &&
                a[static_cast<std::size_t>((k + 1) % 3)] == edge[0]) {
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
            continue;  // two triangles on the same three vertices
        }
        const auto at = [&](std::int32_t v) {
            return rest[static_cast<std::size_t>(v)];
        };
        if (material.bending == BendingModel::isometric) {
            if (const auto stencil = isometric_bending_stencil(at(vertices[0]), at(vertices[1]),
                                                               at(vertices[2]), at(vertices[3]))) {
                isometric_hinges.push_back(vertices);
                stencils.push_back(*stencil);
                continue;
            }
        }
        dihedral_hinges.push_back(vertices);
        rest_angles.push_back(dihedral_angle_value(at(vertices[0]), at(vertices[1]),
                                                   at(vertices[2]), at(vertices[3])));
    }
    m_stretch =
        color_edges(m_stretch_vertices, m_rest_lengths, static_cast<std::int64_t>(num_vertices));
    // The kernels' columns, in colour order.
    m_dihedral = color_hinges(dihedral_hinges, static_cast<std::int64_t>(num_vertices));
    for (const std::int32_t i : m_dihedral.colors.order) {
        m_dihedral_rest.push_back(rest_angles[static_cast<std::size_t>(i)]);
    }
    m_isometric = color_hinges(isometric_hinges, static_cast<std::int64_t>(num_vertices));
    for (const std::int32_t i : m_isometric.colors.order) {
        for (std::size_t k = 0; k < 4; ++k) {
            m_isometric_k[k].push_back(stencils[static_cast<std::size_t>(i)][k]);
        }
    }
    m_packed.resize(num_vertices);
    if (material.stretch_solver == StretchSolver::chains) {
        // In colour order, so that an edge's index in the chains is its column in m_stretch.
        std::vector<std::array<std::int32_t, 2>> colored(m_stretch.p.size());
        for (std::size_t i = 0; i < colored.size(); ++i) {
            colored[i] = {m_stretch.p[i], m_stretch.q[i]};
        }
        m_chains = StretchChains(colored, m_stretch.rest, rest);
        m_chain_scratch.resize(static_cast<std::size_t>(m_chains.scratch_size()));
        m_stretch_lambda.assign(colored.size(), 0.0);
        m_packed.push_back({0.0, 0.0, 0.0, 0.0});  // the padding vertex
    }
    if (std::isfinite(material.strain_limit)) {
        m_strain_hierarchy = StrainHierarchy(static_cast<std::int64_t>(num_vertices),
                                             topology.edges, m_rest_lengths);
    }
}

void XPBDStepper::enable_self_collision(const ClothModel& model, bool enabled) {
    if (!enabled) {
        m_self_collision.reset();
    } else if (!m_self_collision) {
        m_self_collision = detail::make_self_collision(model, m_rest_lengths);
        m_num_position_resets = model.num_position_resets();
        m_gather_end_time = -std::numeric_limits<double>::infinity();
    }
    m_ogc.reset();
    if (enabled && m_ogc_options) {
        m_ogc = detail::make_ogc_contact(model, *m_ogc_options, OGC_UNUSED_STIFFNESS);
    }
}

void XPBDStepper::restart_self_collision(const ClothModel& model) {
    if (m_self_collision) {
        m_self_collision.reset();
        enable_self_collision(model, true);
    }
}

void XPBDStepper::set_ogc(const ClothModel& model, const std::optional<OgcOptions>& options) {
    if (options) {
        OgcContact::check_options(*options);
    }
    m_ogc_options = options;
    // Self-collision stays as it was (on or off), with the new contact when on.
    const bool enabled = m_self_collision != nullptr;
    enable_self_collision(model, false);
    enable_self_collision(model, enabled);
}

bool XPBDStepper::needs_detection(std::int64_t truncated) const {
    return static_cast<double>(truncated) >
           m_ogc->options().redetect_share * static_cast<double>(m_num_free);
}

bool XPBDStepper::audit(std::span<Vec3d> x, std::span<Vec3d> velocities) {
    return detail::audit_ogc_window(*m_self_collision, *m_ogc, m_audit, x, velocities);
}

void XPBDStepper::detect(std::span<Vec3d> x, std::span<Vec3d> velocities, bool held_back) {
    if (m_ogc->options().audit) {
        audit(x, velocities);
    }
    if (held_back) {
        m_ogc->redetect(x);
    } else {
        m_ogc->detect(x);
    }
}

void XPBDStepper::catch_up(std::span<Vec3d> x, std::span<Vec3d> velocities,
                           std::span<const double> inverse_masses) {
    for (int round = 0; round < detail::MAX_CATCH_UP_DETECTIONS; ++round) {
        // Velocities the audit sets are overwritten at the substep's end.
        detect(x, velocities);  // the truncated positions, intersection-free
        m_ogc_from.assign(x.begin(), x.end());
        std::copy(m_ogc_wanted.begin(), m_ogc_wanted.end(), x.begin());
        std::int64_t ball_held = 0;
        detail::truncate_moves(*m_ogc, m_ogc_from, x, inverse_masses, &ball_held);
        if (ball_held == 0) {
            return;
        }
    }
}

ClothStepStats XPBDStepper::step(ClothModel& model, double dt, int substeps) {
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
    // With self-collision the step runs in windows of FAIL_SAFE_WINDOW substeps, each ending with
    // the fail-safe over the window's motion; candidates are gathered at the start of a window for
    // it and, while contact is sparse, the next one too. A window's start-to-end line is close to
    // the path its substeps took (a frame's is not: cloth that folds around something within a
    // frame crosses it on the straight line between the frame's ends), and a vertex put back loses
    // only that window's motion.
    model.begin_step(dt);
    m_step_pushes_undone = 0;
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<Vec3d> velocities = model.mutable_velocities();
    detail::OgcStepStart ogc_start;
    if (m_ogc) {
        ogc_start =
            detail::begin_ogc_step(*m_ogc, positions, model.inverse_masses(), m_audit, m_num_free);
        m_step_truncated = 0;
    }
    for (int s = 0; s < substeps; ++s) {
        if (m_self_collision && !m_ogc && s % FAIL_SAFE_WINDOW == 0) {
            // A new gather unless the last one's span covers this window (times compared to a
            // millionth of a substep: steps sum their times differently).
            const double window_start = start_time + s * h;
            const double window_end = start_time + std::min(s + FAIL_SAFE_WINDOW, substeps) * h;
            const double slop = 1e-6 * h;
            if (window_start < m_gather_start_time - slop ||
                window_end > m_gather_end_time + slop) {
                const int windows = m_self_collision->windows_for_next_gather();
                const double span = windows * FAIL_SAFE_WINDOW * h;
                m_self_collision->prepare(positions, velocities, window_start, span);
                m_gather_start_time = window_start;
                m_gather_end_time = window_start + span;
            }
            m_window_start.assign(positions.begin(), positions.end());
            m_window_start_time = window_start;
            if (!model.mesh_obstacles().empty()) {
                m_window_obstacles.capture(model);
            }
        }
        const ObstacleTally tally = substep(model, h, start_time + (s + 1) * h, stats.solve_ms);
        stats.obstacle_contacts = tally.contacts;
        stats.obstacle_swept_contacts += tally.swept;
        stats.obstacle_edge_contacts += tally.edges;
        stats.obstacle_face_contacts += tally.faces;
        stats.obstacle_carried += tally.carried;
        stats.obstacles_lagging = tally.lagging;
        stats.obstacle_max_lag = std::max(stats.obstacle_max_lag, tally.max_lag);
        stats.obstacle_max_step = std::max(stats.obstacle_max_step, model.obstacle_step());
        if (m_self_collision && !m_ogc &&
            (s % FAIL_SAFE_WINDOW == FAIL_SAFE_WINDOW - 1 || s == substeps - 1)) {
            stats.obstacle_carried += enforce_window(model, start_time + (s + 1) * h);
        }
    }
    if (m_ogc) {
        // The audit's last window ends with the step; vertices it put back left their sets.
        if (m_ogc->options().audit && audit(positions, velocities)) {
            m_ogc->invalidate();
        }
        detail::ogc_step_stats(*m_ogc, ogc_start, m_step_truncated, m_audit, stats);
    }
    model.end_step();
    stats.obstacle_pushes_undone = m_step_pushes_undone;
    if (m_self_collision) {
        stats.has_self_collision = true;
        stats.self = m_self_collision->stats();
    }
    stats.ms = watch.elapsed_ms();
    return stats;
}

XPBDStepper::ObstacleTally XPBDStepper::substep(ClothModel& model, double h, double t_end,
                                                double& solve_ms) {
    Stopwatch watch;
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<Vec3d> velocities = model.mutable_velocities();
    const std::span<const double> inverse_masses = model.inverse_masses();
    const ClothMaterial& material = model.material();
    const auto n = static_cast<std::int64_t>(positions.size());
    if (m_ogc) {
        m_ogc->begin_substep();
    }
    if (m_ogc && !m_ogc->has_detection()) {
        solve_ms += watch.elapsed_ms();
        detect(positions, velocities);  // x_t, intersection-free
        watch.restart();
    }
    model.apply_air(h, t_end - h);
    const Vec3d gravity = model.gravity();
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_previous_positions[v] = positions[v];
            if (inverse_masses[v] > 0.0) {
                velocities[v] += gravity * h;
                positions[v] += velocities[v] * h;
            }
        },
        VERTEX_GRAIN);
    // With self-collision, pins move at most CATCH_UP_IN_THICKNESS thickness per substep.
    model.move_pins(t_end, detail::catch_up_step(m_self_collision != nullptr, material.thickness));
    if (m_ogc) {
        // The frame shift from the prediction; a detection where pins left their sets (with the
        // pins where they moved, the free vertices where the substep started); then every free
        // vertex within its bound.
        m_ogc->set_shift(positions, inverse_masses);
        m_pins_left_sets = detail::pins_left_sets(*m_ogc, positions, inverse_masses);
        if (m_pins_left_sets) {
            detail::pin_detection_positions(m_previous_positions, positions, inverse_masses,
                                            m_ogc_from);
            // Velocities the audit sets are overwritten at the substep's end.
            detect(m_ogc_from, velocities);
            m_ogc->set_shift(positions, inverse_masses);
        }
        if (m_pins_left_sets) {  // catch_up's target
            m_ogc_wanted.assign(positions.begin(), positions.end());
        }
        std::int64_t ball_held = 0;
        m_substep_truncated = detail::truncate_moves(*m_ogc, m_previous_positions, positions,
                                                     inverse_masses, &ball_held);
        if (m_pins_left_sets && ball_held > 0) {
            catch_up(positions, velocities, inverse_masses);
        }
        m_ogc_from.assign(positions.begin(), positions.end());
    }
    project_constraints(model, h);
    model.seams().project(positions, inverse_masses, t_end);  // seams.hpp
    model.move_obstacles(t_end);
    ObstacleTally contacts = resolve_obstacles(model, h);
    // Vertices left behind a mesh obstacle's surface are found there next substep.
    m_obstacle_lag = contacts.max_lag;
    if (!model.mesh_obstacles().empty()) {
        // What the passes left in a mesh obstacle goes back to where it was, carried along (with
        // OGC after its truncation, which can pull part of a correction back). Analytic
        // obstacles need no such pass: their vertex pass projects each vertex exactly.
        m_put_back.seed(positions, m_before_contacts);
        if (!m_ogc) {
            contacts.carried = put_back_into_obstacle_motion(model);
        }
    }
    solve_ms += watch.elapsed_ms();
    // Self-contacts last: the substep ends with the cloth apart from itself (an obstacle's push
    // may have pressed one layer into the next), and a push that takes cloth into an obstacle is
    // undone.
    if (m_ogc) {
        watch.restart();
        const bool meshes = !model.mesh_obstacles().empty();
        if (meshes) {
            // Where the passes left the cloth: the undo's fallback below, and
            // release_stuck_triangles'.
            m_before_self.assign(positions.begin(), positions.end());
        }
        m_ogc->project(positions, m_previous_positions, inverse_masses,
                       material.self_static_friction, material.self_kinetic_friction);
        if (meshes) {
            // A push that took a triangle into an obstacle is undone (the truncation below keeps
            // every vertex within its bound either way); then every vertex moved since the
            // passes began (by them or by the contact) is seeded for the put-back after the
            // truncation.
            m_put_back.seed(positions, m_before_self);
            m_step_pushes_undone +=
                m_put_back.run(model, m_before_self, ObstaclePutBack::Fallback::reference);
            m_put_back.seed(positions, m_before_contacts);
        }
        // Vertices held back in the prediction or here (a vertex held back in both counts twice).
        if (m_pins_left_sets) {  // catch_up's target
            m_ogc_wanted.assign(positions.begin(), positions.end());
        }
        std::int64_t ball_held = 0;
        m_substep_truncated +=
            detail::truncate_moves(*m_ogc, m_ogc_from, positions, inverse_masses, &ball_held);
        if (m_pins_left_sets && ball_held > 0) {
            catch_up(positions, velocities, inverse_masses);
        }
        if (meshes) {
            contacts.carried = put_back_into_obstacle_motion(model);
            contacts.carried += release_stuck_triangles(model);
        }
        m_step_truncated += m_substep_truncated;
        solve_ms += watch.elapsed_ms();
    } else if (m_self_collision) {
        if (model.has_obstacles()) {
            m_before_self.assign(positions.begin(), positions.end());
        }
        m_self_collision->project(positions, m_previous_positions, inverse_masses, material, t_end,
                                  h);
        if (model.has_obstacles()) {
            // A push that took a triangle into an obstacle is undone.
            m_put_back.seed(positions, m_before_self);
            m_step_pushes_undone +=
                m_put_back.run(model, m_before_self, ObstaclePutBack::Fallback::reference);
        }
    }
    watch.restart();
    const double keep = std::max(0.0, 1.0 - material.damping * h);
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            flush_tiny(positions[v]);
            Vec3d velocity = (positions[v] - m_previous_positions[v]) * (1.0 / h);
            if (m_contact_depths[v] > 0.0) {
                // A penetration the substep began with is undone without becoming velocity
                // (cloth given inside an obstacle comes out, it is not thrown out); friction acts
                // on the velocity relative to the obstacle's surface, bounded by the rest.
                const double settled = m_contact_settled[v];
                velocity -= m_contact_normals[v] * (settled / h);
                velocity = m_contact_velocities[v] +
                           apply_friction(velocity - m_contact_velocities[v], m_contact_normals[v],
                                          (m_contact_depths[v] - settled) / h,
                                          material.static_friction, material.kinetic_friction);
            }
            velocities[v] = velocity * keep;
        },
        VERTEX_GRAIN);
    solve_ms += watch.elapsed_ms();
    if (m_ogc && needs_detection(m_substep_truncated)) {
        detect(positions, velocities, /*held_back=*/true);
    } else if (m_ogc && contacts.carried > 0) {
        detect(positions, velocities);  // carried vertices left their sets
    }
    return contacts;
}

void XPBDStepper::project_constraints(ClothModel& model, double h) {
    // Positions and inverse masses packed for the kernels (detail/constraint_kernels.hpp), then
    // the strain limits (with material.strain_limit; strain_hierarchy.hpp), stretch and bending
    // colour by colour, each colour in parallel over fixed chunks.
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<const double> inverse_masses = model.inverse_masses();
    const ClothMaterial& material = model.material();
    const auto n = static_cast<std::int64_t>(positions.size());
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            m_packed[v] = {positions[v].x, positions[v].y, positions[v].z, inverse_masses[v]};
        },
        VERTEX_GRAIN);
    detail::PackedVertex* x = m_packed.data();
    if (std::isfinite(material.strain_limit)) {
        m_strain_hierarchy.project(x, material.strain_limit,
                                   material.thickness > 0.0
                                       ? STRAIN_LIMIT_MOVE * material.thickness
                                       : std::numeric_limits<double>::infinity());
    }
    const double stretch_alpha = material.stretch_compliance / (h * h);
    // Chains first (their Δλ per edge, in colour order, to m_stretch_lambda), then the sweep
    // over single edges as XPBD's next iteration from those λ.
    const detail::ChainSolve chain_solve{stretch_alpha, CHAIN_REGULARIZATION,
                                         CHAIN_STRAIN_REGULARIZATION};
    for (std::int32_t f = 0; f < m_chains.num_families(); ++f) {
        const std::int32_t first = m_chains.first_packet(f);
        parallel_for_chunks(m_chains.first_packet(f + 1) - first, CHAIN_PACKET_GRAIN,
                            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                                for (std::int64_t i = begin; i < end; ++i) {
                                    const auto p = first + static_cast<std::int32_t>(i);
                                    detail::project_chain_packet(
                                        x, m_chains.packet(p), chain_solve, m_stretch_lambda.data(),
                                        m_chain_scratch.data() + m_chains.scratch_offset(p));
                                }
                            });
    }
    const bool chains = m_chains.num_families() > 0;
    for (std::int32_t c = 0; c < m_stretch.colors.num_colors(); ++c) {
        const auto offset =
            static_cast<std::size_t>(m_stretch.colors.offsets[static_cast<std::size_t>(c)]);
        const detail::StretchColumns columns{
            m_stretch.p.data() + offset, m_stretch.q.data() + offset,
            m_stretch.rest.data() + offset, chains ? m_stretch_lambda.data() + offset : nullptr};
        parallel_for_chunks(static_cast<std::int64_t>(m_stretch.colors.color(c).size()),
                            CONSTRAINT_GRAIN,
                            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                                detail::project_stretch(x, columns, begin, end, stretch_alpha);
                            });
    }
    const double bend_alpha = material.bend_compliance / (h * h);
    for (std::int32_t c = 0; c < m_dihedral.colors.num_colors(); ++c) {
        const auto offset =
            static_cast<std::size_t>(m_dihedral.colors.offsets[static_cast<std::size_t>(c)]);
        const detail::BendingColumns columns{
            m_dihedral.v[0].data() + offset, m_dihedral.v[1].data() + offset,
            m_dihedral.v[2].data() + offset, m_dihedral.v[3].data() + offset,
            m_dihedral_rest.data() + offset};
        parallel_for_chunks(static_cast<std::int64_t>(m_dihedral.colors.color(c).size()),
                            CONSTRAINT_GRAIN,
                            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                                detail::project_bending(x, columns, begin, end, bend_alpha);
                            });
    }
    for (std::int32_t c = 0; c < m_isometric.colors.num_colors(); ++c) {
        const auto offset =
            static_cast<std::size_t>(m_isometric.colors.offsets[static_cast<std::size_t>(c)]);
        const detail::IsometricBendingColumns columns{
            m_isometric.v[0].data() + offset, m_isometric.v[1].data() + offset,
            m_isometric.v[2].data() + offset, m_isometric.v[3].data() + offset,
            m_isometric_k[0].data() + offset, m_isometric_k[1].data() + offset,
            m_isometric_k[2].data() + offset, m_isometric_k[3].data() + offset};
        parallel_for_chunks(
            static_cast<std::int64_t>(m_isometric.colors.color(c).size()), CONSTRAINT_GRAIN,
            [&](std::int64_t, std::int64_t begin, std::int64_t end) {
                detail::project_isometric_bending(x, columns, begin, end, bend_alpha);
            });
    }
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(i);
            positions[v] = {m_packed[v].x, m_packed[v].y, m_packed[v].z};
        },
        VERTEX_GRAIN);
}

XPBDStepper::ObstacleTally XPBDStepper::resolve_obstacles(ClothModel& model, double h) {
    if (!model.has_obstacles()) {
        return {};
    }
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<const double> inverse_masses = model.inverse_masses();
    const std::span<const MovingObstacle> obstacles = model.obstacles();
    const std::span<const MovingMeshObstacle> mesh_obstacles = model.mesh_obstacles();
    const double thickness = model.material().thickness;
    // Of a penetration the substep began with, at most this much is undone per substep (the
    // rest stays for the next substeps): cloth given deep inside an obstacle, or left there by
    // an obstacle that jumps, comes out at a bounded speed, as a jumping pin chases its target.
    const double max_settle = detail::catch_up_step(m_self_collision != nullptr, thickness);
    // Holds back the part of a push of `depth` along `normal` that undoes more than max_settle of
    // the penetration `settled` the substep began with: moves x back by it and returns it.
    const auto bound_settle = [max_settle](Vec3d& x, const Vec3d& normal, double settled) {
        const double excess = settled > max_settle ? settled - max_settle : 0.0;
        if (excess > 0.0) {
            x -= normal * excess;
        }
        return excess;
    };
    // Of the rest of a push (beyond the vertex's own motion and the thickness), at most this
    // much per substep: an obstacle that jumps pushes cloth out at a bounded speed (the vertex
    // lags behind its surface) instead of sweeping it through the cloth in one substep.
    const double max_push = max_settle;
    if (!mesh_obstacles.empty()) {
        m_before_contacts.assign(positions.begin(), positions.end());
    }
    ObstacleTally total = parallel_reduce(
        static_cast<std::int64_t>(positions.size()), ObstacleTally{},
        [&](std::int64_t begin, std::int64_t end) {
            ObstacleTally tally;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                m_contact_depths[v] = 0.0;
                m_contact_settled[v] = 0.0;
                if (!(inverse_masses[v] > 0.0)) {
                    continue;
                }
                const Vec3d& start = m_previous_positions[v];
                double lag = 0.0;
                for (const MovingObstacle& obstacle : obstacles) {
                    if (out_of_reach(obstacle.current, positions[v], thickness)) {
                        continue;  // push_out's answer, without the call
                    }
                    const Vec3d before_push = positions[v];
                    ContactCorrection contact = push_out(obstacle.current, positions[v], thickness);
                    if (contact.depth > 0.0) {
                        // How deep the vertex already was when the substep began.
                        const double was_in =
                            thickness - surface_distance(obstacle.previous, start).distance;
                        double settled = std::clamp(was_in, 0.0, contact.depth);
                        const double excess = bound_settle(positions[v], contact.normal, settled);
                        contact.depth -= excess;
                        settled -= excess;
                        // The part of the push the obstacle's own motion asks for, bounded.
                        const double pushed =
                            std::max(0.0, contact.depth - settled -
                                              (norm(before_push - start) + thickness + max_push));
                        if (pushed > 0.0) {
                            positions[v] -= contact.normal * pushed;
                            contact.depth -= pushed;
                            lag = std::max(lag, pushed);
                        }
                        if (contact.depth > m_contact_depths[v]) {
                            m_contact_depths[v] = contact.depth;
                            m_contact_normals[v] = contact.normal;
                            // The surface point under x moved from where the previous pose had
                            // it.
                            m_contact_velocities[v] =
                                obstacle.state.surface_displacement(positions[v]) * (1.0 / h);
                            m_contact_settled[v] = settled;
                        }
                    }
                }
                for (const MovingMeshObstacle& mesh : mesh_obstacles) {
                    const MeshContact contact =
                        resolve_mesh_contact(mesh, positions[v], start, thickness, h, max_settle,
                                             max_push, m_obstacle_lag);
                    tally.swept += contact.swept ? 1 : 0;
                    lag = std::max(lag, contact.lag);
                    if (contact.depth > m_contact_depths[v]) {
                        m_contact_depths[v] = contact.depth;
                        m_contact_normals[v] = contact.normal;
                        m_contact_velocities[v] = contact.surface_velocity;
                        m_contact_settled[v] = contact.settled;
                    }
                }
                tally.lagging += lag > 0.0 ? 1 : 0;
                tally.max_lag = std::max(tally.max_lag, lag);
                tally.contacts += m_contact_depths[v] > 0.0 ? 1 : 0;
            }
            return tally;
        },
        [](const ObstacleTally& a, const ObstacleTally& b) {
            return ObstacleTally{.contacts = a.contacts + b.contacts,
                                 .swept = a.swept + b.swept,
                                 .lagging = a.lagging + b.lagging,
                                 .max_lag = std::max(a.max_lag, b.max_lag)};
        },
        VERTEX_GRAIN);
    // Then the cloth's edges against the mesh obstacles' edges.
    for (const MovingMeshObstacle& mesh : mesh_obstacles) {
        total.edges += resolve_mesh_edge_contacts(
            mesh, positions, m_previous_positions, m_before_contacts, inverse_masses,
            model.topology().edges, thickness, max_push, m_feature_contacts);
    }
    // Then the cloth's triangles against the mesh obstacles' vertices.
    for (const MovingMeshObstacle& mesh : mesh_obstacles) {
        total.faces += resolve_mesh_face_contacts(
            mesh, positions, m_previous_positions, m_before_contacts, inverse_masses,
            model.triangles(), thickness, max_push, m_feature_contacts);
    }
    return total;
}

std::int64_t XPBDStepper::put_back_into_obstacle_motion(ClothModel& model) {
    // As far as the passes may push (resolve_obstacles' max_push, beyond the thickness).
    const double thickness = model.material().thickness;
    const double max_carry =
        thickness + detail::catch_up_step(m_self_collision != nullptr, thickness);
    const std::int64_t moved =
        m_put_back.run(model, m_previous_positions, ObstaclePutBack::Fallback::carried, max_carry);
    for (const std::int32_t v : m_put_back.moved()) {
        m_contact_depths[static_cast<std::size_t>(v)] = 0.0;  // it moves with the surface
    }
    return moved;
}

std::int64_t XPBDStepper::release_stuck_triangles(ClothModel& model) {
    if (m_put_back.stuck() == 0 || !m_ogc->options().audit) {
        return 0;
    }
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<const double> inverse_masses = model.inverse_masses();
    std::int64_t moved = 0;
    for (const std::int32_t t : m_put_back.stuck_triangles()) {
        for (const std::int32_t corner : model.triangles()[static_cast<std::size_t>(t)]) {
            const auto v = static_cast<std::size_t>(corner);
            if (inverse_masses[v] > 0.0 && !(positions[v] == m_before_self[v])) {
                positions[v] = m_before_self[v];
                m_contact_depths[v] = 0.0;
                ++moved;
            }
        }
    }
    return moved;
}

std::int64_t XPBDStepper::enforce_window(ClothModel& model, double t_end) {
    const std::span<Vec3d> positions = model.mutable_positions();
    const std::span<Vec3d> velocities = model.mutable_velocities();
    if (model.mesh_obstacles().empty()) {
        m_self_collision->enforce(m_window_start, positions, velocities, m_window_start_time,
                                  t_end);
        return 0;
    }
    m_before_fail_safe.assign(positions.begin(), positions.end());
    m_self_collision->enforce(m_window_start, positions, velocities, m_window_start_time, t_end);
    m_put_back.seed(positions, m_before_fail_safe);
    const std::int64_t carried =
        m_put_back.run(model, m_window_start, ObstaclePutBack::Fallback::carried,
                       std::numeric_limits<double>::infinity(), &m_window_obstacles);
    if (carried == 0) {
        return 0;
    }
    // A carried vertex moves with the surface: the window's mean velocity, no obstacle contact.
    const double window = t_end - m_window_start_time;
    for (const std::int32_t v : m_put_back.moved()) {
        const auto k = static_cast<std::size_t>(v);
        velocities[k] = (positions[k] - m_window_start[k]) * (1.0 / window);
        m_contact_depths[k] = 0.0;
    }
    m_self_collision->enforce(m_window_start, positions, velocities, m_window_start_time, t_end);
    return carried;
}

void XPBDStepper::save_state(ByteWriter& out) const {
    out.put(static_cast<std::uint64_t>(m_num_vertices));
    out.put(static_cast<std::uint64_t>(m_num_triangles));
    out.put_vector(m_stretch_lambda);
    out.put_vector(m_previous_positions);
    out.put_vector(m_contact_depths);
    out.put_vector(m_contact_settled);
    out.put_vector(m_contact_normals);
    out.put_vector(m_contact_velocities);
    out.put(m_num_position_resets);
    out.put_vector(m_window_start);
    out.put(m_window_start_time);
    out.put(m_gather_start_time);
    out.put(m_gather_end_time);
    out.put(m_obstacle_lag);
    out.put(m_self_collision != nullptr);
    if (m_self_collision) {
        m_self_collision->save_state(out);
    }
    out.put(m_ogc != nullptr);
    if (m_ogc) {
        m_ogc->save_state(out);
    }
}

void XPBDStepper::load_state(const ClothModel& model, ByteReader& in) {
    const auto num_vertices = in.get<std::uint64_t>("stepper.num_vertices");
    const auto num_triangles = in.get<std::uint64_t>("stepper.num_triangles");
    if (num_vertices != m_num_vertices || num_triangles != m_num_triangles) {
        throw InvalidInput(fmt::format(
            "{}: cloth stepper: a state of {} vertices and {} triangles, the cloth has {} and {}",
            in.source(), num_vertices, num_triangles, m_num_vertices, m_num_triangles));
    }
    const auto n = static_cast<std::int64_t>(m_num_vertices);
    in.get_vector("stepper.stretch_lambda", m_stretch_lambda,
                  static_cast<std::int64_t>(m_stretch_lambda.size()));
    in.get_vector("stepper.previous_positions", m_previous_positions, n);
    in.get_vector("stepper.contact_depths", m_contact_depths, n);
    in.get_vector("stepper.contact_settled", m_contact_settled, n);
    in.get_vector("stepper.contact_normals", m_contact_normals, n);
    in.get_vector("stepper.contact_velocities", m_contact_velocities, n);
    m_num_position_resets = in.get<std::int64_t>("stepper.num_position_resets");
    in.get_vector("stepper.window_start", m_window_start);
    m_window_start_time = in.get<double>("stepper.window_start_time");
    m_gather_start_time = in.get<double>("stepper.gather_start_time");
    m_gather_end_time = in.get<double>("stepper.gather_end_time");
    m_obstacle_lag = in.get<double>("stepper.obstacle_lag");
    const bool has_self_collision = in.get_bool("stepper.has_self_collision");
    if (has_self_collision != (m_self_collision != nullptr)) {
        throw InvalidInput(fmt::format("{}: cloth stepper: self-collision {} in the state, {} here",
                                       in.source(), has_self_collision ? "on" : "off",
                                       m_self_collision ? "on" : "off"));
    }
    if (m_self_collision) {
        // A fresh one, so that nothing of this stepper's own start survives.
        m_self_collision = std::make_unique<SelfCollision>(model.triangles(), model.num_vertices(),
                                                           model.material().thickness);
        m_self_collision->load_state(in);
    }
    const bool has_ogc = in.get_bool("stepper.has_ogc");
    if (has_ogc != (m_ogc != nullptr)) {
        throw InvalidInput(fmt::format("{}: cloth stepper: ogc contact {} in the state, {} here",
                                       in.source(), has_ogc ? "on" : "off", m_ogc ? "on" : "off"));
    }
    if (m_ogc) {
        m_ogc->load_state(in);
    }
}

}  // namespace pliant::cloth
