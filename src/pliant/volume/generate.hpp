// Generated test volumes: the 3D Shepp–Logan head phantom, a uniform sphere, and an RGBA
// orientation object for checking renderers. All are computed per voxel centre
// (origin + (i + 0.5) spacing, volume/volume.hpp), in parallel over z slices, with results
// bitwise identical for any number of threads.
//
//   const volume::Volume phantom = volume::shepp_logan_3d({128, 128, 128});
//   const volume::Volume ball = volume::uniform_sphere({64, 64, 64}, 20.0, 1.0f);
//   const volume::Volume axes = volume::rgba_test_object({96, 96, 96});
#pragma once

#include <array>

#include "pliant/volume/volume.hpp"

namespace pliant::volume {

// The 3D Shepp–Logan phantom: ten ellipsoids whose intensities add up, from
//   A. C. Kak, M. Slaney, "Principles of Computerized Tomographic Imaging", IEEE Press 1988,
//   Table 3.2, p. 102 (the 3D extension of Shepp & Logan 1974),
// as also tabulated by TIGRE's sheppLogan3D and tsadakane/sl3d ("kak-slaney" / "yu-ye-wang").
// Ellipsoid n has semi-axes (a, b, c), centre (x0, y0, z0), a rotation φ about z (degrees; the
// a-axis makes the angle φ with +x, counter-clockwise seen from +z) and an additive intensity A;
// a point p is inside when (x'/a)² + (y'/b)² + (z'/c)² ≤ 1 with
//   x' = cos φ·(px − x0) + sin φ·(py − y0),  y' = −sin φ·(px − x0) + cos φ·(py − y0),  z' = pz −
//   z0.
// Intensities, in the phantom's units (relative density, water ≈ 1):
//   kak_slaney   2.00, −0.98, −0.02, −0.02, 0.02, 0.02, 0.01, 0.01, 0.02, −0.02 (skull 2.0,
//   brain 1.02) yu_ye_wang   1.0, −0.8, −0.2, −0.2, 0.2, 0.2, 0.1, 0.1, 0.2, −0.2 (the "modified",
//   higher
//                contrast version of Yu, Ye & Wang, SPIE 5535, 2004: skull 1.0, brain 0.2)
enum class SheppLoganVariant { kak_slaney, yu_ye_wang };

// The phantom's intensity at a point of its own coordinates (the head fits in [−1, 1]³).
float shepp_logan_value(const Vec3d& p, SheppLoganVariant variant = SheppLoganVariant::kak_slaney);

// An f32 volume of `dims` voxels spanning the box [−1, 1]³ (spacing 2/dims per axis, origin
// (−1, −1, −1)), each voxel the phantom's value at its centre (point sampled, no anti-aliasing).
// InvalidInput for dims < 1 (from Volume::allocate).
Volume shepp_logan_3d(const Dims& dims, SheppLoganVariant variant = SheppLoganVariant::kak_slaney);

struct SphereOptions {
    Vec3d spacing{1.0, 1.0, 1.0};  // world units per voxel
    Vec3d origin{0.0, 0.0, 0.0};   // the volume covers [origin, origin + dims · spacing]
    bool has_center = false;       // false: the sphere is centred in the volume's box
    Vec3d center{0.0, 0.0, 0.0};   // world units, used when has_center
    // Samples per axis inside each voxel (1 ≤ n ≤ 16). n = 1: a voxel is inside when its centre
    // is (binary). n > 1: the voxel's coverage f is the fraction of its n³ sub-voxel centres
    // (at (s + 0.5)/n of the voxel, s = 0 … n − 1 per axis) inside the sphere, and the voxel holds
    // f · value (scalar) or (colour, f · opacity) (RGBA: an anti-aliased edge, approximate since
    // opacity per unit distance is not linear in coverage).
    int supersample = 1;
};

// A sphere of `radius` world units holding `value` in an f32 volume, 0 outside.
// InvalidInput for a radius that is not finite and > 0, supersample outside [1, 16], a centre
// that is not finite, or bad dims/spacing/origin (Volume::allocate).
Volume uniform_sphere(const Dims& dims, double radius, float value,
                      const SphereOptions& options = {});
// The same in an rgba32f volume: straight (not premultiplied) colour rgba[0..2] in [0, 1] and
// opacity rgba[3] in [0, 1] per opacity unit (volume/transfer_function.hpp) inside, (0, 0, 0, 0)
// outside. InvalidInput also for components outside [0, 1].
Volume uniform_sphere(const Dims& dims, double radius, const std::array<float, 4>& rgba,
                      const SphereOptions& options = {});

// An RGBA object that makes orientation obvious, in a volume of `dims` voxels spanning [−1, 1]³
// (spacing 2/dims, origin (−1, −1, −1)), straight colour and opacity per opacity unit:
//   a red arrow along +x, a green arrow along +y, a blue arrow along +z (each a shaft of radius
//   0.05 from 0.25 to 0.6 and a cone from 0.6 to 0.9 with base radius 0.13; opacity 0.6),
//   a translucent grey sphere of radius 0.25 at the origin (opacity 0.1),
//   a yellow cube of half-size 0.1 at (−0.6, −0.6, −0.6), the −x −y −z corner (opacity 0.6).
// Where primitives overlap, the later in this list wins. type is rgba8 (channels round(255 · c))
// or rgba32f; else InvalidInput.
Volume rgba_test_object(const Dims& dims, VoxelType type = VoxelType::rgba32f);

}  // namespace pliant::volume
