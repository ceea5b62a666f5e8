// The source-scale soft body under a driver, shared by bench_pbd (BM_SourceScaleStep) and
// bench_deform_frame: pbd::SoftBody on source_scale_phantom.hpp's tet grid at stiffness 0.8 with
// driver d (0 twist 90° over 1 s, 1 wave of amplitude 0.05, 2 bubble inflating 2× over 0.5 s,
// 3 mouse drag); the drag pulls the vertex nearest to the box's corner (1, 1, 1) (with the
// vertices within 0.25) 0.3 along −x over the first 12 frames (for another workload's box: its
// largest corner, 1/8 and 0.15 of its width along x). Frames are 1/24 s.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "pliant/core/aabb.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "source_scale_phantom.hpp"

namespace pliant::bench {

struct DrivenBody {
    pbd::SoftBody body;
    int driver = 0;            // d above
    std::int32_t grabbed = 0;  // drag: the vertex pulled
    Vec3f start{};             // drag: its rest position
    float width = 2.0f;        // drag: the box's width along x

    // Frame `frame` (from 0): the drag's target, then SoftBody::step of 1/24 s.
    void step(int frame) {
        if (driver == 3) {
            const float f = static_cast<float>(std::min(frame + 1, 12)) / 12.0f;
            body.set_drag(grabbed, start - Vec3f{0.15f * width * f, 0.0f, 0.0f}, width / 8.0f);
        }
        body.step(1.0 / 24.0);
    }
};

// The body of workload w at rest with driver d and solver options o (their stiffness set to
// 0.8).
inline DrivenBody source_scale_driven_body(int d, pbd::SoftBodyOptions o,
                                           const SourceScaleWorkload& w = source_scale_workload()) {
    o.stiffness = 0.8;
    const AABBd box = w.source.bounds();
    DrivenBody out{pbd::SoftBody(w.grid, o), d};
    out.width = static_cast<float>(box.hi.x - box.lo.x);
    switch (d) {
        case 0:
            out.body.add_driver(pbd::TwistDriver{.angle = 90.0, .ramp_time = 1.0});
            break;
        case 1:
            out.body.add_driver(pbd::WaveDriver{.amplitude = 0.05});
            break;
        case 2:
            out.body.add_driver(pbd::BubbleDriver{.inflation = 2.0, .ramp_time = 0.5});
            break;
        default:
            break;
    }
    if (d == 3) {
        float best = 1e30f;
        const auto rest = out.body.rest_positions();
        for (std::size_t v = 0; v < rest.size(); ++v) {
            const float dist = squared_norm(rest[v] - vec3_cast<float>(box.hi));
            if (dist < best) {
                best = dist;
                out.grabbed = static_cast<std::int32_t>(v);
            }
        }
        out.start = rest[static_cast<std::size_t>(out.grabbed)];
    }
    return out;
}

}  // namespace pliant::bench
