// The state behind `pliant view volume`, without any drawing: a volume shown through the
// library's ray caster (render::RayCaster) with a transfer function, an opacity scale, the
// paper's cleaning threshold and a clipping plane, and with --deform the deformable-volume
// pipeline (pipeline::DeformableVolume: tet grid, XPBD soft body, resampling) under a driver and
// mouse drag.
//
// Controls and what they change:
//   transfer function (scalar volumes): a preset (volume::preset_names) or a JSON file; with
//     --deform the tet grid is rebuilt over what the new function shows (the deformation
//     restarts). RGBA volumes use their own colour and opacity.
//   opacity scale s > 0: opacities are per opacity unit u / s (a denser or thinner medium; s = 1
//     renders as `pliant render`).
//   threshold T ∈ [0, 255]: the paper's cleaning, α' = 0 where 255 α < T (volume/clean.hpp):
//     on the voxels of RGBA volumes, on the classification of scalar volumes (the transfer
//     function's opacity curve cut at T / 255).
//   clipping plane: render::ClipPlane (the half-space (p − point) · normal ≥ 0 is shown).
//   driver (with --deform): none, wave, twist or bubble (pbd/drivers.hpp); choosing another kind
//     restarts the body from rest so the new driver ramps in; changing a parameter replaces the
//     driver at the current time. Stiffness: SoftBody::set_stiffness.
//   drag (with --deform): the tet-mesh vertex under the cursor (nearest to the camera within a
//     few pixels, on the visible side of the clipping plane) and the vertices within the drag
//     radius follow the cursor in the view plane (SoftBody::set_drag).
//
// Every frame of a deforming volume: SoftBody::step(1 / fps), resampling into a grid like the
// source, a new RayCaster over it, one render; or with resample = map, the frame's inverse map
// (DeformableVolume::build_map, double-buffered like the resampled volumes) and one render of
// the source through it (render::MappedRayCaster, the source prepared once); the map's state
// (render::MapOccupancy: its cells' occupancy, and the empty cubes of the last render's octants)
// is computed by the frame right after its map, on the frame's thread, and swapped into the
// caster before the render (computed on the render's thread instead when the caster was
// rebuilt since the frame began: the state is the caster's own). Static volumes prepare
// the RayCaster only when the transfer function, opacity or threshold change. Not thread safe; the
// library calls parallelise internally and stay deterministic.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pliant/core/parallel_task.hpp"
#include "pliant/pbd/drivers.hpp"
#include "pliant/pbd/soft_body.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/pipeline/deformable_volume.hpp"
#include "pliant/render/camera.hpp"
#include "pliant/render/image.hpp"
#include "pliant/render/mapped_raycast.hpp"
#include "pliant/render/raycast.hpp"
#include "pliant/volume/inverse_map.hpp"
#include "pliant/volume/transfer_function.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::viewer {

enum class DriverKind { none, wave, twist, bubble };
// Where a frame in flight's map state (render::MapOccupancy) is computed, resample = map.
//   balanced: on the frame's thread when the last frame's step, map and state took less than
//             the last render (the main thread's side), so that the frame stays the shorter
//             side; else by render() on the main thread (the state costs the same on either);
//   frame:    always on the frame's thread.
// The images are the same either way.
enum class MapStatePlacement { balanced, frame };

// "none", "wave", "twist", "bubble"; InvalidInput listing them otherwise.
DriverKind parse_driver_kind(const std::string& name);
const char* driver_kind_name(DriverKind kind);

struct DriverSettings {
    DriverKind kind = DriverKind::none;
    pbd::WaveDriver wave{};
    pbd::TwistDriver twist{.axis = pbd::Axis::z, .angle = 90.0, .ramp_time = 1.0, .grip = 0.1};
    pbd::BubbleDriver bubble{};
};

struct VolumeSessionOptions {
    std::string tf = "grayscale";  // preset or JSON file (scalar volumes)
    double opacity_scale = 1.0;    // > 0
    double threshold = 0.0;        // [0, 255]
    std::optional<render::ClipPlane> clip = std::nullopt;
    bool shading = false;
    double step = 0.0;  // ray-casting step, world units (0: half the smallest spacing)
    render::Color background{0.0f, 0.0f, 0.0f};
    // Deformation.
    bool deform = false;
    pbd::TetGridOptions grid{.cell_voxels = 4};
    pbd::SoftBodyOptions body{};
    DriverSettings driver{};
    double fps = 24.0;          // a frame simulates 1 / fps seconds
    double drag_radius = 0.05;  // box units (fraction of the volume's largest side)
    pipeline::ResampleMode resample = pipeline::ResampleMode::map;  // how frames are shown
    // Through the map, an rgba8 volume: render::RayCastOptions::thin_levels.
    int thin_levels = render::RayCastOptions{}.thin_levels;
    MapStatePlacement map_state = MapStatePlacement::balanced;
};

struct VolumeFrameStats {
    double step_ms = 0.0;      // soft body, last frame
    double resample_ms = 0.0;  // last resampling (or inverse map, resample = map)
    // resample = map: the last frame's map state (MapOccupancy) on the frame's thread; 0 when
    // the render computed it (no caster yet, or one rebuilt since the frame began).
    double occupancy_ms = 0.0;
    double prepare_ms = 0.0;   // last RayCaster preparation (or map state computed or installed)
    bool prepared = false;     // the last render() prepared a RayCaster
    double render_ms = 0.0;    // last render
    std::int64_t samples = 0;  // of the last render
    double volume_ratio = 1.0;
    std::int64_t inverted_tets = 0;
};

class VolumeSession {
public:
    // Throws InvalidInput for options out of range or nothing to deform, IoError for a transfer
    // function file that cannot be read.
    VolumeSession(volume::Volume source, const VolumeSessionOptions& options);
    ~VolumeSession();
    VolumeSession(const VolumeSession&) = delete;
    VolumeSession& operator=(const VolumeSession&) = delete;

    void set_transfer_function(const std::string& name_or_file);
    void set_opacity_scale(double scale);  // InvalidInput unless finite and > 0
    void set_threshold(double threshold);  // InvalidInput outside [0, 255]
    void set_clip(const std::optional<render::ClipPlane>& clip);
    void set_shading(bool shading);
    const VolumeSessionOptions& settings() const { return m_options; }

    bool is_deformable() const { return m_deformable != nullptr; }
    // The calls below need --deform (InvalidInput otherwise).
    // Settings of the body wait for a frame in flight first.
    void set_driver(const DriverSettings& driver);
    void set_stiffness(double stiffness);
    void set_drag_radius(double box_units);
    // One frame: 1 / fps seconds of the soft body, then resampling. step(): on the caller, with
    // every thread (after a frame in flight). In the background (core/parallel_task.hpp, on one
    // thread: the step's one-thread path, which never waits for a second thread, and the other
    // threads free for render()): start_step returns at once (false, doing nothing, while a
    // frame is in flight) and finish_step publishes the frame when it is done (block: waits) —
    // the resampled volume is double-buffered, so the current one can be ray-cast meanwhile.
    // Both give the same frames bit for bit. Rethrows what the frame threw. start_step returns
    // once the frame runs on its thread: the caller's parallel loops cannot take that thread
    // from it (the frame overlaps them instead of waiting for them to end).
    void step();
    bool start_step();
    bool finish_step(bool block);
    bool is_stepping() const { return m_task.is_started(); }
    // True when no frame is in flight or it has ended; the one call that any thread may make.
    bool is_frame_done() const { return m_task.is_done(); }
    void reset_deformation();  // back to rest, time 0, the driver ramping in again
    // Dragging picks on the published vertices; the body gets the drag now, or at the next
    // start_step while a frame is in flight.
    bool begin_drag(const render::Camera& camera, double x, double y);
    void drag(const render::Camera& camera, double x, double y);
    void end_drag();
    bool is_dragging() const { return m_drag_vertex >= 0; }
    // The soft body (null without --deform); not to be used while a frame is in flight.
    const pbd::SoftBody* body() const;
    double time() const { return m_time; }  // simulated seconds of the published frame

    // Ray-casts the current state with `camera` (any size) into `image`.
    render::RayCastStats render(const render::Camera& camera, render::Image& image);

    const volume::Volume& source() const { return m_source; }
    bool is_rgba() const { return m_is_rgba; }
    const VolumeFrameStats& stats() const { return m_stats; }
    // Changes whenever the rendered image would (for caching).
    unsigned long long generation() const { return m_generation; }

private:
    void update_render_tf();
    void build_deformable();
    void apply_driver();
    // The RayCaster for the current state (built when something it prepares changed).
    // The ray-casting options of the session's current view settings.
    render::RayCastOptions caster_options() const;
    void prepare_caster();
    // Waits for a frame in flight and publishes it.
    void settle();
    void publish();
    // The soft body's step and fill(buffer, caster), with the frame's stats (start_step's work).
    void run_frame(int buffer, const render::MappedRayCaster* caster, int octants);
    void resample_front();  // the body as it is, into the shown buffer, published
    void apply_pending_drag();
    void require_deformable(const char* what) const;
    bool uses_map() const {
        return m_deformable != nullptr && m_options.resample == pipeline::ResampleMode::map;
    }
    // The body's current positions into buffer `buffer` (resampled volume or inverse map); with
    // a caster (resample = map) the map's state too, with the empty cubes of `octants`, else
    // that state is cleared.
    void fill(int buffer, const render::MappedRayCaster* caster, int octants);
    // The mapped caster a frame may compute its map state with: the current one unless it is to
    // be rebuilt (null then, and without one).
    std::shared_ptr<const render::MappedRayCaster> frame_caster() const;
    // frame_caster() when the frame in flight should compute the map state
    // (MapStatePlacement), else null.
    std::shared_ptr<const render::MappedRayCaster> step_caster() const;

    volume::Volume m_original;  // as read (RGBA: before the threshold)
    volume::Volume m_source;    // what is deformed and shown (RGBA: thresholded copy)
    bool m_is_rgba = false;
    VolumeSessionOptions m_options;
    volume::TransferFunction m_base_tf;        // as chosen (scalar volumes)
    volume::TransferFunction m_visibility_tf;  // the tet grid's (scalar volumes with --deform)
    volume::TransferFunction m_render_tf;      // threshold and opacity scale applied
    std::unique_ptr<pipeline::DeformableVolume> m_deformable;
    // Resampled volumes (--deform): m_targets[m_front] is shown, the other one is filled by the
    // frame in flight.
    std::array<volume::Volume, 2> m_targets;
    int m_front = 0;
    // resample = map: the frames' inverse maps (the same double buffer), their states
    // (computed by the frame that built the map; the one of the front buffer is swapped into
    // the caster by the next render) and their caster (shared with the frame in flight, which
    // computes the state with it: a caster rebuilt meanwhile leaves the old one to that frame).
    std::array<volume::InverseMap, 2> m_maps;
    std::array<render::MapOccupancy, 2> m_map_states;
    std::shared_ptr<render::MappedRayCaster> m_mapped;
    int m_octants = 0;  // of the last render's camera (render::MappedRayCaster::octants_of)
    std::unique_ptr<render::RayCaster> m_caster;
    bool m_caster_dirty = true;     // options changed: a new caster
    bool m_volume_changed = false;  // only the shown volume changed: update() the caster
    // The published frame.
    std::vector<Vec3f> m_positions;
    double m_time = 0.0;
    VolumeFrameStats m_stats;
    VolumeFrameStats m_solver_stats;  // written by the frame in flight
    // The drag as the user leaves it; the body gets it when no frame is in flight.
    std::int32_t m_drag_vertex = -1;
    Vec3d m_drag_anchor;
    Vec3d m_drag_target;
    double m_drag_radius = 0.0;  // world units
    bool m_drag_changed = false;
    unsigned long long m_generation = 0;
    BackgroundTask m_task{1};  // last: destroyed first, waiting for a frame in flight
};

}  // namespace pliant::viewer
