// Sym3: a symmetric 3 × 3 matrix for the per-vertex Newton steps of the VBD stepper
// (vbd_stepper.hpp) and the contact energy that adds to them (ogc_contact.hpp).
#pragma once

#include <cmath>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth::detail {

// Entries xx, yy, zz, xy, xz, yz.
struct Sym3 {
    double xx = 0.0, yy = 0.0, zz = 0.0, xy = 0.0, xz = 0.0, yz = 0.0;

    void add_diagonal(double s) {
        xx += s;
        yy += s;
        zz += s;
    }
    // += s · a aᵀ
    void add_outer(const Vec3d& a, double s) {
        xx += s * a.x * a.x;
        yy += s * a.y * a.y;
        zz += s * a.z * a.z;
        xy += s * a.x * a.y;
        xz += s * a.x * a.z;
        yz += s * a.y * a.z;
    }
};

// Solves H d = f by the adjugate; false when H is (numerically) singular.
inline bool solve(const Sym3& h, const Vec3d& f, Vec3d& d) {
    const double c00 = h.yy * h.zz - h.yz * h.yz;
    const double c01 = h.xz * h.yz - h.xy * h.zz;
    const double c02 = h.xy * h.yz - h.xz * h.yy;
    const double det = h.xx * c00 + h.xy * c01 + h.xz * c02;
    const double scale = std::abs(h.xx) + std::abs(h.yy) + std::abs(h.zz);
    if (!(std::abs(det) > 1e-30 * scale * scale * scale)) {
        return false;
    }
    const double c11 = h.xx * h.zz - h.xz * h.xz;
    const double c12 = h.xy * h.xz - h.xx * h.yz;
    const double c22 = h.xx * h.yy - h.xy * h.xy;
    const double inv = 1.0 / det;
    d = {(c00 * f.x + c01 * f.y + c02 * f.z) * inv, (c01 * f.x + c11 * f.y + c12 * f.z) * inv,
         (c02 * f.x + c12 * f.y + c22 * f.z) * inv};
    return true;
}

}  // namespace pliant::cloth::detail
