// Lens models of real cameras: COLMAP's and nerfstudio's camera models, mapping between the
// pinhole ("undistorted") normalized image coordinates and the distorted ones a photo records.
//
// Coordinates (OpenCV / COLMAP axes): a camera-frame point (X, Y, Z) with x right, y down, z
// forward has the normalized coordinates (u, v) = (X / Z, Y / Z); the lens maps them to the
// distorted (u_d, v_d), and the pixel is (fx · u_d + cx, fy · v_d + cy) in continuous pixel
// coordinates with the origin at the image's top-left corner (pixel (i, j) has its centre at
// (i + 0.5, j + 0.5), COLMAP's convention).
//
// Models (names as COLMAP and nerfstudio's `camera_model` spell them), with r² = u² + v²:
//   SIMPLE_PINHOLE, PINHOLE   u_d = u                                        (no coefficient)
//   SIMPLE_RADIAL             u_d = u (1 + k1 r²)                            (k1)
//   RADIAL                    u_d = u (1 + k1 r² + k2 r⁴)                    (k1, k2)
//   OPENCV                    u_d = u (1 + k1 r² + k2 r⁴ + k3 r⁶ + k4 r⁸) + 2 p1 u v + p2 (r² + 2
//   u²)
//                             v_d = v (1 + …)                + 2 p2 u v + p1 (r² + 2 v²)
//                             (COLMAP's OPENCV has k1, k2, p1, p2; nerfstudio's radial polynomial
//                             also carries k3, k4)
//   OPENCV_FISHEYE            θ = atan(r), θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸),
//                             (u_d, v_d) = (θ_d / r) (u, v)   (the equidistant fisheye of OpenCV)
// The simple models are the OPENCV one with the other coefficients zero; a model only accepts
// its own coefficients (lens_model_uses).
//
// The inverse (undistort) is Newton's method on the 2 × 2 system (1-D in θ for the fisheye)
// started at the distorted point, to |residual| ≤ 1e-12 in normalized units within 50 steps;
// a point where it does not converge (a lens whose polynomial folds back inside the image) is
// reported, never guessed.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "pliant/core/vec3.hpp"

namespace pliant::nerf {

enum class LensModel { simple_pinhole, pinhole, simple_radial, radial, opencv, opencv_fisheye };

// COLMAP's name ("OPENCV_FISHEYE"), and back (nullopt for any other name).
std::string_view lens_model_name(LensModel model);
std::optional<LensModel> lens_model_from_name(std::string_view name);
// "SIMPLE_PINHOLE, PINHOLE, …" for error messages.
std::string lens_model_names();

// Distortion coefficients; those the model does not use are zero.
struct Lens {
    LensModel model = LensModel::pinhole;
    double k1 = 0.0, k2 = 0.0, k3 = 0.0, k4 = 0.0;  // radial (θ polynomial for the fisheye)
    double p1 = 0.0, p2 = 0.0;                      // tangential (OPENCV only)

    // No distortion at all (a pinhole model, or any model with every coefficient zero).
    bool is_identity() const;
};

// Whether `model` has the coefficient named `key` ("k1" … "k4", "p1", "p2").
bool lens_model_uses(LensModel model, std::string_view key);

// InvalidInput naming `where`, the coefficient and the model when a coefficient the model does
// not use is non-zero, or any coefficient is not finite.
void validate(const Lens& lens, std::string_view where);

struct Point2 {
    double x = 0.0, y = 0.0;
};

// Normalized pinhole coordinates (u, v) → distorted normalized coordinates (the formulas above).
Point2 distort(const Lens& lens, Point2 undistorted);

// The inverse: distorted normalized coordinates → the unit ray direction in the camera frame
// (OpenCV axes: x right, y down, z forward), or nullopt when Newton's method does not converge.
// The fisheye's direction comes from θ directly, so it is valid up to θ = π.
std::optional<Vec3d> undistorted_direction(const Lens& lens, Point2 distorted);

// The inverse as normalized pinhole coordinates (u, v) = (x / z, y / z) of that direction;
// nullopt when it does not converge or the direction is not in front of the camera.
std::optional<Point2> undistort(const Lens& lens, Point2 distorted);

}  // namespace pliant::nerf
