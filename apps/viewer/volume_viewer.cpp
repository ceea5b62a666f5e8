// `pliant view volume`: the library's ray caster shown live (viewer.hpp).
//
// Per frame: events → camera gestures and (with --deform) dragging → the deformation (a frame
// ahead in the background, below) → ray casting when the image would change, at 1 / preview_divisor
// of the resolution while the user interacts and at full resolution otherwise → the image drawn
// over the window → screenshot (last frame) → overlay → swap. A view that does not change is not
// ray-cast again, and an idle window waits for events.
#include <algorithm>
#include <array>
#include <optional>

#include "frame_clock.hpp"
#include "gl.hpp"
#include "image_drawer.hpp"
#include "mouse.hpp"
#include "orbit_controller.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/volume_io.hpp"
#include "screenshot.hpp"
#include "view_summary.hpp"
#include "viewer.hpp"
#include "volume_panel.hpp"
#include "volume_session.hpp"
#include "window.hpp"

namespace pliant::viewer {
namespace {

// Seconds after the last wheel notch during which frames are still previews.
constexpr double SCROLL_PREVIEW_SECONDS = 0.25;

}  // namespace

nlohmann::ordered_json run_volume_view(const std::filesystem::path& volume_path,
                                       const VolumeViewOptions& options) {
    if (options.preview_divisor < 1) {
        throw InvalidInput("viewer: the preview divisor must be >= 1");
    }
    io::ReadVolumeOptions read;
    read.max_bytes = static_cast<std::size_t>(options.max_memory_mib * 1024.0 * 1024.0);
    // An oblique volume is shown as it lies (the ray caster works in world space); --deform
    // resamples it onto an axis-aligned grid first, as `pliant deform` does (its tet grid and
    // drivers are built on the axis-aligned box).
    read.orientation = options.session.deform || options.axis_aligned
                           ? io::Orientation::axis_aligned
                           : io::Orientation::keep;
    VolumeSession session(io::read_volume(volume_path, read), options.session);
    const ViewRunOptions& run = options.run;
    // The overlay is a panel docked at the window's left; the image has the requested size
    // beside it.
    const int panel = run.window.show_ui ? VOLUME_PANEL_WIDTH : 0;
    WindowOptions window_options = run.window;
    window_options.width += panel;
    Window window("pliant view volume: " + volume_path.string(), window_options);

    ImageDrawer drawer;
    int window_width = 0, height = 0;
    window.framebuffer_size(window_width, height);
    int width = std::max(1, window_width - panel);  // the image's viewport
    const AABBd box = session.source().world_bounds();
    OrbitController controller(box, run.azimuth, run.elevation, run.distance, width, height);

    VolumeViewState state;
    state.paused = run.paused;
    state.title = volume_path.filename().string();
    state.renderer = window.gl_renderer();
    if (options.session.clip) {
        clip_fields_from_plane(*options.session.clip, box, state);
    } else {
        state.clip_azimuth = 0.0f;  // default plane when enabled: normal +x through the centre
    }
    MouseTracker mouse_tracker;
    KeyTracker key_tracker;
    FrameClock clock;
    Stopwatch since_scroll;
    bool scrolled = false;
    Mean step_ms, resample_ms, occupancy_ms, prepare_ms, render_ms;
    // The main thread's share of a frame: the wait for the deformed frame in flight, the image's
    // texture upload, the drawing (image and overlay) and the buffer swap.
    Mean wait_ms, upload_ms, draw_ms, swap_ms;
    std::int64_t full_frames = 0, preview_frames = 0;
    bool dragging = false;
    render::Image image;
    // What the current image shows: session and view generations, size, divisor.
    std::array<unsigned long long, 5> shown{~0ull, ~0ull, 0, 0, 0};
    std::optional<render::Camera> last_camera;
    bool rendered = true;

    for (int frame = 0; !window.should_close() && (run.frames <= 0 || frame < run.frames);
         ++frame) {
        const bool animating = session.is_deformable() && (!state.paused || session.is_stepping());
        const bool idle =
            run.frames <= 0 && !animating && !dragging && !rendered &&
            !(scrolled && since_scroll.elapsed_ms() < 1000.0 * SCROLL_PREVIEW_SECONDS);
        window.poll_events(idle ? SCROLL_PREVIEW_SECONDS : 0.0);
        window.framebuffer_size(window_width, height);
        width = window_width - panel;
        if (width < 1 || height < 1) {
            continue;
        }
        MouseFrame mouse = mouse_tracker.update(window);
        mouse.x -= panel;  // viewport coordinates
        const KeyFrame keys = key_tracker.update(window);
        if (keys.escape) {
            window.request_close();
        }
        if (mouse.scroll != 0.0) {
            scrolled = true;
            since_scroll.restart();
        }
        const render::Camera before = controller.camera(width, height);
        if (session.is_deformable()) {
            state.paused = keys.space ? !state.paused : state.paused;
            state.step_requested = state.step_requested || keys.n;
            if (keys.r) {
                session.reset_deformation();
            }
            if (mouse.pressed[0] && !mouse.shift) {
                dragging = session.begin_drag(before, mouse.x, mouse.y);
            }
            if (dragging && (mouse.released[0] || !mouse.held[0])) {
                session.end_drag();
                dragging = false;
            }
        }
        apply_camera_gestures(mouse, !dragging, height, controller);
        if (keys.c || state.reset_camera) {
            controller.reset();
            state.reset_camera = false;
        }
        if (dragging) {
            session.drag(controller.camera(width, height), mouse.x, mouse.y);
        }
        // The deformation runs a frame ahead in the background (as the cloth view's): without
        // input a frame waits for (and helps compute) the next deformed volume, with input the
        // view is redrawn at once; --sync: one deformed frame per drawn frame, in turn.
        if (session.is_deformable()) {
            const bool input = mouse.any_activity() || keys.any() || window.ui_is_active();
            const auto on_published = [&] {
                step_ms.add(session.stats().step_ms);
                resample_ms.add(session.stats().resample_ms);
                occupancy_ms.add(session.stats().occupancy_ms);
            };
            const Stopwatch waiting;
            const bool published =
                session.is_stepping() && session.finish_step(run.sync || (!input && !state.paused));
            if (published) {
                wait_ms.add(waiting.elapsed_ms());
                on_published();
            }
            if (!session.is_stepping() && (!state.paused || state.step_requested)) {
                session.start_step();
                state.step_requested = false;
                if (run.sync && session.finish_step(true)) {
                    on_published();
                }
            }
        }

        // Ray casting, when the image would change.
        const bool interacting =
            mouse.any_held() || window.ui_is_active() ||
            (scrolled && since_scroll.elapsed_ms() < 1000.0 * SCROLL_PREVIEW_SECONDS);
        const int divisor = interacting ? options.preview_divisor : 1;
        const int w = std::max(1, width / divisor), h = std::max(1, height / divisor);
        const std::array<unsigned long long, 5> wanted{
            session.generation(), controller.generation(), static_cast<unsigned long long>(w),
            static_cast<unsigned long long>(h), static_cast<unsigned long long>(divisor)};
        rendered = wanted != shown;
        if (rendered) {
            const render::Camera camera = controller.camera(w, h);
            session.render(camera, image);
            const Stopwatch uploading;
            drawer.upload(image);
            upload_ms.add(uploading.elapsed_ms());
            shown = wanted;
            render_ms.add(session.stats().render_ms);
            if (session.stats().prepared) {
                prepare_ms.add(session.stats().prepare_ms);
            }
            (divisor == 1 ? full_frames : preview_frames) += 1;
            state.image_width = w;
            state.image_height = h;
            state.preview = divisor > 1;
            if (divisor == 1) {
                last_camera = camera;
            }
        }
        const Stopwatch drawing;
        glViewport(0, 0, window_width, height);
        glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT);
        drawer.draw(panel, 0, width, height);
        const bool last = run.frames > 0 && frame + 1 == run.frames;
        if (last && !run.screenshot.empty()) {
            save_screenshot(run.screenshot, panel, 0, width, height);
        }
        if (window.has_ui()) {
            window.begin_ui_frame();
            draw_volume_panel(session, state, clock, height);
            window.end_ui_frame();
        }
        check_gl("volume frame");
        draw_ms.add(drawing.elapsed_ms());
        const Stopwatch swapping;
        window.swap_buffers();
        swap_ms.add(swapping.elapsed_ms());
        clock.tick();
    }

    nlohmann::ordered_json result;
    result["view"] = "volume";
    result["volume"] = volume_path.string();
    const volume::Dims& dims = session.source().dims();
    result["dims"] = {dims[0], dims[1], dims[2]};
    result["deform"] = session.is_deformable();
    result["driver"] = driver_kind_name(session.settings().driver.kind);
    if (const pbd::SoftBody* body = session.body()) {
        result["tets"] = body->tets().size();  // fixed topology: safe during a frame in flight
        result["vertices"] = body->rest_positions().size();
        result["simulated_seconds"] = session.time();  // of the last frame shown
        result["sync"] = run.sync;
    }
    result["full_resolution_images"] = full_frames;
    result["preview_images"] = preview_frames;
    add_run_summary(result, clock, run, window, last_camera);
    result["mean_step_ms"] = step_ms.value();
    result["mean_resample_ms"] = resample_ms.value();
    result["mean_occupancy_ms"] = occupancy_ms.value();
    result["mean_prepare_ms"] = prepare_ms.value();
    result["mean_render_ms"] = render_ms.value();
    result["mean_wait_ms"] = wait_ms.value();
    result["mean_upload_ms"] = upload_ms.value();
    result["mean_draw_ms"] = draw_ms.value();
    result["mean_swap_ms"] = swap_ms.value();
    return result;
}

}  // namespace pliant::viewer
