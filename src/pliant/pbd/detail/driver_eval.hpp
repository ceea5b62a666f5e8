// Evaluation of the drivers of drivers.hpp: validation, ramps, rotations, wave displacement and
// bubble profile, in double precision. Internal to SoftBody.
#pragma once

#include <array>

#include "pliant/core/vec3.hpp"
#include "pliant/pbd/drivers.hpp"

namespace pliant::pbd::detail {

// The rest mesh's axis-aligned box: lo, hi, centre, L = the largest side (box units).
struct BodyBox {
    Vec3d lo{};
    Vec3d hi{};
    Vec3d centre{};
    double size = 1.0;  // L (> 0; 1 for a degenerate box)
};

// InvalidInput naming the field when a driver's parameters are out of range (drivers.hpp).
void validate_driver(const Driver& driver);

// s(t) = min(1, t / ramp_time), 1 when ramp_time ≤ 0.
double ramp(double t, double ramp_time);

// Row-major rotation by `degrees` about +axis (right-handed).
std::array<double, 9> rotation(Axis axis, double degrees);
Vec3d rotate(const std::array<double, 9>& r, const Vec3d& p);

// The wave's displacement (world units) of a rest point at time t.
Vec3d wave_displacement(const WaveDriver& wave, const BodyBox& box, const Vec3d& rest, double t);

// The bubble's rest-volume factor f at a rest point at time t (1 outside).
double bubble_factor(const BubbleDriver& bubble, const BodyBox& box, const Vec3d& rest, double t);
// Whether the bubble reaches a rest point: false exactly where bubble_factor is 1 at every t
// for the bubble's distance alone (r ≥ R).
bool bubble_reaches(const BubbleDriver& bubble, const BodyBox& box, const Vec3d& rest);

}  // namespace pliant::pbd::detail
