// Air: wind and aerodynamic drag on the cloth's triangles.
//
// Every substep each triangle of area A, unit normal n and mean velocity v feels the pressure drag
// of the air moving at w (wind) relative to it, u = v − w:
//   f = −½ ρ C_d A (u·n) |u·n| n,
// the quadratic drag of a flat plate on the normal component of the relative velocity (tangential
// air friction is neglected), split equally among the triangle's three vertices. Applied
// explicitly per substep h, its impulse is capped at the triangle's normal momentum
// ρ_A A |u·n| (it can stop the relative motion, not reverse it), which keeps it stable at any
// speed. With no wind the
// same force is air resistance. Wind may gust: its speed is scaled by
//   1 + gust_amplitude · sin(2π (t / gust_period − (x·ŵ) / gust_wavelength)),
// a gust travelling downwind with the wind's direction ŵ, so that a flag flutters instead of
// settling into a steady billow.
//
// ClothModel::apply_air evaluates the force per triangle with detail/air_kernels.hpp (four
// triangles at a time, the bits of wind_at and the formula above).
//
// Units: kg/m³, m/s, s, m. density 0 (the default) turns air off.
#pragma once

#include <cmath>
#include <numbers>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

struct Air {
    double density = 0.0;           // kg/m³ (air at sea level: 1.2); 0 = no air
    double drag_coefficient = 1.0;  // C_d of a flat plate, unitless
    Vec3d wind{0.0, 0.0, 0.0};      // m/s
    double gust_amplitude = 0.0;    // fraction of the wind's speed, >= 0
    double gust_period = 1.0;       // s, > 0
    double gust_wavelength = 5.0;   // m, > 0

    bool is_active() const { return density > 0.0 && drag_coefficient > 0.0; }

    // The wind's velocity at x and time t (m/s).
    Vec3d wind_at(const Vec3d& x, double t) const {
        const double speed = norm(wind);
        if (!(gust_amplitude > 0.0) || !(speed > 0.0)) {
            return wind;
        }
        const double along = dot(x, wind) / speed;
        const double phase = 2.0 * std::numbers::pi * (t / gust_period - along / gust_wavelength);
        return wind * (1.0 + gust_amplitude * std::sin(phase));
    }
};

}  // namespace pliant::cloth
