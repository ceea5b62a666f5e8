// `pliant view cloth`: the cloth simulation live, drawn with OpenGL (viewer.hpp).
//
// Per frame: events → camera gestures and grabbing → the simulation (below) → draw obstacles at
// their pose and the cloth with fresh normals (mesh_drawer.hpp) → screenshot (last frame) →
// overlay → swap.
//
// The simulation runs a frame ahead in the background (ClothSession::start_advance): while the
// user moves the camera or the cloth the window is redrawn at once with the latest simulated
// frame, whatever a step costs; without input a frame waits for the next simulated frame (the
// waiting thread helps compute it), so the drawing of frame k overlaps the simulation of frame
// k + 1. --sync instead simulates one frame per drawn frame, in turn.
#include <algorithm>
#include <optional>
#include <vector>

#include "cloth_panel.hpp"
#include "cloth_session.hpp"
#include "frame_clock.hpp"
#include "gl.hpp"
#include "mesh_drawer.hpp"
#include "mouse.hpp"
#include "orbit_controller.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/pipeline/cloth_look.hpp"
#include "screenshot.hpp"
#include "view_summary.hpp"
#include "viewer.hpp"
#include "window.hpp"

namespace pliant::viewer {

nlohmann::ordered_json run_cloth_view(const cloth::ClothScene& scene, const std::string& scene_name,
                                      const ClothViewOptions& options) {
    ClothSession session(scene, scene_name, options.session);
    const ViewRunOptions& run = options.run;
    Window window("pliant view cloth: " + scene_name, run.window);

    MeshDrawer drawer;
    MeshBuffers cloth_buffers;
    std::vector<MeshBuffers> obstacle_buffers(session.setup().shapes.size());
    std::vector<Vec3d> animated_positions;  // a deforming obstacle's, per drawn frame
    for (std::size_t k = 0; k < obstacle_buffers.size(); ++k) {
        const pipeline::ObstacleShape& shape = session.setup().shapes[k];
        obstacle_buffers[k].upload(shape.rest.positions, shape.rest.triangles, shape.smooth);
    }
    int width = 0, height = 0;
    window.framebuffer_size(width, height);
    OrbitController controller(session.framing_box(), run.azimuth, run.elevation, run.distance,
                               width, height);
    const AABBd& scene_box = session.scene_box();
    const Vec3d scene_centre = scene_box.center();
    const double scene_radius = 0.5 * norm(scene_box.extent());
    const render::RasterOptions look = pipeline::cloth_raster_options();

    ClothViewState state;
    state.paused = run.paused;
    state.title = scene_name;
    state.renderer = window.gl_renderer();
    MouseTracker mouse_tracker;
    KeyTracker key_tracker;
    FrameClock clock;
    Mean step_ms, draw_ms, solve_ms, refit_ms, traverse_ms, narrow_ms, response_ms;
    std::int64_t max_intersections = 0;
    bool grabbing = false;
    bool cloth_changed = true;
    FrameClock sim_clock;  // ticks when a simulated frame is published
    std::optional<render::Camera> last_camera;
    const Stopwatch run_clock;

    for (int frame = 0; !window.should_close() && (run.frames <= 0 || frame < run.frames);
         ++frame) {
        // Events: an idle, paused view waits for them instead of spinning.
        const bool idle = run.frames <= 0 && state.paused && !grabbing && !session.is_advancing();
        window.poll_events(idle ? 0.1 : 0.0);
        window.framebuffer_size(width, height);
        if (width < 1 || height < 1) {
            continue;  // minimised
        }
        const render::Camera before = controller.camera(width, height);
        const MouseFrame mouse = mouse_tracker.update(window);
        const KeyFrame keys = key_tracker.update(window);
        if (keys.escape) {
            window.request_close();
        }
        state.paused = keys.space ? !state.paused : state.paused;
        state.step_requested = state.step_requested || keys.n;
        state.reset_requested = state.reset_requested || keys.r;
        state.reset_camera = state.reset_camera || keys.c;

        // Grabbing: a left press on the cloth grabs the vertex under the cursor; elsewhere (or
        // with Shift) the left button orbits.
        if (mouse.pressed[0] && !mouse.shift) {
            grabbing = session.begin_grab(before, mouse.x, mouse.y);
        }
        if (grabbing && (mouse.released[0] || !mouse.held[0])) {
            session.end_grab();
            grabbing = false;
        }
        apply_camera_gestures(mouse, !grabbing, height, controller);
        if (state.reset_camera) {
            controller.reset();
            state.reset_camera = false;
        }
        const render::Camera camera = controller.camera(width, height);
        if (grabbing) {
            session.drag(camera, mouse.x, mouse.y);
        }
        if (state.reset_requested) {
            session.reset();
            grabbing = false;
            state.reset_requested = false;
            cloth_changed = true;
        }
        // The simulation: the frame in flight is published when done (with --sync: waited
        // for), then the next one starts, so drawing never waits for a slow step.
        const auto on_published = [&] {
            const cloth::ClothStepStats& step = session.stats().step;
            step_ms.add(step.ms);
            solve_ms.add(step.solve_ms);
            refit_ms.add(step.self.refit_ms);
            traverse_ms.add(step.self.traverse_ms);
            narrow_ms.add(step.self.narrow_ms);
            response_ms.add(step.self.response_ms);
            max_intersections = std::max(max_intersections, session.stats().intersecting_pairs);
            sim_clock.tick();
            state.simulation_fps = sim_clock.recent_fps();
            cloth_changed = true;
        };
        // Without input there is nothing new to draw before the next simulated frame: wait for
        // it (and help compute it) rather than draw the same image again. With input, draw at
        // once and let the frame finish beside the drawing.
        const bool input = mouse.any_activity() || keys.any() || window.ui_is_active();
        if (session.is_advancing() &&
            session.finish_advance(run.sync || (!input && !state.paused))) {
            on_published();
        }
        if (!session.is_advancing() && (!state.paused || state.step_requested)) {
            session.start_advance();
            state.step_requested = false;
            if (run.sync && session.finish_advance(true)) {
                on_published();
            }
        }

        // Drawing.
        const Stopwatch draw_watch;
        drawer.begin(camera, depth_range(camera, scene_centre, scene_radius), look);
        for (std::size_t k = 0; k < obstacle_buffers.size(); ++k) {
            const pipeline::ObstacleShape& shape = session.setup().shapes[k];
            Matrix4 model = identity_matrix();
            if (shape.animation) {  // a deforming mesh: its frame at this time
                animated_positions.resize(shape.rest.positions.size());
                shape.animation->positions_at(session.time(), animated_positions);
                obstacle_buffers[k].upload(animated_positions, shape.rest.triangles, shape.smooth);
            }
            if (!shape.motion.is_static()) {
                const cloth::Pose pose = shape.motion.pose(session.time());
                model = rigid_matrix(pose.rotation.row, pose.pivot, pose.translate);
            }
            drawer.draw(obstacle_buffers[k], pipeline::OBSTACLE_COLOR, model);
        }
        if (cloth_changed) {  // new normals and upload only for a new state
            cloth_buffers.upload(session.positions(), session.triangles(), true);
            cloth_changed = false;
        }
        drawer.draw(cloth_buffers, pipeline::CLOTH_COLOR, identity_matrix());
        state.draw_ms = draw_watch.elapsed_ms();
        draw_ms.add(state.draw_ms);
        const bool last = run.frames > 0 && frame + 1 == run.frames;
        if (last && !run.screenshot.empty()) {
            save_screenshot(run.screenshot, 0, 0, width, height);
        }
        if (window.has_ui()) {
            window.begin_ui_frame();
            draw_cloth_panel(session, state, clock);
            window.end_ui_frame();
        }
        check_gl("cloth frame");
        window.swap_buffers();
        clock.tick();
        last_camera = camera;
    }

    nlohmann::ordered_json result;
    result["view"] = "cloth";
    result["scene"] = scene_name;
    result["triangles"] = session.triangles().size();
    result["vertices"] = session.positions().size();
    result["initial_intersecting_pairs"] = session.start().initial_intersections;
    result["untangle"] = pipeline::untangle_report(session.start());
    result["substeps_per_frame"] = session.substeps_per_frame();
    result["simulated_frames"] = session.frame();
    result["simulated_seconds"] = session.time();
    result["sync"] = run.sync;
    const double wall_seconds = run_clock.elapsed_ms() / 1000.0;
    result["simulated_frames_per_second"] =
        wall_seconds > 0.0 ? static_cast<double>(session.frame()) / wall_seconds : 0.0;
    add_run_summary(result, clock, run, window, last_camera);
    result["mean_step_ms"] = step_ms.value();
    result["mean_solve_ms"] = solve_ms.value();
    result["mean_refit_ms"] = refit_ms.value();
    result["mean_traverse_ms"] = traverse_ms.value();
    result["mean_narrow_ms"] = narrow_ms.value();
    result["mean_response_ms"] = response_ms.value();
    result["mean_draw_ms"] = draw_ms.value();
    result["intersecting_pairs"] = session.stats().intersecting_pairs;
    result["intersecting_pairs_frame"] = session.stats().checked_frame;
    result["max_intersecting_pairs"] = max_intersections;
    return result;
}

}  // namespace pliant::viewer
