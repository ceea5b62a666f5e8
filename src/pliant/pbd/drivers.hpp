// Deformation drivers of the soft body (SoftBody::add_driver), Park & Kye 2022's wave, twist and
// bubble, plus rotate (a rigid motion, for testing) and drag (SoftBody::set_drag).
//
// Two kinds:
//   - kinematic drivers (twist, rotate, drag) move some vertices along a prescribed path: during
//     each substep a driven vertex has inverse mass 0 and sits at its target for the substep's end
//     time, and its velocity is that path's; the constraints move the other vertices;
//   - rest-state drivers (wave, bubble) change the shape the body wants to have — the rest
//     lengths of its edges and the rest volumes of its tets — and the constraints pull it there.
//     They are evaluated once per step, at the step's end time.
//
// Box units: lengths are fractions of L, the largest side of the rest mesh's axis-aligned
// bounding box, and box coordinates are (p − lo) / (hi − lo) per axis (0 at the box's min corner,
// 1 at its max corner), so that one driver fits volumes of any size and spacing. The centre of
// the box is (lo + hi) / 2. Angles in degrees, right-handed about +axis; times in seconds since
// the solver's start. Every driver ramps in linearly over `ramp_time` (0: at full strength from
// the start): strength s(t) = min(1, t / ramp_time).
#pragma once

#include <cstdint>
#include <optional>
#include <variant>

#include "pliant/core/vec3.hpp"

namespace pliant::pbd {

enum class Axis : std::int8_t { x = 0, y = 1, z = 2 };

// Travelling sinusoidal wave (rest-state driver). The rest positions are displaced along
// `displacement` by
//   u(p, t) = s(t) · amplitude · sin(2π (q − speed · t) / wavelength),
// q = the rest position's coordinate along `direction`, in box units from the box's min face;
// rest edge lengths and rest tet volumes are those of the displaced rest positions. A transverse
// wave (displacement ≠ direction, the default) is a shear: it keeps volumes to first order.
// InvalidInput: displacement == direction, amplitude < 0, wavelength ≤ 0, any value not finite.
struct WaveDriver {
    Axis direction = Axis::x;     // propagation axis
    Axis displacement = Axis::z;  // displacement axis (≠ direction)
    double amplitude = 0.03;      // box units
    double wavelength = 0.5;      // box units
    double speed = 0.5;           // box units per second along +direction
    double ramp_time = 0.5;       // s
};

// Twist (kinematic driver): the vertices of the max face along `axis` turn by s(t) · angle about
// the line through the box's centre parallel to `axis`, right-handed about +axis; the vertices of
// the min face stay at rest. A face's vertices are those within `grip` box units of it (at least
// the extreme lattice plane: 1e-6 L of tolerance). The rest of the body follows through the
// constraints. InvalidInput: grip < 0 or ≥ 0.5, values not finite.
struct TwistDriver {
    Axis axis = Axis::z;
    double angle = 90.0;     // degrees, of the max face relative to the min face
    double ramp_time = 1.0;  // s
    double grip = 0.0;       // box units: thickness of each held slab
};

// Bubble (rest-state driver): a spherical region inflates. A tet whose rest centroid lies at
// distance r from `centre` gets rest volume V0 · f, an edge whose rest midpoint does rest length
// L0 · f^(1/3), with the smooth profile
//   f(r) = 1 + s(t) · (inflation − 1) · (1 − (r / R)²)²  for r < R,  1 outside,
// R = radius. inflation > 1 inflates, < 1 deflates. InvalidInput: inflation ≤ 0, radius ≤ 0,
// values not finite.
struct BubbleDriver {
    Vec3d centre{0.5, 0.5, 0.5};  // box coordinates
    double radius = 0.25;         // box units
    double inflation = 2.0;       // rest-volume factor at the centre
    double ramp_time = 1.0;       // s
};

// Rigid rotation (kinematic driver, for testing): every vertex is driven to
//   c + R(axis, s(t) · angle) · (rest − c),  c = `centre` or else the box's centre,
// so the body turns rigidly and exactly (double-precision targets rounded to float).
// InvalidInput: values not finite, ramp_time < 0.
struct RotateDriver {
    Axis axis = Axis::z;
    double angle = 90.0;     // degrees, right-handed about +axis
    double ramp_time = 0.0;  // s
    // World units: the point the axis goes through (pliant deform: the volume's centre, which a
    // grid over only the visible part need not share); none: the rest box's centre.
    std::optional<Vec3d> centre = std::nullopt;
};

using Driver = std::variant<WaveDriver, TwistDriver, BubbleDriver, RotateDriver>;

// Drag (kinematic driver, SoftBody::set_drag): the grabbed vertex, and the vertices within
// `radius` (world units) of its position when grabbed, translate together so that the grabbed
// vertex reaches `target` (world units) at the end of the next step, linearly over its substeps;
// they then stay at the target until it moves or the drag is released.
struct DragDriver {
    std::int32_t vertex = -1;
    Vec3f target{};    // world units
    float radius = 0;  // world units
};

}  // namespace pliant::pbd
