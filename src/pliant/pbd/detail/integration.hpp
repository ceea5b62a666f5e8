// The soft body's time integration around the constraint projections (soft_body.hpp, steps 1 and
// 4; XPBD, Macklin, Müller, Chentanez 2016, Algorithm 1: the prediction and the velocity update),
// per substep h: predict x += h (v + h g) for free vertices, then, after the projections,
// v = (x − x_previous) / h damped by the factor keep = max(0, 1 − damping · h).
//
// Per-vertex kernels (PLIANT_HOST_DEVICE) and the passes over all #V vertices that run them,
// parallel in fixed chunks, writing by index: bitwise identical for any number of threads.
// x: #V positions (world units) packed with the substep's inverse mass (Float4 {x, y, z, w}).
#pragma once

#include <cstdint>
#include <span>

#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/pbd/detail/projection.hpp"

namespace pliant::pbd::detail {

// The integration constants of one substep, in float as the kernels use them.
struct SubstepMotion {
    float h = 0.0f;      // s
    float inv_h = 0.0f;  // 1/s: 1.0f / h
    float keep = 1.0f;   // max(0, 1 − damping · h): the fraction of the velocity kept
    Vec3f gravity_h{};   // world units / s: gravity · h
};

// The prediction of one vertex with inverse mass w and velocity vel (world units / s): previous
// = p's position; a free vertex (w > 0) gets vel += g h and p += h vel, p.w = w; any other
// (pinned) keeps its position bitwise and gets p.w = 0.
PLIANT_HOST_DEVICE inline void predict_vertex(Float4& p, Vec3f& previous, Vec3f& vel, float w,
                                              const SubstepMotion& m) {
    previous = {p.x, p.y, p.z};
    if (w > 0.0f) {
        vel += m.gravity_h;
        p = {p.x + m.h * vel.x, p.y + m.h * vel.y, p.z + m.h * vel.z, w};
    } else {
        p.w = 0.0f;
    }
}

// The velocity (world units / s) of a vertex from its motion over the substep, damped:
// (p − previous) · inv_h · keep.
PLIANT_HOST_DEVICE inline Vec3f substep_velocity(const Float4& p, const Vec3f& previous,
                                                 const SubstepMotion& m) {
    return Vec3f{(p.x - previous.x) * m.inv_h, (p.y - previous.y) * m.inv_h,
                 (p.z - previous.z) * m.inv_h} *
           m.keep;
}

// The first substep's prediction of every vertex, from velocities (#V, read only: the velocity
// update of the last substep overwrites them). Writes x and previous (#V); inv_masses: #V.
void predict(Float4* x, std::span<Vec3f> previous, std::span<const Vec3f> velocities,
             std::span<const float> inv_masses, const SubstepMotion& m);

// Between two substeps: every vertex's velocity from its motion (0 for pinned vertices, 1 in
// pinned: #V), then its prediction for the next substep with that velocity, which is not stored
// (the body's velocities are those of the last substep). Reads and writes x and previous.
void update_velocities_and_predict(Float4* x, std::span<Vec3f> previous,
                                   std::span<const float> inv_masses,
                                   std::span<const std::uint8_t> pinned, const SubstepMotion& m);

// After the last substep: velocities (#V) from the motion (pinned vertices' left as they are) and
// positions (#V, world units) = x's positions.
void update_velocities(const Float4* x, std::span<const Vec3f> previous,
                       std::span<const std::uint8_t> pinned, const SubstepMotion& m,
                       std::span<Vec3f> velocities, std::span<Vec3f> positions);

}  // namespace pliant::pbd::detail
