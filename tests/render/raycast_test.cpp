#include "pliant/render/raycast.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/raycast_avx2.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"
#include "pliant/volume/generate.hpp"
#include "support/images.hpp"

namespace pliant::render {
namespace {

using volume::Dims;
using volume::Volume;
using volume::VoxelType;

// The sphere test scene: radius R world units in a box of side 2R + 8 voxels (spacing 1), colour
// c, opacity a per opacity unit U. The voxelized sphere (binary voxels, trilinear) differs from
// the analytic one within about a voxel of its silhouette, where the chord L(r) = 2√(R² − r²)
// has an infinite slope: a pixel centred exactly on the silhouette sees a chord of a few voxels
// instead of 0 (up to 0.05 in colour at these opacities). The every-pixel comparison therefore
// uses one pixel per voxel column (pixel centres on voxel centres, none within 0.04 voxel of the
// silhouette) and an opacity per voxel (1 − a^(1/U)) of about 1%.
constexpr double R = 28.0;
constexpr std::int64_t N = 64;
const std::array<float, 4> RGBA{0.8f, 0.6f, 0.4f, 0.5f};
constexpr double U = 80.0;

Volume sphere_volume() {
    volume::SphereOptions o;
    o.supersample = 1;
    return volume::uniform_sphere({N, N, N}, R, RGBA, o);
}

// Analytic colour of pixel (i, j) of view_camera(+z) over the sphere's box: right = −x, up = +y.
std::array<double, 3> analytic_sphere_pixel(int i, int j, int w, int h) {
    const double x = static_cast<double>(N) * (1.0 - (i + 0.5) / w) - 0.5 * N;
    const double y = static_cast<double>(N) * (1.0 - (j + 0.5) / h) - 0.5 * N;
    const double r2 = x * x + y * y;
    const double chord = r2 < R * R ? 2.0 * std::sqrt(R * R - r2) : 0.0;
    const double a = 1.0 - std::pow(1.0 - RGBA[3], chord / U);
    return {RGBA[0] * a, RGBA[1] * a, RGBA[2] * a};
}

double max_error_vs_analytic(const Image& image) {
    double worst = 0.0;
    for (int j = 0; j < image.height; ++j) {
        for (int i = 0; i < image.width; ++i) {
            const auto expected = analytic_sphere_pixel(i, j, image.width, image.height);
            const Color got = to_color(image.at(i, j));
            worst = std::max({worst, std::fabs(got.r - expected[0]), std::fabs(got.g - expected[1]),
                              std::fabs(got.b - expected[2])});
        }
    }
    return worst;
}

double mean_abs_difference(const Image& a, const Image& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        sum += std::abs(static_cast<int>(a.pixels[i]) - static_cast<int>(b.pixels[i]));
    }
    return sum / 255.0 / static_cast<double>(a.pixels.size());
}

TEST(RayCast, AnalyticSphereEveryPixelAtTheDefaultStep) {
    const Volume ball = sphere_volume();
    RayCastOptions options;
    options.opacity_unit = U;
    options.early_termination = 1.0;
    const Camera cam = view_camera(ball.bounds(), ViewAxis::pos_z, N, N);
    Image image;
    const RayCastStats stats = raycast(ball, nullptr, cam, options, image);
    ASSERT_EQ(image.width, N);
    ASSERT_EQ(image.height, N);
    EXPECT_GT(stats.samples, 0);
    EXPECT_LE(max_error_vs_analytic(image), 1e-2);
    // The centre pixel sees the full diameter.
    const double centre = RGBA[0] * (1.0 - std::pow(1.0 - RGBA[3], 2.0 * R / U));
    EXPECT_NEAR(to_color(image.at(N / 2, N / 2)).r, centre, 5e-3);
}

TEST(RayCast, CallerRaysMatchTheCameraPixels) {
    // render_rays with a perspective camera's pixel-centre rays (computed in double here, in
    // float by the kernel) gives render()'s image within one 8-bit level; the analytic sphere
    // bounds both.
    const Volume ball = sphere_volume();
    RayCastOptions options;
    options.opacity_unit = U;
    const Camera cam =
        Camera::perspective({20.0, 40.0, 140.0}, {32.0, 32.0, 32.0}, {0, 1, 0}, 35.0, 48, 40);
    const RayCaster caster(ball, nullptr, options);
    Image image;
    caster.render(cam, image);
    const std::vector<Ray> rays = test::pixel_rays(cam);
    std::vector<float> rgb(3 * rays.size());
    const RayCastStats stats = caster.render_rays(rays, rgb);
    EXPECT_GT(stats.samples, 0);
    EXPECT_LE(test::max_level_difference(rgb, image), 1);
    std::vector<float> wrong(5);
    EXPECT_THROW(caster.render_rays(rays, wrong), InvalidInput);
}

TEST(RayCast, AnalyticSphereConvergesAsTheStepHalves) {
    const Volume ball = sphere_volume();
    const Camera cam = view_camera(ball.bounds(), ViewAxis::neg_y, 96, 96);
    const auto render_at = [&](double step) {
        RayCastOptions options;
        options.opacity_unit = U;
        options.step = step;
        options.early_termination = 1.0;
        Image image;
        raycast(ball, nullptr, cam, options, image);
        return image;
    };
    const Image reference = render_at(0.0625);
    double previous = 1e9;
    for (const double step : {16.0, 8.0, 4.0, 2.0}) {
        const double error = mean_abs_difference(render_at(step), reference);
        EXPECT_LT(error, previous) << "step " << step;
        previous = error;
    }
    EXPECT_LT(previous, 2e-3);
}

// Finer pixels than voxels (4 pixels per voxel column). The exact image of the voxel sphere is
// c · (1 − (1 − a)^(L′ / U)) with L′ the chord weighted by the trilinear opacity along the ray,
// which equals the analytic chord L(r) = 2√(R² − r²) except where the ray crosses the sphere's
// trilinear edge: an anti-aliased sphere (coverage supersampled 4³, so the edge is a ramp of
// about one voxel centred on the true surface, not a binary staircase) shifts each end of the
// chord by a fraction of a voxel over the cosine of the incidence. Pixels whose centre lies
// within 1.5 voxel of the silhouette (|r − R| < 1.5, where the cosine goes to 0 and the chord's
// slope is infinite) are excluded; elsewhere the cosine is ≥ 0.41 (R = 17) and the edge costs at
// most about 0.3 voxel per end × 2 / 0.41 at about 0.7 % opacity per voxel: < 1e-2 in colour.
// Measured: max 0.0067, mean 0.0016 at the default step; the excluded band has errors up to
// 0.02.
struct FineSphere {
    static constexpr double RADIUS = 17.0;
    static constexpr std::int64_t SIDE = 40;
    static constexpr int PIXELS_PER_VOXEL = 4;
    static constexpr double BAND = 1.5;  // voxels either side of the silhouette, excluded
};

struct SphereError {
    double max = 0.0, mean = 0.0, max_in_band = 0.0;
    std::int64_t compared = 0, excluded = 0;
};

SphereError fine_sphere_error(double step) {
    using S = FineSphere;
    volume::SphereOptions o;
    o.supersample = 4;
    const Volume ball = volume::uniform_sphere({S::SIDE, S::SIDE, S::SIDE}, S::RADIUS, RGBA, o);
    const int w = static_cast<int>(S::SIDE) * S::PIXELS_PER_VOXEL;
    const Camera cam = view_camera(ball.bounds(), ViewAxis::pos_z, w, w);
    RayCastOptions options;
    options.opacity_unit = U;
    options.step = step;
    options.early_termination = 1.0;
    Image image;
    raycast(ball, nullptr, cam, options, image);
    SphereError e;
    double sum = 0.0;
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            // Pixel centre in the sphere's frame (right = −x, up = +y), voxels.
            const double x = S::SIDE * (0.5 - (i + 0.5) / w);
            const double y = S::SIDE * (0.5 - (j + 0.5) / w);
            const double r = std::sqrt(x * x + y * y);
            const double chord =
                r < S::RADIUS ? 2.0 * std::sqrt(S::RADIUS * S::RADIUS - r * r) : 0.0;
            const double a = 1.0 - std::pow(1.0 - RGBA[3], chord / U);
            const Color got = to_color(image.at(i, j));
            const double err =
                std::max({std::fabs(got.r - RGBA[0] * a), std::fabs(got.g - RGBA[1] * a),
                          std::fabs(got.b - RGBA[2] * a)});
            if (std::fabs(r - S::RADIUS) < S::BAND) {
                e.max_in_band = std::max(e.max_in_band, err);
                ++e.excluded;
                continue;
            }
            e.max = std::max(e.max, err);
            sum += err;
            ++e.compared;
        }
    }
    e.mean = sum / static_cast<double>(e.compared);
    return e;
}

TEST(RayCast, AnalyticSphereAtFourPixelsPerVoxel) {
    const SphereError e = fine_sphere_error(0.0);  // the default step, half a voxel
    EXPECT_LE(e.max, 1e-2);
    EXPECT_LE(e.mean, 3e-3);
    // The excluded band is a thin ring (about 2π · 17 · 3 voxels² at 16 pixels each) …
    EXPECT_LT(e.excluded, e.compared / 4);
    // … and its error stays bounded: the trilinear edge, not a hole or a halo.
    EXPECT_LE(e.max_in_band, 4e-2);
}

TEST(RayCast, AnalyticSphereAtFourPixelsPerVoxelConvergesAsTheStepShrinks) {
    // Mean error over the compared pixels: 0.009, 0.003, 0.0016, 0.0014 for steps 8, 4, 2, 1
    // voxels; below that the voxelization and 8-bit output (±0.002) dominate (0.0016 at 0.5).
    double previous = 1e9;
    for (const double step : {8.0, 4.0, 2.0, 1.0}) {
        const SphereError e = fine_sphere_error(step);
        EXPECT_LT(e.mean, previous) << "step " << step;
        if (step <= 2.0) {
            EXPECT_LE(e.max, 1e-2) << "step " << step;
        }
        previous = e.mean;
    }
    EXPECT_LT(previous, 2e-3);
}

TEST(RayCast, OpacityUnitMakesImagesIndependentOfTheStep) {
    const Volume phantom = volume::shepp_logan_3d({48, 48, 48});
    const volume::TransferFunction tf = volume::preset("mri-brain", phantom);
    const Camera cam = frame_box(phantom.bounds(), 30.0, 20.0, 64, 64);
    RayCastOptions coarse;
    coarse.step = volume::smallest_spacing(phantom);
    RayCastOptions fine = coarse;
    fine.step = 0.5 * coarse.step;
    Image a, b;
    raycast(phantom, &tf, cam, coarse, a);
    raycast(phantom, &tf, cam, fine, b);
    EXPECT_LT(mean_abs_difference(a, b), 0.01);
}

TEST(RayCast, EmptyVolumeRendersTheBackground) {
    const Volume zero = Volume::allocate({16, 16, 16}, VoxelType::rgba32f);
    RayCastOptions options;
    options.background = {0.2f, 0.4f, 0.6f};
    const Camera cam = frame_box(zero.bounds(), 10.0, 10.0, 32, 24);
    Image image;
    const RayCastStats stats = raycast(zero, nullptr, cam, options, image);
    EXPECT_EQ(image, Image(32, 24, to_rgb8(options.background)));
    EXPECT_EQ(stats.samples, 0);  // every macro cell is empty
}

TEST(RayCast, RaysThatMissSeeTheBackground) {
    const Volume ball = sphere_volume();
    // Looking away from the volume, and past it.
    const Camera away = Camera::perspective({200, 0, 0}, {400, 0, 0}, {0, 0, 1}, 40.0, 16, 16);
    const Camera past =
        Camera::orthographic({-50, -50, 200}, {-50, -50, 0}, {0, 1, 0}, 10.0, 16, 16);
    RayCastOptions options;
    options.background = {1.0f, 1.0f, 1.0f};
    for (const Camera& cam : {away, past}) {
        Image image;
        const RayCastStats stats = raycast(ball, nullptr, cam, options, image);
        EXPECT_EQ(image, Image(16, 16, Rgb8{255, 255, 255}));
        EXPECT_EQ(stats.samples, 0);
    }
}

TEST(RayCast, CameraInsideTheVolume) {
    // A uniform medium filling the box: from its centre every ray travels the distance D to the
    // box's face and renders c · (1 − (1 − a)^(D / U)) exactly.
    const std::array<float, 4> rgba{1.0f, 1.0f, 1.0f, 0.05f};
    volume::SphereOptions o;
    const Volume full = volume::uniform_sphere({20, 20, 20}, 100.0, rgba, o);  // covers the box
    const Camera cam = Camera::perspective({10, 10, 10}, {10, 10, 0}, {0, 1, 0}, 30.0, 9, 9);
    RayCastOptions options;
    options.early_termination = 1.0;
    Image image;
    raycast(full, nullptr, cam, options, image);
    for (int j = 0; j < 9; ++j) {
        for (int i = 0; i < 9; ++i) {
            const Ray ray = cam.pixel_ray(i, j);
            const double distance = 10.0 / std::fabs(ray.direction.z);  // to the z = 0 face
            const double expected = 1.0 - std::pow(1.0 - 0.05, distance);
            EXPECT_NEAR(to_color(image.at(i, j)).r, expected, 3e-3) << i << ", " << j;
        }
    }
}

TEST(RayCast, MaximumIntensityProjection) {
    // Values i / 15 along x, plus one voxel of 2 at (3, 5, 9): looking along −z, pixel columns
    // show the ramp and the hot voxel's column shows the maximum.
    Volume v = Volume::allocate({16, 16, 16}, VoxelType::f32);
    auto values = v.values<VoxelType::f32>();
    for (std::int64_t k = 0; k < 16; ++k) {
        for (std::int64_t j = 0; j < 16; ++j) {
            for (std::int64_t i = 0; i < 16; ++i) {
                values[static_cast<std::size_t>(v.index(i, j, k))] = static_cast<float>(i) / 15.0f;
            }
        }
    }
    values[static_cast<std::size_t>(v.index(3, 5, 9))] = 2.0f;
    const volume::TransferFunction tf = volume::preset("grayscale", v);  // 0 → black, 2 → white
    RayCastOptions options;
    options.mode = RayCastMode::mip;
    options.step = 1.0;  // samples at voxel centres along z
    const Camera cam = view_camera(v.bounds(), ViewAxis::neg_z, 16, 16);  // x right, y up
    Image image;
    raycast(v, &tf, cam, options, image);
    for (int i = 0; i < 16; ++i) {
        // Row 8 (y index 7) holds voxels of j = 7: the ramp value i/15 → grey (i/15)/2 at
        // opacity (i/15)/2.
        const double g = (i / 15.0) / 2.0;
        EXPECT_NEAR(to_color(image.at(i, 8)).r, g * g, 4e-3) << i;
    }
    EXPECT_EQ(image.at(3, 15 - 5), (Rgb8{255, 255, 255}));
}

TEST(RayCast, ViewCameraCoversTheBoxExactly) {
    const AABBd box{{-1, 2, 3}, {3, 4, 9}};
    // −z: x right (extent 4), y up (extent 2) at 40 × 20 pixels.
    const Camera cam = view_camera(box, ViewAxis::neg_z, 40, 20);
    for (int i : {0, 17, 39}) {
        for (int j : {0, 9, 19}) {
            const Ray ray = cam.pixel_ray(i, j);
            EXPECT_NEAR(ray.origin.x, -1.0 + 4.0 * (i + 0.5) / 40, 1e-12);
            EXPECT_NEAR(ray.origin.y, 4.0 - 2.0 * (j + 0.5) / 20, 1e-12);
            EXPECT_GT(ray.origin.z, 9.0);
            EXPECT_EQ(ray.direction, (Vec3d{0, 0, -1}));
        }
    }
    // +x: right −y, up +z.
    const Camera px = view_camera(box, ViewAxis::pos_x, 20, 60);
    const Ray first = px.pixel_ray(0, 0);
    EXPECT_NEAR(first.origin.y, 4.0 - 2.0 * 0.5 / 20, 1e-12);
    EXPECT_NEAR(first.origin.z, 9.0 - 6.0 * 0.5 / 60, 1e-12);
    EXPECT_LT(first.origin.x, -1.0);
    EXPECT_EQ(parse_view_axis("-y"), ViewAxis::neg_y);
    EXPECT_THROW(parse_view_axis("up"), InvalidInput);
}

TEST(RayCast, SkippingDoesNotChangeTheImage) {
    const Volume phantom = volume::shepp_logan_3d({40, 40, 40});
    const Volume rgba = volume::rgba_test_object({36, 36, 36}, VoxelType::rgba8);
    const volume::TransferFunction tf = volume::preset("mri-brain", phantom);
    // Oblique perspective views and axis views (rays parallel to the cell planes, sample
    // midpoints on voxel centres), composite with and without shading, and MIP.
    const std::vector<Camera> cameras = {
        frame_box(phantom.bounds(), -50.0, 35.0, 48, 40),
        frame_box(phantom.bounds(), 45.0, 0.0, 41, 37),
        view_camera(phantom.bounds(), ViewAxis::neg_y, 40, 40),
        view_camera(phantom.bounds(), ViewAxis::pos_z, 80, 80),
        // Far away (7.5 × 10⁵ voxels), telephoto: positions round to ≈ 0.06 voxel, more than
        // the fixed part of the jump margin (1/32 voxel).
        Camera::perspective(phantom.bounds().center() + Vec3d{30000.0, 20000.0, 10000.0},
                            phantom.bounds().center(), {0.0, 0.0, 1.0}, 0.006, 40, 40),
    };
    for (const RayCastMode mode : {RayCastMode::composite, RayCastMode::mip}) {
        for (const bool shading : {false, true}) {
            for (std::size_t c = 0; c < cameras.size(); ++c) {
                RayCastOptions on;
                on.mode = mode;
                on.shading = shading;
                RayCastOptions off = on;
                off.empty_space_skipping = false;
                Image a, b, ra, rb;
                const RayCastStats sa = raycast(phantom, &tf, cameras[c], on, a);
                const RayCastStats sb = raycast(phantom, &tf, cameras[c], off, b);
                raycast(rgba, nullptr, cameras[c], on, ra);
                raycast(rgba, nullptr, cameras[c], off, rb);
                EXPECT_EQ(a, b) << "camera " << c << " shading " << shading;
                EXPECT_EQ(ra, rb) << "RGBA, camera " << c << " shading " << shading;
                EXPECT_LT(sa.samples, sb.samples) << "camera " << c;
            }
        }
    }
}

// The occupancy test of a cell widens its value range by detail::LERP_ROUNDING only, not by a
// whole lookup entry: a background exactly at an entry of zero opacity (the phantom's air under
// `grayscale`, whose opacity is zero only at the range's bottom) is skipped, and images stay
// identical. Also on random voxels against a transfer function whose opacity starts just above
// an entry's centre, where a coarser bound would miss samples rounding into it.
TEST(RayCast, SkippingIsExactAtTheEdgeOfZeroOpacity) {
    const Volume phantom = volume::shepp_logan_3d({48, 40, 44});
    const volume::TransferFunction grey = volume::preset("grayscale", phantom);
    Volume noise = Volume::allocate({33, 30, 31}, VoxelType::f32);
    std::uint32_t state = 12345;
    for (float& x : noise.values<VoxelType::f32>()) {
        state = state * 1664525u + 1013904223u;
        x = static_cast<float>(state >> 8) / 16777216.0f;
    }
    noise.values<VoxelType::f32>()[0] = 0.0f;  // the range is [0, 1) at most
    volume::TransferFunction edge;
    edge.name = "edge";
    edge.color = {{0.0, {1.0f, 1.0f, 1.0f}}};
    // Opacity zero up to the entry 2048 of [0, max] and rising after it.
    const double top = volume::value_range(noise)[1];
    const double at = top * 2048.0 / (detail::LUT_SIZE - 1);
    edge.opacity = {{0.0, 0.0f}, {at, 0.0f}, {top, 0.3f}};
    for (const Camera& cam : {frame_box(phantom.bounds(), 30.0, 20.0, 64, 56),
                              view_camera(phantom.bounds(), ViewAxis::neg_y, 48, 44)}) {
        RayCastOptions on;
        RayCastOptions off;
        off.empty_space_skipping = false;
        Image a, b;
        const RayCastStats sa = raycast(phantom, &grey, cam, on, a);
        const RayCastStats sb = raycast(phantom, &grey, cam, off, b);
        EXPECT_EQ(a, b);
        EXPECT_LT(2 * sa.samples, sb.samples);  // the air is skipped
    }
    const Camera cam = frame_box(noise.bounds(), -40.0, 25.0, 61, 57);
    for (const bool shading : {false, true}) {
        RayCastOptions on;
        on.shading = shading;
        on.early_termination = 1.0;
        RayCastOptions off = on;
        off.empty_space_skipping = false;
        Image a, b;
        raycast(noise, &edge, cam, on, a);
        raycast(noise, &edge, cam, off, b);
        EXPECT_EQ(a, b) << "shading " << shading;
    }
}

TEST(RayCast, EmptyCubesMatchBruteForce) {
    const int cells[3] = {9, 7, 5};
    std::vector<std::uint8_t> occupied(9 * 7 * 5, 0);
    std::uint32_t state = 12345;
    for (auto& o : occupied) {
        state = state * 1664525u + 1013904223u;
        o = (state >> 24) < 8 ? 1 : 0;  // about 3 %
    }
    const auto is_occupied = [&](int x, int y, int z) {
        return x >= 0 && y >= 0 && z >= 0 && x < 9 && y < 7 && z < 5 &&
               occupied[static_cast<std::size_t>(x + 9 * (y + 7 * z))] != 0;
    };
    std::vector<std::uint8_t> side(occupied.size());
    for (int octant = 0; octant < 8; ++octant) {
        detail::empty_cubes(occupied, cells, octant, side);
        const int dir[3] = {(octant & 1) != 0 ? -1 : 1, (octant & 2) != 0 ? -1 : 1,
                            (octant & 4) != 0 ? -1 : 1};
        for (int z = 0; z < 5; ++z) {
            for (int y = 0; y < 7; ++y) {
                for (int x = 0; x < 9; ++x) {
                    // Grow the cube from (x, y, z) towards the octant until it holds an occupied
                    // cell (cells outside the grid are empty); its largest empty side, ≤ 20.
                    int expected = 0;
                    for (int s = 1; s <= 20; ++s) {
                        bool empty = true;
                        for (int k = 0; k < s && empty; ++k) {
                            for (int j = 0; j < s && empty; ++j) {
                                for (int i = 0; i < s && empty; ++i) {
                                    empty = !is_occupied(x + dir[0] * i, y + dir[1] * j,
                                                         z + dir[2] * k);
                                }
                            }
                        }
                        if (!empty) {
                            break;
                        }
                        expected = s;
                    }
                    const int got = side[static_cast<std::size_t>(x + 9 * (y + 7 * z))];
                    // Cubes reaching 20 cells lie mostly outside the grid: only "at least".
                    if (expected < 20) {
                        EXPECT_EQ(got, expected) << octant << ": " << x << " " << y << " " << z;
                    } else {
                        EXPECT_GE(got, 20) << octant << ": " << x << " " << y << " " << z;
                    }
                }
            }
        }
    }
    // No occupied cell: every cube at the cap.
    std::fill(occupied.begin(), occupied.end(), 0);
    detail::empty_cubes(occupied, cells, 5, side);
    EXPECT_EQ(*std::min_element(side.begin(), side.end()), detail::MAX_CUBE);
}

TEST(RayCast, DeterministicForOneAndTwoThreads) {
    const Volume phantom = volume::shepp_logan_3d({40, 40, 40});
    const volume::TransferFunction tf = volume::preset("grayscale", phantom);
    const Volume rgba = volume::rgba_test_object({32, 32, 32}, VoxelType::rgba8);
    const Camera cam = frame_box(phantom.bounds(), 30.0, 20.0, 70, 50);
    RayCastOptions options;
    options.shading = true;
    Image one, two, rgba_one, rgba_two;
    set_num_threads(1);
    const RayCastStats s1 = raycast(phantom, &tf, cam, options, one);
    raycast(rgba, nullptr, cam, options, rgba_one);
    set_num_threads(2);
    const RayCastStats s2 = raycast(phantom, &tf, cam, options, two);
    raycast(rgba, nullptr, cam, options, rgba_two);
    set_num_threads(0);
    EXPECT_EQ(one, two);
    EXPECT_EQ(rgba_one, rgba_two);
    EXPECT_EQ(s1.samples, s2.samples);
}

// Composite views take the AVX2 march (detail::composite_avx2_fits) on CPUs that have it (the
// test above shades, on it too). Unshaded scalar views are bit for bit the same for 1, 2 and the
// default thread count, over images of many tiles, with and without skipping and clipped.
TEST(RayCast, Avx2MarchDeterministicForOneAndManyThreads) {
    const Volume phantom = volume::shepp_logan_3d({48, 40, 44});
    const volume::TransferFunction tf = volume::preset("mri-brain", phantom);
    const AABBd box = phantom.bounds();
    const std::vector<Camera> cameras = {frame_box(box, 30.0, 20.0, 150, 110),
                                         view_camera(box, ViewAxis::pos_z, 97, 131)};
    for (const Camera& cam : cameras) {
        for (int variant = 0; variant < 3; ++variant) {
            RayCastOptions o;
            o.shading = false;
            o.empty_space_skipping = variant != 1;
            if (variant == 2) {
                o.clip = ClipPlane{box.center(), {0.3, 1.0, -0.2}};
            }
            const RayCaster caster(phantom, &tf, o);
            Image one, two, many;
            set_num_threads(1);
            const RayCastStats s1 = caster.render(cam, one);
            set_num_threads(2);
            const RayCastStats s2 = caster.render(cam, two);
            set_num_threads(0);
            const RayCastStats s0 = caster.render(cam, many);
            EXPECT_EQ(one, two) << "variant " << variant;
            EXPECT_EQ(one, many) << "variant " << variant;
            EXPECT_EQ(s1.samples, s2.samples) << "variant " << variant;
            EXPECT_EQ(s1.samples, s0.samples) << "variant " << variant;
        }
    }
}

// The AVX2 march (detail/raycast_avx2.hpp: 8 rays per instruction, lanes refilled as rays end)
// gives the scalar kernel's images and sample counts bit for bit: views with every kind of ray
// (oblique, axis-parallel with zero direction components, from inside, far away, clipped), tiles
// and groups of 8 cut short by odd image sizes, with and without skipping, several transfer
// functions and early-termination thresholds, non-cubic volumes and the smallest ones.
TEST(RayCast, Avx2MarchMatchesTheScalarKernel) {
    if (!has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    struct Scene {
        Volume volume;
        const char* tf;
    };
    std::vector<Scene> scenes;
    scenes.push_back({volume::shepp_logan_3d({40, 40, 40}), "mri-brain"});
    scenes.push_back({volume::shepp_logan_3d({37, 23, 30}), "grayscale"});
    scenes.push_back({volume::shepp_logan_3d({2, 9, 5}), "grayscale"});
    scenes.push_back({volume::shepp_logan_3d({1, 12, 12}), "grayscale"});  // scalar kernel only
    for (const Scene& scene : scenes) {
        const Volume& v = scene.volume;
        const volume::TransferFunction tf = volume::preset(scene.tf, v);
        const AABBd box = v.bounds();
        const std::vector<Camera> cameras = {
            frame_box(box, 30.0, 20.0, 53, 47),
            frame_box(box, -120.0, -60.0, 40, 33),
            view_camera(box, ViewAxis::neg_y, 45, 40),
            view_camera(box, ViewAxis::pos_x, 17, 29),
            view_camera(box, ViewAxis::neg_z, 64, 64),
            Camera::perspective(box.center(), box.center() + Vec3d{1.0, 0.3, 0.2}, {0.0, 0.0, 1.0},
                                90.0, 31, 31),  // inside
            Camera::perspective(box.center() + Vec3d{30000.0, 20000.0, 10000.0}, box.center(),
                                {0.0, 0.0, 1.0}, 0.006, 24, 24),
        };
        for (std::size_t c = 0; c < cameras.size(); ++c) {
            for (int variant = 0; variant < 4; ++variant) {
                RayCastOptions o;
                o.empty_space_skipping = variant != 1;
                o.early_termination = variant == 2 ? 1.0 : 0.99;
                if (variant == 3) {
                    o.clip = ClipPlane{box.center(), {1.0, -0.5, 0.25}};
                    o.step = 0.37 * v.spacing().x;
                    o.background = {0.1f, 0.5f, 1.0f};
                }
                const RayCaster caster(v, &tf, o);
                Image simd, scalar;
                const RayCastStats s_simd = caster.render(cameras[c], simd);
                allow_avx2(false);
                const RayCastStats s_scalar = caster.render(cameras[c], scalar);
                allow_avx2(true);
                EXPECT_EQ(simd, scalar) << scene.tf << " camera " << c << " variant " << variant;
                EXPECT_EQ(s_simd.samples, s_scalar.samples)
                    << scene.tf << " camera " << c << " variant " << variant;
            }
        }
    }
}

// Every kind of rendering on the AVX2 march, composite (scalar volumes shaded, RGBA volumes
// (rgba8 and rgba32f) shaded or not) and MIP (scalar and RGBA), gives the scalar kernel's images
// and sample counts bit for bit: the views of the test above (oblique, axis, inside, far away) and
// clipped ones, odd image and volume sizes, the smallest volumes and empty ones (nothing visible),
// with and without skipping and early termination.
Volume rgba_of(const Volume& scalar, const char* tf, VoxelType type) {
    const Volume rgba = volume::apply(scalar, volume::preset(tf, scalar));
    if (type == VoxelType::rgba32f) {
        return rgba;
    }
    Volume out = Volume::allocate(rgba.dims(), VoxelType::rgba8, rgba.spacing(), rgba.origin());
    const auto in = rgba.values<VoxelType::rgba32f>();
    const auto values = out.values<VoxelType::rgba8>();
    for (std::size_t i = 0; i < in.size(); ++i) {
        values[i] = static_cast<std::uint8_t>(std::lround(255.0f * in[i]));
    }
    return out;
}

TEST(RayCast, Avx2MarchMatchesTheScalarKernelForEveryKind) {
    if (!has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    struct Scene {
        std::string name;
        Volume volume;
        const char* tf;  // scalar volumes
    };
    std::vector<Scene> scenes;
    scenes.push_back({"scalar 37x23x30", volume::shepp_logan_3d({37, 23, 30}), "mri-brain"});
    scenes.push_back({"scalar 2x9x5", volume::shepp_logan_3d({2, 9, 5}), "grayscale"});
    scenes.push_back({"scalar empty", Volume::allocate({9, 7, 5}, VoxelType::f32), "grayscale"});
    scenes.push_back({"rgba32f object 33x29x31",
                      volume::rgba_test_object({33, 29, 31}, VoxelType::rgba32f), nullptr});
    scenes.push_back({"rgba8 object 21x18x23",
                      volume::rgba_test_object({21, 18, 23}, VoxelType::rgba8), nullptr});
    scenes.push_back(
        {"rgba32f phantom 40x36x38",
         rgba_of(volume::shepp_logan_3d({40, 36, 38}), "mri-brain", VoxelType::rgba32f), nullptr});
    scenes.push_back({"rgba8 phantom 3x5x4",
                      rgba_of(volume::shepp_logan_3d({3, 5, 4}), "grayscale", VoxelType::rgba8),
                      nullptr});
    scenes.push_back({"rgba8 2x2x2",
                      rgba_of(volume::shepp_logan_3d({2, 2, 2}), "grayscale", VoxelType::rgba8),
                      nullptr});
    scenes.push_back({"rgba empty", Volume::allocate({6, 11, 7}, VoxelType::rgba8), nullptr});
    scenes.push_back({"rgba 1x12x12 (scalar kernel only)",
                      rgba_of(volume::shepp_logan_3d({1, 12, 12}), "grayscale", VoxelType::rgba8),
                      nullptr});
    std::int64_t total_samples = 0;
    for (const Scene& scene : scenes) {
        const Volume& v = scene.volume;
        const volume::TransferFunction tf =
            scene.tf != nullptr ? volume::preset(scene.tf, v) : volume::TransferFunction{};
        const AABBd box = v.bounds();
        const std::vector<Camera> cameras = {
            frame_box(box, 30.0, 20.0, 53, 47),
            frame_box(box, -120.0, -60.0, 40, 33),
            view_camera(box, ViewAxis::neg_y, 45, 40),
            view_camera(box, ViewAxis::pos_x, 17, 29),
            Camera::perspective(box.center(), box.center() + Vec3d{1.0, 0.3, 0.2}, {0.0, 0.0, 1.0},
                                90.0, 31, 31),  // inside
            Camera::perspective(box.center() + Vec3d{30000.0, 20000.0, 10000.0}, box.center(),
                                {0.0, 0.0, 1.0}, 0.006, 24, 24),
        };
        // 0: composite, 1: composite shaded, 2: MIP.
        for (int shading = 0; shading < 3; ++shading) {
            for (int variant = 0; variant < 4; ++variant) {
                RayCastOptions o;
                o.shading = shading == 1;
                o.mode = shading == 2 ? RayCastMode::mip : RayCastMode::composite;
                o.empty_space_skipping = variant != 1;
                o.early_termination = variant == 2 ? 1.0 : 0.9;
                if (variant == 3) {
                    o.clip = ClipPlane{box.center(), {1.0, -0.5, 0.25}};
                    o.step = 0.37 * v.spacing().x;
                    o.background = {0.1f, 0.5f, 1.0f};
                }
                const RayCaster caster(v, scene.tf != nullptr ? &tf : nullptr, o);
                for (std::size_t c = 0; c < cameras.size(); ++c) {
                    Image simd, scalar;
                    const RayCastStats s_simd = caster.render(cameras[c], simd);
                    allow_avx2(false);
                    const RayCastStats s_scalar = caster.render(cameras[c], scalar);
                    allow_avx2(true);
                    EXPECT_EQ(simd, scalar) << scene.name << " shading " << shading << " camera "
                                            << c << " variant " << variant;
                    EXPECT_EQ(s_simd.samples, s_scalar.samples)
                        << scene.name << " shading " << shading << " camera " << c << " variant "
                        << variant;
                    total_samples += s_simd.samples;
                }
            }
        }
    }
    EXPECT_GT(total_samples, 0);
}

// The AVX2 conversion of voxels to lookup coordinates (the ray caster's preparation) gives the
// scalar formula's floats bit for bit for every scalar voxel type: values below, inside and above
// the range, the range's ends, ±0, ±∞ and NaN, lengths that are not a multiple of 4.
template <typename T>
void expect_lookup_coordinates_match(const std::vector<T>& in, double lo, double hi) {
    const double scale = (detail::LUT_SIZE - 1) / (hi - lo);
    for (std::size_t count = 0; count <= in.size(); ++count) {
        std::vector<float> out(count, -7.0f);
        const std::int64_t done = detail::lookup_coordinates_avx2(
            in.data(), static_cast<std::int64_t>(count), lo, scale, out.data());
        ASSERT_EQ(done, static_cast<std::int64_t>(count - count % 4));
        for (std::int64_t i = 0; i < done; ++i) {
            const float expected = detail::lookup_coordinate(
                static_cast<double>(in[static_cast<std::size_t>(i)]), lo, scale);
            std::uint32_t a = 0, b = 0;
            std::memcpy(&a, &out[static_cast<std::size_t>(i)], 4);
            std::memcpy(&b, &expected, 4);
            EXPECT_EQ(a, b) << "value " << static_cast<double>(in[static_cast<std::size_t>(i)]);
        }
    }
}

TEST(RayCast, Avx2LookupCoordinatesMatchTheScalarFormula) {
    if (!has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    expect_lookup_coordinates_match<std::uint8_t>(
        {0, 1, 2, 17, 100, 127, 128, 200, 254, 255, 3, 9, 77}, 2.0, 254.0);
    expect_lookup_coordinates_match<std::int16_t>(
        {-32768, -1000, -1, 0, 1, 999, 1000, 1001, 32767, 12345, -7, 42, 5}, -1000.0, 1000.0);
    expect_lookup_coordinates_match<std::uint16_t>({0, 1, 4095, 4096, 65535, 300, 2048, 7, 11}, 1.0,
                                                   4096.0);
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    expect_lookup_coordinates_match<float>(
        {-1.0f, -0.0f, 0.0f, 1.0f, 0.5f, 1.5f, -2.0f, inf, -inf, nan, 1e30f, -1e30f, 0.123456f,
         0.999999f, std::numeric_limits<float>::denorm_min(), 0.3f, 0.7f},
        -1.0, 1.0);
    expect_lookup_coordinates_match<float>({-0.0f, 0.0f, 0.25f, 1.0f, 3.0f}, 0.0, 1.0);
}

// The AVX2 conversion of RGBA voxels (opacity-weighted colour and α, α apart) gives the scalar
// formula's floats bit for bit: channels below 0 (−0 included), above 1, ±∞, NaN, rgba8 and
// rgba32f, odd voxel counts.
template <typename T>
void expect_rgba_values_match(const std::vector<T>& in) {
    const auto channel = [](T x) {
        const float f = std::is_same_v<T, std::uint8_t> ? static_cast<float>(x) / 255.0f
                                                        : static_cast<float>(x);
        return std::isfinite(f) ? std::clamp(f, 0.0f, 1.0f) : 0.0f;
    };
    const std::size_t voxels = in.size() / 4;
    for (std::size_t count = 0; count <= voxels; ++count) {
        std::vector<float> out(4 * count, -7.0f), alpha(count, -7.0f);
        const std::int64_t done = detail::rgba_values_avx2(
            in.data(), static_cast<std::int64_t>(count), out.data(), alpha.data());
        ASSERT_EQ(done, static_cast<std::int64_t>(count - count % 2));
        for (std::size_t v = 0; v < static_cast<std::size_t>(done); ++v) {
            const float a = channel(in[4 * v + 3]);
            const float expected[5] = {channel(in[4 * v]) * a, channel(in[4 * v + 1]) * a,
                                       channel(in[4 * v + 2]) * a, a, a};
            const float got[5] = {out[4 * v], out[4 * v + 1], out[4 * v + 2], out[4 * v + 3],
                                  alpha[v]};
            for (int c = 0; c < 5; ++c) {
                std::uint32_t x = 0, y = 0;
                std::memcpy(&x, &got[c], 4);
                std::memcpy(&y, &expected[c], 4);
                EXPECT_EQ(x, y) << "voxel " << v << " channel " << c;
            }
        }
    }
}

TEST(RayCast, Avx2RgbaValuesMatchTheScalarFormula) {
    if (!has_avx2()) {
        GTEST_SKIP() << "the CPU has no AVX2";
    }
    std::vector<std::uint8_t> bytes;
    for (int i = 0; i < 4 * 13; ++i) {
        bytes.push_back(static_cast<std::uint8_t>((i * 97 + 13) % 256));
    }
    bytes[3] = 0;
    bytes[7] = 255;
    expect_rgba_values_match(bytes);
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    expect_rgba_values_match<float>({0.5f, 0.25f,  1.0f, 0.5f, -0.0f,  0.3f, 2.0f,  0.7f, -1.0f,
                                     inf,  nan,    1.0f, 0.1f, 0.2f,   0.3f, -0.0f, 0.9f, 0.8f,
                                     0.7f, nan,    0.4f, -inf, 1.5f,   inf,  0.3f,  0.3f, 0.3f,
                                     0.3f, 1e-40f, 0.6f, 0.2f, 0.999f, 0.5f, 0.5f,  0.5f, 2.0f});
}

// A uniform RGBA cube (every voxel the same, so every sample inside the box is exact) seen
// along +x, one pixel per voxel: pixel row j sees z = 31.5 − j, column i sees y = 31.5 − i.
Volume uniform_cube() {
    Volume cube = Volume::allocate({32, 32, 32}, VoxelType::rgba32f);
    const auto values = cube.values<VoxelType::rgba32f>();
    for (std::size_t v = 0; v < values.size(); v += 4) {
        for (int c = 0; c < 4; ++c) {
            values[v + static_cast<std::size_t>(c)] = RGBA[static_cast<std::size_t>(c)];
        }
    }
    return cube;
}

TEST(RayCast, ClipPlaneCutsTheChordAnalytically) {
    const Volume cube = uniform_cube();
    const Camera cam = view_camera(cube.bounds(), ViewAxis::pos_x, 32, 32);
    const double unit = 20.0;
    // An oblique plane through the centre, normal (1, 0, 1): kept where x ≥ 32 − z, so the ray
    // at height z keeps the chord x ∈ [max(0, 32 − z), 32] of length min(32, z).
    for (const double step : {0.0, 0.37}) {
        RayCastOptions options;
        options.opacity_unit = unit;
        options.step = step;
        options.early_termination = 1.0;
        options.clip = ClipPlane{{16.0, 16.0, 16.0}, {1.0, 0.0, 1.0}};
        Image image;
        raycast(cube, nullptr, cam, options, image);
        double worst = 0.0;
        for (int j = 0; j < 32; ++j) {
            const double z = 31.5 - j;
            const double a = 1.0 - std::pow(1.0 - RGBA[3], std::min(32.0, z) / unit);
            for (int i = 0; i < 32; ++i) {
                const Color got = to_color(image.at(i, j));
                worst = std::max({worst, std::fabs(got.r - RGBA[0] * a),
                                  std::fabs(got.g - RGBA[1] * a), std::fabs(got.b - RGBA[2] * a)});
            }
        }
        EXPECT_LT(worst, 3.0 / 255.0) << "step " << step;
    }
    // A plane parallel to the rays (normal +z at z = 20.3): rays below it miss, rays above keep
    // the whole chord of 32.
    RayCastOptions options;
    options.opacity_unit = unit;
    options.early_termination = 1.0;
    options.clip = ClipPlane{{0.0, 0.0, 20.3}, {0.0, 0.0, 2.0}};
    Image image;
    raycast(cube, nullptr, cam, options, image);
    const double full = 1.0 - std::pow(1.0 - RGBA[3], 32.0 / unit);
    for (int j = 0; j < 32; ++j) {
        const bool kept = 31.5 - j >= 20.3;
        const Color got = to_color(image.at(5, j));
        EXPECT_NEAR(got.r, kept ? RGBA[0] * full : 0.0, 2.0 / 255.0) << "row " << j;
    }
    // The whole volume behind the plane: the background.
    options.clip = ClipPlane{{40.0, 0.0, 0.0}, {1.0, 0.0, 0.0}};
    options.background = {0.2f, 0.4f, 0.6f};
    raycast(cube, nullptr, cam, options, image);
    EXPECT_EQ(image, Image(32, 32, to_rgb8(options.background)));
}

TEST(RayCast, ClipPlaneKeepsSkippingExact) {
    const Volume phantom = volume::shepp_logan_3d({40, 40, 40});
    const volume::TransferFunction tf = volume::preset("mri-brain", phantom);
    const Camera cam = frame_box(phantom.bounds(), -50.0, 35.0, 48, 40);
    RayCastOptions on;
    on.clip = ClipPlane{phantom.bounds().center(), {0.3, -1.0, 0.4}};
    on.shading = true;
    RayCastOptions off = on;
    off.empty_space_skipping = false;
    Image a, b, whole;
    raycast(phantom, &tf, cam, on, a);
    raycast(phantom, &tf, cam, off, b);
    EXPECT_EQ(a, b);
    on.clip.reset();
    raycast(phantom, &tf, cam, on, whole);
    EXPECT_GT(mean_abs_difference(a, whole), 0.003);  // the plane removed a visible part
    // set_clip on a prepared caster gives the same images as constructing with the plane.
    RayCaster caster(phantom, &tf, on);
    Image c;
    caster.set_clip(off.clip);
    caster.render(cam, c);
    EXPECT_EQ(c, a);
    caster.set_clip(std::nullopt);
    caster.render(cam, c);
    EXPECT_EQ(c, whole);
    EXPECT_THROW(caster.set_clip(ClipPlane{{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}}), InvalidInput);
}

TEST(RayCast, ErrorsNameTheArgument) {
    const Volume phantom = volume::shepp_logan_3d({8, 8, 8});
    const Camera cam = frame_box(phantom.bounds(), 0.0, 0.0, 8, 8);
    Image image;
    try {
        raycast(phantom, nullptr, cam, {}, image);
        FAIL() << "no throw";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("transfer function"), std::string::npos);
    }
    RayCastOptions bad;
    bad.step = -1.0;
    const volume::TransferFunction tf = volume::preset("grayscale", phantom);
    try {
        raycast(phantom, &tf, cam, bad, image);
        FAIL() << "no throw";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("options.step (-1)"), std::string::npos);
    }
    EXPECT_THROW(raycast(Volume{}, &tf, cam, {}, image), InvalidInput);
    RayCastOptions flat;
    flat.clip = ClipPlane{{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    try {
        raycast(phantom, &tf, cam, flat, image);
        FAIL() << "no throw";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("options.clip"), std::string::npos);
    }
}

}  // namespace
}  // namespace pliant::render
