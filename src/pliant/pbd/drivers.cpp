#include <cmath>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/pbd/detail/driver_eval.hpp"

namespace pliant::pbd::detail {
namespace {

void require(bool ok, const char* driver, const char* field, double value, const char* rule) {
    if (!ok) {
        throw InvalidInput(std::string("pbd::") + driver + ": " + field + " (" +
                           std::to_string(value) + ") must be " + rule);
    }
}

void require_finite(const char* driver, const char* field, double value) {
    require(std::isfinite(value), driver, field, value, "finite");
}

}  // namespace

void validate_driver(const Driver& driver) {
    if (const auto* wave = std::get_if<WaveDriver>(&driver)) {
        const char* name = "WaveDriver";
        require_finite(name, "amplitude", wave->amplitude);
        require_finite(name, "wavelength", wave->wavelength);
        require_finite(name, "speed", wave->speed);
        require_finite(name, "ramp_time", wave->ramp_time);
        require(wave->amplitude >= 0.0, name, "amplitude", wave->amplitude, ">= 0");
        require(wave->wavelength > 0.0, name, "wavelength", wave->wavelength, "> 0");
        require(wave->ramp_time >= 0.0, name, "ramp_time", wave->ramp_time, ">= 0");
        if (wave->direction == wave->displacement) {
            throw InvalidInput(
                "pbd::WaveDriver: displacement must differ from direction (a transverse wave)");
        }
    } else if (const auto* twist = std::get_if<TwistDriver>(&driver)) {
        const char* name = "TwistDriver";
        require_finite(name, "angle", twist->angle);
        require_finite(name, "ramp_time", twist->ramp_time);
        require_finite(name, "grip", twist->grip);
        require(twist->ramp_time >= 0.0, name, "ramp_time", twist->ramp_time, ">= 0");
        require(twist->grip >= 0.0 && twist->grip < 0.5, name, "grip", twist->grip,
                "in [0, 0.5) box units");
    } else if (const auto* bubble = std::get_if<BubbleDriver>(&driver)) {
        const char* name = "BubbleDriver";
        require(is_finite(bubble->centre), name, "centre.x", bubble->centre.x,
                "finite (all three coordinates)");
        require_finite(name, "radius", bubble->radius);
        require_finite(name, "inflation", bubble->inflation);
        require_finite(name, "ramp_time", bubble->ramp_time);
        require(bubble->radius > 0.0, name, "radius", bubble->radius, "> 0");
        require(bubble->inflation > 0.0, name, "inflation", bubble->inflation, "> 0");
        require(bubble->ramp_time >= 0.0, name, "ramp_time", bubble->ramp_time, ">= 0");
    } else if (const auto* rotate_driver = std::get_if<RotateDriver>(&driver)) {
        const char* name = "RotateDriver";
        require_finite(name, "angle", rotate_driver->angle);
        if (rotate_driver->centre) {
            require_finite(name, "centre.x", rotate_driver->centre->x);
            require_finite(name, "centre.y", rotate_driver->centre->y);
            require_finite(name, "centre.z", rotate_driver->centre->z);
        }
        require_finite(name, "ramp_time", rotate_driver->ramp_time);
        require(rotate_driver->ramp_time >= 0.0, name, "ramp_time", rotate_driver->ramp_time,
                ">= 0");
    }
    const auto axis_ok = [](Axis a) {
        return a == Axis::x || a == Axis::y || a == Axis::z;
    };
    std::visit(
        [&](const auto& d) {
            using D = std::decay_t<decltype(d)>;
            if constexpr (std::is_same_v<D, WaveDriver>) {
                require(axis_ok(d.direction) && axis_ok(d.displacement), "WaveDriver", "axis",
                        static_cast<double>(d.direction), "x, y or z");
            } else if constexpr (!std::is_same_v<D, BubbleDriver>) {
                require(axis_ok(d.axis), "driver", "axis", static_cast<double>(d.axis),
                        "x, y or z");
            }
        },
        driver);
}

double ramp(double t, double ramp_time) {
    if (!(ramp_time > 0.0)) {
        return 1.0;
    }
    return std::min(1.0, t / ramp_time);
}

std::array<double, 9> rotation(Axis axis, double degrees) {
    const double a = degrees * std::numbers::pi / 180.0;
    const double c = std::cos(a);
    const double s = std::sin(a);
    switch (axis) {
        case Axis::x:
            return {1, 0, 0, 0, c, -s, 0, s, c};
        case Axis::y:
            return {c, 0, s, 0, 1, 0, -s, 0, c};
        case Axis::z:
            break;
    }
    return {c, -s, 0, s, c, 0, 0, 0, 1};
}

Vec3d rotate(const std::array<double, 9>& r, const Vec3d& p) {
    return {r[0] * p.x + r[1] * p.y + r[2] * p.z, r[3] * p.x + r[4] * p.y + r[5] * p.z,
            r[6] * p.x + r[7] * p.y + r[8] * p.z};
}

Vec3d wave_displacement(const WaveDriver& wave, const BodyBox& box, const Vec3d& rest, double t) {
    const int d = static_cast<int>(wave.direction);
    const double q = (rest[d] - box.lo[d]) / box.size;  // box units
    const double u = ramp(t, wave.ramp_time) * wave.amplitude *
                     std::sin(2.0 * std::numbers::pi * (q - wave.speed * t) / wave.wavelength);
    Vec3d out{};
    out[static_cast<int>(wave.displacement)] = u * box.size;
    return out;
}

namespace {

// (r / R)² of a rest point for the bubble: its squared distance from the centre over the radius's.
double bubble_q2(const BubbleDriver& bubble, const BodyBox& box, const Vec3d& rest) {
    const Vec3d centre{box.lo.x + bubble.centre.x * (box.hi.x - box.lo.x),
                       box.lo.y + bubble.centre.y * (box.hi.y - box.lo.y),
                       box.lo.z + bubble.centre.z * (box.hi.z - box.lo.z)};
    const double radius = bubble.radius * box.size;
    return squared_norm(rest - centre) / (radius * radius);
}

}  // namespace

bool bubble_reaches(const BubbleDriver& bubble, const BodyBox& box, const Vec3d& rest) {
    return !(bubble_q2(bubble, box, rest) >= 1.0);
}

double bubble_factor(const BubbleDriver& bubble, const BodyBox& box, const Vec3d& rest, double t) {
    const double q2 = bubble_q2(bubble, box, rest);
    if (q2 >= 1.0) {
        return 1.0;
    }
    const double profile = (1.0 - q2) * (1.0 - q2);
    return 1.0 + ramp(t, bubble.ramp_time) * (bubble.inflation - 1.0) * profile;
}

}  // namespace pliant::pbd::detail
