// Analytic obstacles for the cloth solver (plane, sphere, axis-aligned box), the contact
// projection that keeps cloth vertices `thickness` away from them, and Coulomb friction.
//
// Units: metres, seconds. Obstacles are static here; the solver calls push_out once per vertex
// and substep after the constraint projection, then apply_friction on the new velocity.
#pragma once

#include <variant>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

// The half-space on the normal's side of the plane through `point` is free space.
struct PlaneObstacle {
    Vec3d point{0.0, 0.0, 0.0};
    Vec3d normal{0.0, 0.0, 1.0};  // need not be unit; must be nonzero
};

struct SphereObstacle {
    Vec3d center{0.0, 0.0, 0.0};
    double radius = 0.5;
};

// Axis-aligned, solid.
struct BoxObstacle {
    Vec3d min{-0.5, -0.5, -0.5};
    Vec3d max{0.5, 0.5, 0.5};
};

using Obstacle = std::variant<PlaneObstacle, SphereObstacle, BoxObstacle>;

// Signed distance from x to the obstacle's surface (negative inside) and the unit outward
// normal of the surface at the closest point (for a point exactly at a sphere's centre or on a
// box's medial set: a fixed, valid normal).
struct SurfaceDistance {
    double distance;
    Vec3d normal;
};
SurfaceDistance surface_distance(const Obstacle& obstacle, const Vec3d& x);

// The positional part of a contact: when x is closer than thickness to the surface, moves it out
// along the surface normal to distance thickness. Returns the correction's length (0 when x was
// not in contact) and the normal it moved along (meaningful only when the length is > 0).
struct ContactCorrection {
    double depth;
    Vec3d normal;
};
ContactCorrection push_out(const Obstacle& obstacle, Vec3d& x, double thickness);

// Whether push_out(obstacle, x, thickness) certainly finds no contact, by a test cheaper than
// push_out's (false: ask push_out). A sphere: x farther from the centre than
// (radius + thickness)(1 + 1e-9), on squared distances, which no rounding of push_out's exact
// test (a few 1e-16 relative) can bring within the thickness; other shapes: false.
inline bool out_of_reach(const Obstacle& obstacle, const Vec3d& x, double thickness) {
    if (const auto* sphere = std::get_if<SphereObstacle>(&obstacle)) {
        const Vec3d d = x - sphere->center;
        const double reach = (sphere->radius + thickness) * (1.0 + 1e-9);
        return dot(d, d) > reach * reach;
    }
    return false;
}

// Coulomb friction at the velocity level (as in M. Müller, M. Macklin, N. Chentanez, S. Jeschke,
// T.-Y. Kim, "Detailed Rigid Body Simulation with Extended Position Based Dynamics", SCA 2020,
// §3.6): the contact's normal speed change normal_speed (= depth / h, m/s) bounds the tangential
// speed it can remove. The tangential part of v is removed entirely when it is at most
// static_friction · normal_speed (sticking), else shortened by kinetic_friction · normal_speed.
// Acting on velocities after the constraint projection, friction never undoes a constraint's
// positional correction.
Vec3d apply_friction(const Vec3d& velocity, const Vec3d& normal, double normal_speed,
                     double static_friction, double kinetic_friction);

}  // namespace pliant::cloth
