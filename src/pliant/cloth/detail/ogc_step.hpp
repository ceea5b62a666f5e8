// A step with Offset Geometric Contact (ogc_contact.hpp) as every cloth stepper (XPBDStepper,
// VBDStepper) runs it: at the step's start the counters and the audit's first window, the CCD
// audit of a window's motion (on the detection's pairs when OGC's bounds held over the window,
// whose cost then follows the contacts; else the full fail-safe), and at the step's end its
// statistics.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/detail/ogc_audit_window.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/cloth/xpbd_stepper.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

// The contact's counters at a step's start (ogc_step_stats() reports the step's share).
struct OgcStepStart {
    std::int64_t detections = 0;
    std::int64_t wide_detections = 0;
    double detect_ms = 0.0;
};

// The contact of a stepper's cloth: radius options.radius, or the material's thickness when 0;
// stiffness options.stiffness, or default_stiffness when 0 (N/m).
std::unique_ptr<OgcContact> make_ogc_contact(const ClothModel& model, const OgcOptions& options,
                                             double default_stiffness);

// Truncates every free vertex's move from `from` to x to its bound (OgcContact::truncate, in
// parallel: each vertex alone); returns the vertices held back, and adds those of them the ball
// held back (left on its sphere, OgcContact::at_ball; a vertex held back by a contact plane alone
// is resting on a contact, and stays) to *ball_held when given.
std::int64_t truncate_moves(const OgcContact& ogc, std::span<const Vec3d> from, std::span<Vec3d> x,
                            std::span<const double> inverse_masses,
                            std::int64_t* ball_held = nullptr);

// Whether some pinned vertex (inverse mass 0) lies outside its feasible set at x (#V).
bool pins_left_sets(const OgcContact& ogc, std::span<const Vec3d> x,
                    std::span<const double> inverse_masses);

// Where a detection for pins that left their sets takes place: every pinned vertex at x (where
// the pins moved it), every free vertex at start (where the substep started), into out (#V).
// Detecting there puts the pins at the centres of their sets, and the free vertices' sets
// around where the substep started.
void pin_detection_positions(std::span<const Vec3d> start, std::span<const Vec3d> x,
                             std::span<const double> inverse_masses, std::vector<Vec3d>& out);

// Detections that XPBDStepper::catch_up makes at most per truncation.
inline constexpr int MAX_CATCH_UP_DETECTIONS = 4;

// Starts a step: the audit's first window starts at `positions` (into audit, with the contact's
// detection count and shift; the audit's counters restart), num_free becomes the number of free
// vertices (inverse mass > 0, what the re-detection share is of).
OgcStepStart begin_ogc_step(const OgcContact& ogc, std::span<const Vec3d> positions,
                            std::span<const double> inverse_masses, OgcAuditWindow& audit,
                            std::int64_t& num_free);

// Whether the detection's pairs hold every pair that can touch over the window's straight motion
// from audit.start to x, so that the CCD need test only those (audit_ogc_window):
//   Let D be the detection's positions, T_0 the frame shift at the window's start (audit.shift
//   when no detection came since, else 0: any translation serves, the test below is explicit)
//   and T_1 the shift now. Every pair the detection did not keep was at least r_q apart at D
//   (OgcContact::detect keeps every non-incident pair closer than the query radius r_q; the CCD
//   tests only non-incident pairs too). On the straight motion p_v(τ) = (1 − τ) a_v + τ x_v,
//   with T(τ) = (1 − τ) T_0 + τ T_1, |p_v(τ) − D_v − T(τ)| is convex in τ, so at most
//   M = max(m_0, m_1), where m_0 = max_v |a_v − D_v − T_0| and m_1 = max_v |x_v − D_v − T_1|
//   (every vertex, pinned ones included: a pin that jumped fails the test). Distances do not
//   change under a common translation, and a vertex-face or edge-edge distance moves by at most M
//   when each vertex moves by at most M (every point of a feature is a convex combination of its
//   vertices), so a pair at least r_q apart at D stays at least r_q − 2M apart over the window:
//   it cannot touch while 2M < r_q (less a rounding margin of 1e-9 (1 + the largest
//   coordinate)). OGC's bounds keep every free vertex within b = bound_share · r_q < r_q / 2 of
//   D_v + S (Chen et al. 2025, §4: the same argument with the conservative bound), so the test
//   holds whenever the stepper's truncation held; it fails (the full fail-safe then runs) after a
//   pin jumps, when the solver moved vertices past their bounds, without a detection, or when the
//   pairs exceed CCDFailSafe::pair_budget.
bool ogc_pairs_cover_window(const OgcContact& ogc, const OgcAuditWindow& audit,
                            std::span<const Vec3d> x);

// The CCD fail-safe over the motion from audit.start to x (velocities of the vertices it puts
// back set as SelfCollision::enforce does), then the next window starts at x. On the detection's
// pairs alone (SelfCollision::enforce_pairs, counted in audit.pair_audits) when
// ogc_pairs_cover_window and use_pairs, else the full fail-safe with its broad phase
// (SelfCollision::enforce, audit.full_audits); nothing when no vertex moved. A vertex the pair
// audit puts back stands at its start, which need not follow the frame shift: when it put back
// any, the test is repeated on the changed motion and, should it fail, the full fail-safe runs on
// that motion too (also counted in full_audits). Returns whether it put any vertex back.
bool audit_ogc_window(SelfCollision& self_collision, const OgcContact& ogc, OgcAuditWindow& audit,
                      std::span<Vec3d> x, std::span<Vec3d> velocities, bool use_pairs = true);

// The step's OGC statistics into stats (has_ogc, detections and their time since `start`, the
// `truncated` moves, the pairs of the last detection, the audit's windows by kind).
void ogc_step_stats(const OgcContact& ogc, const OgcStepStart& start, std::int64_t truncated,
                    const OgcAuditWindow& audit, ClothStepStats& stats);

}  // namespace pliant::cloth::detail
