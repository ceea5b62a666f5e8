// A step with Offset Geometric Contact (ogc_contact.hpp) as every cloth stepper (XPBDStepper,
// VBDStepper) runs it: at the step's start the counters and the audit's first window, the CCD
// audit of a window's motion, and at the step's end its statistics.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/cloth/xpbd_stepper.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

// The contact's counters at a step's start (ogc_step_stats() reports the step's share).
struct OgcStepStart {
    std::int64_t detections = 0;
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

// Starts a step: the audit's first window starts at `positions` (into audit_start), num_free
// becomes the number of free vertices (inverse mass > 0, what the re-detection share is of).
OgcStepStart begin_ogc_step(const OgcContact& ogc, std::span<const Vec3d> positions,
                            std::span<const double> inverse_masses, std::vector<Vec3d>& audit_start,
                            std::int64_t& num_free);

// The CCD fail-safe over the motion from audit_start to x (velocities of the vertices it puts
// back set as SelfCollision::enforce does), then the next window starts at x. Returns whether it
// put any vertex back.
bool audit_ogc_window(SelfCollision& self_collision, std::vector<Vec3d>& audit_start,
                      std::span<Vec3d> x, std::span<Vec3d> velocities);

// The step's OGC statistics into stats (has_ogc, detections and their time since `start`, the
// `truncated` moves, the pairs of the last detection).
void ogc_step_stats(const OgcContact& ogc, const OgcStepStart& start, std::int64_t truncated,
                    ClothStepStats& stats);

}  // namespace pliant::cloth::detail
