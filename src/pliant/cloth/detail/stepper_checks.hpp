// What every cloth stepper (XPBDStepper, VBDStepper) checks and sets up the same way: the
// arguments of a step, and self-collision for a model's thickness and rest lengths.
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <span>

#include "pliant/cloth/cloth_model.hpp"
#include "pliant/cloth/self_collision.hpp"

namespace pliant::cloth::detail {

// Self-collision needs a thickness of at most this many median edge lengths: with more, every
// triangle is within reach of hundreds of others (in a flat sheet about 2π (thickness / edge)²),
// and a broad phase costs gigabytes (a 5 cm sheet of 134 × 134 quads under 5 mm: 24 GB).
inline constexpr double MAX_THICKNESS_IN_EDGES = 4.0;

// With self-collision, a moving pin moves at most this fraction of the thickness per substep
// toward its keyframed target (ClothModel::move_pins), and an obstacle undoes at most this
// fraction of the thickness of a penetration the substep began with: pins whose keyframes jump
// chase their target, and cloth deep inside an obstacle comes out, over several substeps instead
// of sweeping through the cloth in one, which the self-collision fail-safe could only hold back
// window after window (scenes/stress/jump_ribbon.json: with a whole thickness, the end the
// ribbon starts with inside a sphere stayed caught and the budget was exceeded in every window
// from frame 8; with half, never). The proximity constraints act once per substep, so a move
// well under the thickness keeps them ahead of it (as the strain limits' moves in XPBDStepper).
inline constexpr double CATCH_UP_IN_THICKNESS = 0.5;

// That bound for a stepper (m per substep): CATCH_UP_IN_THICKNESS · thickness with self-collision
// and a thickness > 0, else none (infinity).
inline double catch_up_step(bool self_collision, double thickness) {
    return self_collision && thickness > 0.0 ? CATCH_UP_IN_THICKNESS * thickness
                                             : std::numeric_limits<double>::infinity();
}

// InvalidInput unless dt > 0 (finite), substeps ≥ 1 and the model has the vertex and triangle
// counts the stepper was built for.
void check_step(const ClothModel& model, double dt, int substeps, std::size_t num_vertices,
                std::size_t num_triangles);

// Self-collision for the model's triangles at its material's thickness. InvalidInput when the
// thickness is more than MAX_THICKNESS_IN_EDGES times the median of rest_lengths (m).
std::unique_ptr<SelfCollision> make_self_collision(const ClothModel& model,
                                                   std::span<const double> rest_lengths);

}  // namespace pliant::cloth::detail
