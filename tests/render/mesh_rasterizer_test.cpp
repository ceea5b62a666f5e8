#include "pliant/render/mesh_rasterizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::render {
namespace {

using geometry::Triangle;
using geometry::TriangleMeshD;

// Coverage of the last render as 0/1 per sample.
std::vector<int> coverage(const MeshRasterizer& r) {
    std::vector<int> c;
    for (const std::uint32_t id : r.sample_triangles()) {
        c.push_back(id != MeshRasterizer::NO_TRIANGLE ? 1 : 0);
    }
    return c;
}

RasterOptions one_sample() {
    RasterOptions o;
    o.samples_per_axis = 1;
    return o;
}

// Orthographic camera looking down −z with 1 world unit = 1 pixel: world (x, y) lands on pixel
// coordinates (W/2 + x, H/2 − y) exactly.
Camera unit_ortho(int w, int h) {
    return Camera::orthographic({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, static_cast<double>(h), w, h);
}

TEST(MeshRasterizer, SingleTriangleMatchesPixelCentreInsideTest) {
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> coord(-1.2, 1.2);
    const Camera cam = Camera::perspective({0.3, -4, 2.5}, {0, 0, 0}, {0, 0, 1}, 40.0, 97, 71);
    MeshRasterizer r;
    int compared = 0, skipped = 0;
    for (int trial = 0; trial < 20; ++trial) {
        const std::vector<Vec3d> p = {{coord(rng), coord(rng), coord(rng)},
                                      {coord(rng), coord(rng), coord(rng)},
                                      {coord(rng), coord(rng), coord(rng)}};
        const std::vector<Triangle> t = {{0, 1, 2}};
        const RenderMesh mesh{p, t, {}};
        Image image;
        r.render(cam, {&mesh, 1}, one_sample(), image);
        const std::vector<int> cov = coverage(r);
        // Independent reference: signed distances of the pixel centre to the projected edges.
        const PixelPoint q[3] = {cam.project(p[0]), cam.project(p[1]), cam.project(p[2])};
        for (int j = 0; j < cam.height(); ++j) {
            for (int i = 0; i < cam.width(); ++i) {
                const double x = i + 0.5, y = j + 0.5;
                double d[3];
                double min_abs = 1e300;
                for (int k = 0; k < 3; ++k) {
                    const PixelPoint& a = q[k];
                    const PixelPoint& b = q[(k + 1) % 3];
                    const double len = std::hypot(b.x - a.x, b.y - a.y);
                    d[k] = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / len;
                    min_abs = std::min(min_abs, std::abs(d[k]));
                }
                if (min_abs < 1e-3) {  // within snapping distance of an edge: ambiguous
                    ++skipped;
                    continue;
                }
                const bool inside =
                    (d[0] > 0 && d[1] > 0 && d[2] > 0) || (d[0] < 0 && d[1] < 0 && d[2] < 0);
                ASSERT_EQ(cov[static_cast<std::size_t>(j * cam.width() + i)], inside ? 1 : 0)
                    << "trial " << trial << " pixel " << i << "," << j;
                compared += inside ? 1 : 0;
            }
        }
    }
    EXPECT_GT(compared, 2000);
    EXPECT_LT(skipped, 20);
}

TEST(MeshRasterizer, TwoTrianglesCoverASquareExactlyOnce) {
    // Square corners and its diagonal pass exactly through pixel centres: the fill rule decides.
    const Camera cam = unit_ortho(64, 48);
    const std::vector<Vec3d> p = {
        {-10.5, -8.5, 0}, {9.5, -8.5, 0}, {9.5, 11.5, 0}, {-10.5, 11.5, 0}};
    const std::vector<Triangle> a = {{0, 1, 2}}, b = {{0, 2, 3}}, both = {{0, 1, 2}, {0, 2, 3}};
    MeshRasterizer r;
    Image image;
    const auto run = [&](const std::vector<Triangle>& t) {
        const RenderMesh mesh{p, t, {}};
        r.render(cam, {&mesh, 1}, one_sample(), image);
        return coverage(r);
    };
    const std::vector<int> ca = run(a), cb = run(b), cab = run(both);
    // Pixel x of world x: 32 + x; pixel y of world y: 24 − y. Square: x ∈ [21.5, 41.5],
    // y ∈ [12.5, 32.5]. Top-left rule: left and top edges in, right and bottom edges out.
    int covered = 0;
    for (int j = 0; j < 48; ++j) {
        for (int i = 0; i < 64; ++i) {
            const auto s = static_cast<std::size_t>(j * 64 + i);
            const bool expected =
                i + 0.5 >= 21.5 && i + 0.5 < 41.5 && j + 0.5 >= 12.5 && j + 0.5 < 32.5;
            ASSERT_LE(ca[s] + cb[s], 1) << "double coverage at " << i << "," << j;
            ASSERT_EQ(ca[s] + cb[s], expected ? 1 : 0) << "pixel " << i << "," << j;
            ASSERT_EQ(cab[s], expected ? 1 : 0);
            covered += cab[s];
        }
    }
    EXPECT_EQ(covered, 20 * 20);
}

TEST(MeshRasterizer, FanOfTrianglesHasNoCracksAndNoOverlapAtAnySampleRate) {
    // A star-shaped fan around an off-grid centre under a perspective camera: arbitrary edge
    // positions, each sample covered by exactly one triangle of the fan or by none.
    const Camera cam = Camera::perspective({0.2, -3, 2}, {0, 0, 0}, {0, 0, 1}, 45.0, 57, 43);
    std::vector<Vec3d> p = {{0.0123, -0.0271, 0.05}};
    const int n = 13;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> radius(0.4, 1.1);
    for (int k = 0; k < n; ++k) {
        const double a = 2.0 * std::numbers::pi * k / n;
        const double rr = radius(rng);
        p.push_back({rr * std::cos(a), rr * std::sin(a), 0.1 * std::sin(3 * a)});
    }
    std::vector<Triangle> all;
    for (int k = 0; k < n; ++k) {
        all.push_back({0, 1 + k, 1 + (k + 1) % n});
    }
    for (const int s : {1, 2, 3}) {
        RasterOptions o;
        o.samples_per_axis = s;
        MeshRasterizer r;
        Image image;
        const RenderMesh whole{p, all, {}};
        r.render(cam, {&whole, 1}, o, image);
        const std::vector<int> union_cov = coverage(r);
        std::vector<int> sum(union_cov.size(), 0);
        for (int k = 0; k < n; ++k) {
            const std::vector<Triangle> one = {all[static_cast<std::size_t>(k)]};
            const RenderMesh mesh{p, one, {}};
            r.render(cam, {&mesh, 1}, o, image);
            const std::vector<int> c = coverage(r);
            for (std::size_t i = 0; i < c.size(); ++i) {
                sum[i] += c[i];
            }
        }
        int covered = 0;
        for (std::size_t i = 0; i < sum.size(); ++i) {
            ASSERT_LE(sum[i], 1) << "sample " << i << " covered twice, s = " << s;
            ASSERT_EQ(sum[i], union_cov[i]) << "sample " << i << ", s = " << s;
            covered += sum[i];
        }
        EXPECT_GT(covered, 100 * s * s);
    }
}

TEST(MeshRasterizer, NearerTriangleWinsInEitherOrder) {
    const Camera cam = Camera::perspective({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 50.0, 40, 40);
    const std::vector<Vec3d> near_p = {{-1, -1, 0.5}, {1, -1, 0.5}, {0, 1, 0.5}};
    const std::vector<Vec3d> far_p = {{-1, 1, -0.5}, {0, -1, -0.5}, {1, 1, -0.5}};
    const std::vector<Triangle> t = {{0, 1, 2}};
    const RenderMesh near_mesh{near_p, t, {1, 0, 0}}, far_mesh{far_p, t, {0, 0, 1}};
    for (const bool near_first : {true, false}) {
        const std::vector<RenderMesh> meshes =
            near_first ? std::vector{near_mesh, far_mesh} : std::vector{far_mesh, near_mesh};
        MeshRasterizer r;
        Image image;
        r.render(cam, meshes, one_sample(), image);
        const std::uint32_t id = r.sample_triangles()[20 * 40 + 20];
        ASSERT_NE(id, MeshRasterizer::NO_TRIANGLE);
        EXPECT_EQ(r.source_of(id).mesh, near_first ? 0 : 1);
        const Rgb8 c = image.at(20, 20);
        EXPECT_GT(c.r, 0);
        EXPECT_EQ(c.b, 0);  // the blue far triangle is hidden
    }
}

TEST(MeshRasterizer, NearPlaneClippingDrawsTheGroundUpToTheHorizon) {
    // A ground square reaching far behind the camera, seen from just above it: without clipping,
    // vertices behind the eye would project mirrored into the sky.
    const TriangleMeshD ground = geometry::make_plane_square({0, 0, 0}, {0, 0, 1}, 50.0);
    const Camera cam = Camera::perspective({0, 0, 1}, {0, 10, 0.2}, {0, 0, 1}, 60.0, 80, 60);
    MeshRasterizer r;
    Image image;
    const RenderMesh mesh{ground.positions, ground.triangles, {0.5f, 0.7f, 0.5f}};
    r.render(cam, {&mesh, 1}, one_sample(), image);
    EXPECT_GT(r.stats().clipped_triangles, 0);
    const std::vector<int> cov = coverage(r);
    int checked = 0;
    for (int j = 0; j < 60; ++j) {
        for (int i = 0; i < 80; ++i) {
            const Ray ray = cam.pixel_ray(i, j);
            bool hits = false;
            double margin = 1.0;
            if (ray.direction.z < 0) {
                const double t = -ray.origin.z / ray.direction.z;
                const Vec3d h = ray.origin + t * ray.direction;
                hits = std::abs(h.x) < 50 && std::abs(h.y) < 50;
                margin = std::min(50 - std::abs(h.x), 50 - std::abs(h.y));
            }
            if (std::abs(margin) < 0.5 || std::abs(ray.direction.z) < 1e-3) {
                continue;  // at the square's far edge or the horizon
            }
            ASSERT_EQ(cov[static_cast<std::size_t>(j * 80 + i)], hits ? 1 : 0) << i << "," << j;
            ++checked;
        }
    }
    EXPECT_GT(checked, 4000);
}

TEST(MeshRasterizer, TriangleBehindTheCameraIsNotDrawn) {
    const Camera cam = Camera::perspective({0, 0, 0}, {0, 1, 0}, {0, 0, 1}, 60.0, 32, 32);
    const std::vector<Vec3d> p = {{-1, -2, -1}, {1, -2, -1}, {0, -2, 1}};  // behind the eye
    const std::vector<Triangle> t = {{0, 1, 2}};
    MeshRasterizer r;
    Image image;
    const RenderMesh mesh{p, t, {}};
    r.render(cam, {&mesh, 1}, {}, image);
    EXPECT_EQ(r.stats().culled_triangles, 1);
    EXPECT_EQ(image, Image(32, 32, Rgb8{255, 255, 255}));
}

TEST(MeshRasterizer, DegenerateTrianglesAreSkippedAndCounted) {
    const Camera cam = unit_ortho(32, 32);
    const std::vector<Vec3d> p = {{-5, -5, 0}, {5, -5, 0}, {0, 5, 0}, {10, 10, 0}, {-5, 5, 0}};
    // Two repeat a vertex, two are proper triangles.
    const std::vector<Triangle> t = {{0, 0, 1}, {0, 1, 3}, {4, 4, 4}, {0, 2, 3}};
    // Collinear corners, in both orders.
    const std::vector<Vec3d> q = {{-5, -5, 0}, {0, 0, 0}, {5, 5, 0}};
    const std::vector<Triangle> tq = {{0, 1, 2}, {2, 1, 0}};
    MeshRasterizer r;
    Image image;
    const RenderMesh meshes[] = {{p, t, {}}, {q, tq, {}}};
    r.render(cam, meshes, {}, image);
    EXPECT_EQ(r.stats().triangles, 6);
    EXPECT_EQ(r.stats().degenerate_triangles, 4);
    EXPECT_EQ(r.stats().drawn_triangles, 2);
}

TEST(MeshRasterizer, BackFacesAreTintedAndFrontFacesLit) {
    const std::vector<Vec3d> p = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};  // normal +z
    const std::vector<Triangle> t = {{0, 1, 2}};
    const RenderMesh mesh{p, t, {0.6f, 0.6f, 0.6f}};
    const Camera above = Camera::perspective({0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 45.0, 32, 32);
    const Camera below = Camera::perspective({0, 0, -4}, {0, 0, 0}, {0, 1, 0}, 45.0, 32, 32);
    const Image front = render_meshes(above, {&mesh, 1});
    const Image back = render_meshes(below, {&mesh, 1});
    const Rgb8 f = front.at(16, 16), b = back.at(16, 16);
    EXPECT_EQ(f.r, f.g);  // grey base stays grey
    EXPECT_EQ(f.g, f.b);
    EXPECT_GT(b.r, b.b + 40);  // back faces take the warm tint
    EXPECT_GT(f.r, 60);
    // Background where nothing is drawn; an anti-aliased edge pixel lies between.
    EXPECT_EQ(front.at(0, 0), (Rgb8{255, 255, 255}));
}

TEST(MeshRasterizer, ThreadsDoNotChangeTheImage) {
    // The drape scene's sheet folded onto itself, over a sphere, in one frame.
    geometry::TriangleMesh sheet = geometry::make_grid_sheet(134, 134, 2.0f, 2.0f);
    geometry::fold_accordion(sheet.positions, 0.3f, 0.02f);
    std::vector<Vec3d> cloth;
    for (const Vec3f& v : sheet.positions) {
        cloth.push_back({v.x - 0.5, v.y, v.z + 0.2 * std::sin(3.0 * v.y)});
    }
    const TriangleMeshD sphere = geometry::make_uv_sphere({0, 0, -0.6}, 0.5, 48);
    const RenderMesh meshes[] = {{cloth, sheet.triangles, {0.3f, 0.5f, 0.8f}},
                                 {sphere.positions, sphere.triangles, {0.7f, 0.7f, 0.7f}}};
    const Camera cam = frame_box({{-1.5, -1, -1.1}, {1.5, 1, 0.5}}, 30.0, 25.0, 160, 120);
    const auto run = [&](int threads) {
        set_num_threads(threads);
        MeshRasterizer r;
        Image image;
        r.render(cam, meshes, {}, image);
        return std::pair{image, std::vector<std::uint32_t>(r.sample_triangles().begin(),
                                                           r.sample_triangles().end())};
    };
    const auto one = run(1);
    const auto two = run(2);
    set_num_threads(0);
    EXPECT_EQ(one.first, two.first);
    EXPECT_EQ(one.second, two.second);
    // Something was drawn, including back faces of the folds.
    int non_background = 0;
    for (int j = 0; j < 120; ++j) {
        for (int i = 0; i < 160; ++i) {
            non_background += one.first.at(i, j) != Rgb8{255, 255, 255} ? 1 : 0;
        }
    }
    EXPECT_GT(non_background, 500);
}

TEST(MeshRasterizer, RejectsBadInput) {
    const Camera cam = unit_ortho(16, 16);
    std::vector<Vec3d> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<Triangle> good = {{0, 1, 2}}, bad = {{0, 1, 3}};
    MeshRasterizer r;
    Image image;
    {
        const RenderMesh meshes[] = {{p, good, {}}, {p, bad, {}}};
        try {
            r.render(cam, meshes, {}, image);
            FAIL();
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("meshes[1].triangles: triangle 0 corner 2"),
                      std::string::npos)
                << e.what();
        }
    }
    p[1].y = NAN;
    {
        const RenderMesh mesh{p, good, {}};
        try {
            r.render(cam, {&mesh, 1}, {}, image);
            FAIL();
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("meshes[0].positions: vertex 1"),
                      std::string::npos)
                << e.what();
        }
    }
    p[1].y = 0;
    const RenderMesh mesh{p, good, {}};
    RasterOptions o;
    o.samples_per_axis = 0;
    EXPECT_THROW(r.render(cam, {&mesh, 1}, o, image), InvalidInput);
    o = {};
    o.back_tint_weight = 2.0f;
    EXPECT_THROW(r.render(cam, {&mesh, 1}, o, image), InvalidInput);
    o = {};
    o.key_direction = {0, 0, 0};
    EXPECT_THROW(r.render(cam, {&mesh, 1}, o, image), InvalidInput);
    // Nothing to draw is fine: the background.
    const Image empty = render_meshes(cam, {});
    EXPECT_EQ(empty, Image(16, 16, Rgb8{255, 255, 255}));
}

}  // namespace
}  // namespace pliant::render
