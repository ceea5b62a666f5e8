#include "volume_session.hpp"

#include <gtest/gtest.h>

#include <thread>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/volume/clean.hpp"
#include "pliant/volume/generate.hpp"

namespace pliant::viewer {
namespace {

using volume::Volume;

const volume::Dims DIMS{32, 32, 32};

render::Camera camera_for(const Volume& v, int w = 48, int h = 40) {
    return render::frame_box(v.bounds(), 30.0, 20.0, w, h);
}

int differing_pixels(const render::Image& a, const render::Image& b) {
    int count = 0;
    for (std::size_t i = 0; i < a.pixels.size(); i += 3) {
        count += a.pixels[i] != b.pixels[i] || a.pixels[i + 1] != b.pixels[i + 1] ||
                         a.pixels[i + 2] != b.pixels[i + 2]
                     ? 1
                     : 0;
    }
    return count;
}

// With an opacity scale of 1 and no threshold the view is `pliant render`'s image; a scale s is
// the opacity unit divided by s; a threshold is volume::threshold_alpha on the transfer function.
TEST(VolumeSession, RendersWhatTheRayCasterRendersForTheSettings) {
    const Volume phantom = volume::shepp_logan_3d(DIMS);
    const render::Camera camera = camera_for(phantom);
    VolumeSession session(phantom, {.tf = "mri-brain"});
    render::Image view, expected;
    session.render(camera, view);
    const volume::TransferFunction tf = volume::preset("mri-brain", phantom);
    render::raycast(phantom, &tf, camera, {}, expected);
    EXPECT_EQ(view, expected);

    session.set_opacity_scale(4.0);
    session.render(camera, view);
    render::RayCastOptions denser;
    denser.opacity_unit = volume::smallest_spacing(phantom) / 4.0;
    render::raycast(phantom, &tf, camera, denser, expected);
    EXPECT_EQ(view, expected);

    session.set_opacity_scale(1.0);
    session.set_threshold(40.0);
    session.render(camera, view);
    const volume::TransferFunction cut = volume::threshold_alpha(tf, 40.0);
    render::raycast(phantom, &cut, camera, {}, expected);
    EXPECT_EQ(view, expected);
    render::Image unthresholded;
    render::raycast(phantom, &tf, camera, {}, unthresholded);
    EXPECT_GT(differing_pixels(view, unthresholded), 50);

    // A clipping plane, set on the prepared caster.
    session.set_threshold(0.0);
    const render::ClipPlane plane{phantom.bounds().center(), {-1.0, 0.2, 0.0}};
    session.set_clip(plane);
    session.render(camera, view);
    render::RayCastOptions clipped;
    clipped.clip = plane;
    render::raycast(phantom, &tf, camera, clipped, expected);
    EXPECT_EQ(view, expected);
    EXPECT_THROW(session.set_clip(render::ClipPlane{{0, 0, 0}, {0, 0, 0}}), InvalidInput);

    // Another preset and shading.
    session.set_clip(std::nullopt);
    session.set_transfer_function("grayscale");
    session.set_shading(true);
    session.render(camera, view);
    const volume::TransferFunction gray = volume::preset("grayscale", phantom);
    render::RayCastOptions shaded;
    shaded.shading = true;
    render::raycast(phantom, &gray, camera, shaded, expected);
    EXPECT_EQ(view, expected);
    EXPECT_THROW(session.set_transfer_function("/nonexistent/tf.json"), IoError);
}

TEST(VolumeSession, RgbaThresholdCleansTheVoxels) {
    const Volume object = volume::rgba_test_object(DIMS, volume::VoxelType::rgba8);
    const render::Camera camera = camera_for(object);
    VolumeSession session(object, {.threshold = 120.0});
    render::Image view, expected;
    session.render(camera, view);
    Volume cleaned = object;
    volume::threshold_alpha(cleaned, 120.0);
    render::raycast(cleaned, nullptr, camera, {}, expected);
    EXPECT_EQ(view, expected);
    // Back to no threshold: the original voxels again.
    session.set_threshold(0.0);
    session.set_opacity_scale(0.5);
    session.render(camera, view);
    render::RayCastOptions thinner;
    thinner.opacity_unit = volume::smallest_spacing(object) / 0.5;
    render::raycast(object, nullptr, camera, thinner, expected);
    EXPECT_EQ(view, expected);
}

TEST(VolumeSession, DeformsWithDriversAndDrag) {
    const Volume phantom = volume::shepp_logan_3d(DIMS);
    const render::Camera camera = camera_for(phantom, 96, 80);
    VolumeSessionOptions options{.tf = "mri-brain", .deform = true};
    options.grid.cell_voxels = 4;
    VolumeSession session(phantom, options);
    ASSERT_TRUE(session.is_deformable());
    render::Image rest, twisted;
    session.render(camera, rest);

    DriverSettings twist;
    twist.kind = DriverKind::twist;
    twist.twist.angle = 90.0;
    twist.twist.ramp_time = 0.25;
    session.set_driver(twist);
    const unsigned long long generation = session.generation();
    for (int f = 0; f < 8; ++f) {
        session.step();
    }
    EXPECT_GT(session.generation(), generation);
    EXPECT_NEAR(session.time(), 8.0 / 24.0, 1e-12);
    EXPECT_EQ(session.stats().inverted_tets, 0);
    session.render(camera, twisted);
    EXPECT_GT(differing_pixels(rest, twisted), 200);

    // Another kind restarts from rest; a parameter change keeps the time.
    DriverSettings bubble;
    bubble.kind = DriverKind::bubble;
    session.set_driver(bubble);
    EXPECT_EQ(session.time(), 0.0);
    session.step();
    bubble.bubble.inflation = 3.0;
    session.set_driver(bubble);
    EXPECT_NEAR(session.time(), 1.0 / 24.0, 1e-12);
    DriverSettings bad = bubble;
    bad.bubble.inflation = -1.0;
    EXPECT_THROW(session.set_driver(bad), InvalidInput);
    EXPECT_EQ(session.settings().driver.bubble.inflation, 3.0);  // kept the valid one

    // Drag: the vertex under the cursor follows it.
    session.set_driver(DriverSettings{});
    session.reset_deformation();
    const render::PixelPoint centre = camera.project(phantom.bounds().center());
    // Start at a point of the body's silhouette seen from the camera: the projected vertex
    // nearest to the camera close to the centre of the image.
    ASSERT_TRUE(session.begin_drag(camera, centre.x, centre.y));
    EXPECT_TRUE(session.is_dragging());
    const std::int32_t vertex = session.body()->drag()->vertex;
    session.drag(camera, centre.x + 10.0, centre.y);
    session.step();
    const Vec3f moved = session.body()->positions()[static_cast<std::size_t>(vertex)];
    EXPECT_NEAR(camera.project(vec3_cast<double>(moved)).x, centre.x + 10.0, 0.5);
    session.end_drag();
    EXPECT_FALSE(session.is_dragging());
    EXPECT_FALSE(session.body()->drag().has_value());
    EXPECT_FALSE(session.begin_drag(camera, 0.0, 0.0));  // nothing there

    session.set_stiffness(0.8);
    EXPECT_EQ(session.body()->options().stiffness, 0.8);
    EXPECT_THROW(session.set_stiffness(0.0), InvalidInput);
    EXPECT_THROW(session.set_drag_radius(-1.0), InvalidInput);
    // A new transfer function rebuilds the grid over what it shows.
    session.set_transfer_function("grayscale");
    EXPECT_EQ(session.time(), 0.0);
}

// In the background: while a frame is in flight the published volume is rendered (double
// buffering), and the published frames are those of step().
TEST(VolumeSession, BackgroundFramesPublishTheSameVolumes) {
    const Volume phantom = volume::shepp_logan_3d(DIMS);
    const render::Camera camera = camera_for(phantom, 64, 64);
    VolumeSessionOptions options{.tf = "mri-brain", .deform = true};
    options.driver.kind = DriverKind::twist;
    options.driver.twist.ramp_time = 0.2;
    VolumeSession background(phantom, options);
    VolumeSession foreground(phantom, options);
    render::Image before, during, after, expected;
    for (int f = 1; f <= 4; ++f) {
        background.render(camera, before);
        ASSERT_TRUE(background.start_step());
        EXPECT_TRUE(background.is_stepping());
        EXPECT_FALSE(background.start_step());
        background.render(camera, during);
        EXPECT_EQ(during, before);  // the frame in flight fills the other buffer
        while (!background.finish_step(false)) {
        }
        EXPECT_FALSE(background.is_stepping());
        foreground.step();
        background.render(camera, after);
        foreground.render(camera, expected);
        EXPECT_EQ(after, expected) << "frame " << f;
        EXPECT_EQ(background.time(), foreground.time());
    }
    EXPECT_NE(after, before);
    // Settings wait for a frame in flight.
    background.start_step();
    background.set_stiffness(0.9);
    EXPECT_FALSE(background.is_stepping());
    EXPECT_NEAR(background.time(), 5.0 / 24.0, 1e-12);
}

// A started frame runs on its own thread: it ends while every thread of the caller's parallel
// loop waits for it (a frame that waited for a worker taken by the loop would never end).
TEST(VolumeSession, StartedFramesRunBesideTheCallersLoops) {
    const Volume phantom = volume::shepp_logan_3d({16, 16, 16});
    VolumeSessionOptions options{.tf = "mri-brain", .deform = true};
    options.driver.kind = DriverKind::wave;
    VolumeSession session(phantom, options);
    set_num_threads(2);
    for (int f = 1; f <= 3; ++f) {
        ASSERT_TRUE(session.start_step());
        parallel_for(
            2,
            [&](std::int64_t) {
                while (!session.is_frame_done()) {
                    std::this_thread::yield();
                }
            },
            1);
        EXPECT_TRUE(session.finish_step(false)) << "frame " << f;
    }
    set_num_threads(0);
    EXPECT_NEAR(session.time(), 3.0 / 24.0, 1e-12);
}

// resample = map: the frames through their inverse maps, double-buffered like the resampled
// volumes (background frames = foreground frames), near the exact route's image; a clipping
// plane and shading reach the mapped caster.
TEST(VolumeSession, RendersThroughTheInverseMap) {
    const Volume phantom = volume::shepp_logan_3d(DIMS);
    const render::Camera camera = camera_for(phantom, 64, 64);
    VolumeSessionOptions options{.tf = "mri-brain", .deform = true};
    options.driver.kind = DriverKind::twist;
    options.driver.twist.ramp_time = 0.2;
    VolumeSession exact(phantom, options);
    options.resample = pipeline::ResampleMode::map;
    VolumeSession background(phantom, options);
    VolumeSession foreground(phantom, options);
    render::Image before, during, after, expected, exact_image;
    for (int f = 1; f <= 4; ++f) {
        background.render(camera, before);
        ASSERT_TRUE(background.start_step());
        background.render(camera, during);
        EXPECT_EQ(during, before);
        while (!background.finish_step(false)) {
        }
        foreground.step();
        exact.step();
        background.render(camera, after);
        foreground.render(camera, expected);
        EXPECT_EQ(after, expected) << "frame " << f;
    }
    EXPECT_NE(after, before);
    exact.render(camera, exact_image);
    EXPECT_LT(differing_pixels(exact_image, after), static_cast<int>(after.pixels.size() / 3));
    render::Image clipped, shaded;
    foreground.set_clip(render::ClipPlane{phantom.bounds().center(), {1.0, 0.0, 0.0}});
    foreground.render(camera, clipped);
    EXPECT_GT(differing_pixels(clipped, after), 100);
    foreground.set_shading(true);
    foreground.render(camera, shaded);
    EXPECT_GT(differing_pixels(shaded, clipped), 100);
}

// The phantom under mri-brain (threshold 60), twisting, shown through the inverse map.
VolumeSessionOptions twisting_through_the_map() {
    VolumeSessionOptions options{.tf = "mri-brain", .threshold = 60.0, .deform = true};
    options.driver.kind = DriverKind::twist;
    options.driver.twist.ramp_time = 0.2;
    options.resample = pipeline::ResampleMode::map;
    return options;
}

// resample = map: a frame computes its map's state (the occupancy) on its own thread with the
// caster, and the render installs it: the images and sample counts of a session stepping on the
// caller. A caster rebuilt while the frame is in flight (the threshold lowered: more of the
// volume seen) does not take the state made with the old one (it computes its own).
TEST(VolumeSession, FramesComputeTheMapStateForTheirCaster) {
    const Volume phantom = volume::shepp_logan_3d(DIMS);
    const render::Camera camera = camera_for(phantom, 64, 64);
    VolumeSessionOptions options = twisting_through_the_map();
    options.map_state = MapStatePlacement::frame;
    VolumeSession background(phantom, options);
    VolumeSession foreground(phantom, options);
    render::Image a, b;
    for (int f = 1; f <= 3; ++f) {
        background.render(camera, a);
        foreground.render(camera, b);
        ASSERT_TRUE(background.start_step());
        while (!background.finish_step(false)) {
        }
        foreground.step();
    }
    // The last frames began with a caster: their states were computed beside the render.
    EXPECT_GT(background.stats().occupancy_ms, 0.0);
    EXPECT_GT(foreground.stats().occupancy_ms, 0.0);
    const render::RayCastStats sa = background.render(camera, a);
    const render::RayCastStats sb = foreground.render(camera, b);
    EXPECT_EQ(a, b);
    EXPECT_EQ(sa.samples, sb.samples);
    EXPECT_GT(sb.samples, 0);
    // The caster rebuilt (render) while the frame computes its state with the old one.
    ASSERT_TRUE(background.start_step());
    background.set_threshold(0.0);
    background.render(camera, a);
    while (!background.finish_step(false)) {
    }
    foreground.set_threshold(0.0);
    foreground.step();
    EXPECT_EQ(foreground.stats().occupancy_ms, 0.0);  // no caster to compute it with
    render::Image lowered_a, lowered_b;
    const render::RayCastStats la = background.render(camera, lowered_a);
    const render::RayCastStats lb = foreground.render(camera, lowered_b);
    EXPECT_EQ(lowered_a, lowered_b);
    EXPECT_EQ(la.samples, lb.samples);
    EXPECT_GT(la.samples, sb.samples);  // the lowered threshold shows more
    EXPECT_GT(differing_pixels(lowered_b, b), 0);
}

// MapStatePlacement::balanced: a frame computes the map state only when the last frame's step,
// map and state took less than the last render; before any render (0 ms) the render computes
// it. The images are those of MapStatePlacement::frame.
TEST(VolumeSession, BalancedMapStateKeepsTheImages) {
    const Volume phantom = volume::shepp_logan_3d(DIMS);
    const render::Camera camera = camera_for(phantom, 64, 64);
    VolumeSessionOptions options = twisting_through_the_map();
    VolumeSession balanced(phantom, options);
    options.map_state = MapStatePlacement::frame;
    VolumeSession frame(phantom, options);
    ASSERT_TRUE(balanced.start_step());  // no render yet: no time to hide the state behind
    balanced.finish_step(true);
    EXPECT_EQ(balanced.stats().occupancy_ms, 0.0);
    ASSERT_TRUE(frame.start_step());
    frame.finish_step(true);
    render::Image a, b;
    for (int f = 1; f <= 3; ++f) {
        const render::RayCastStats sa = balanced.render(camera, a);
        const render::RayCastStats sb = frame.render(camera, b);
        ASSERT_EQ(a, b) << "frame " << f;
        ASSERT_EQ(sa.samples, sb.samples);
        ASSERT_TRUE(balanced.start_step());
        balanced.finish_step(true);
        ASSERT_TRUE(frame.start_step());
        frame.finish_step(true);
    }
}

TEST(VolumeSession, ErrorsNameTheProblem) {
    const Volume phantom = volume::shepp_logan_3d({8, 8, 8});
    EXPECT_THROW(VolumeSession(phantom, {.opacity_scale = 0.0}), InvalidInput);
    EXPECT_THROW(VolumeSession(phantom, {.threshold = 300.0}), InvalidInput);
    EXPECT_THROW(VolumeSession(Volume{}, {}), InvalidInput);
    EXPECT_THROW(VolumeSession(phantom, {.tf = "no-such-preset"}), IoError);
    VolumeSession still(phantom, {});
    EXPECT_FALSE(still.is_deformable());
    EXPECT_THROW(still.step(), InvalidInput);
    EXPECT_THROW(still.set_driver({}), InvalidInput);
    EXPECT_THROW(still.set_stiffness(0.9), InvalidInput);
    EXPECT_THROW(still.reset_deformation(), InvalidInput);
    EXPECT_FALSE(still.begin_drag(camera_for(phantom), 4.0, 4.0));
    try {
        still.set_opacity_scale(-2.0);
        FAIL() << "no throw";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("opacity scale -2"), std::string::npos);
    }
    EXPECT_EQ(parse_driver_kind("twist"), DriverKind::twist);
    EXPECT_STREQ(driver_kind_name(DriverKind::bubble), "bubble");
    EXPECT_THROW(parse_driver_kind("spin"), InvalidInput);
    // Nothing visible to deform.
    const Volume empty = Volume::allocate({8, 8, 8}, volume::VoxelType::u8);
    EXPECT_THROW(VolumeSession(empty, {.deform = true}), InvalidInput);
}

}  // namespace
}  // namespace pliant::viewer
