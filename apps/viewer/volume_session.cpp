#include "volume_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "picking.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/timer.hpp"
#include "pliant/io/transfer_function_json.hpp"
#include "pliant/volume/clean.hpp"

namespace pliant::viewer {
namespace {

// Pixels around the cursor within which a tet-mesh vertex is grabbed.
constexpr double DRAG_PICK_PIXELS = 12.0;

void check_scale(double scale) {
    if (!(scale > 0.0) || !std::isfinite(scale)) {
        throw InvalidInput(
            fmt::format("viewer: opacity scale {}, expected a finite value > 0", scale));
    }
}

void check_threshold(double threshold) {
    if (!(threshold >= 0.0 && threshold <= 255.0)) {
        throw InvalidInput(
            fmt::format("viewer: threshold {}, expected a value in [0, 255]", threshold));
    }
}

}  // namespace

DriverKind parse_driver_kind(const std::string& name) {
    if (name == "none") {
        return DriverKind::none;
    }
    if (name == "wave") {
        return DriverKind::wave;
    }
    if (name == "twist") {
        return DriverKind::twist;
    }
    if (name == "bubble") {
        return DriverKind::bubble;
    }
    throw InvalidInput(fmt::format("driver '{}' is not one of none, wave, twist, bubble", name));
}

const char* driver_kind_name(DriverKind kind) {
    switch (kind) {
        case DriverKind::wave:
            return "wave";
        case DriverKind::twist:
            return "twist";
        case DriverKind::bubble:
            return "bubble";
        case DriverKind::none:
            break;
    }
    return "none";
}

VolumeSession::VolumeSession(volume::Volume source, const VolumeSessionOptions& options)
    : m_options(options) {
    check_scale(options.opacity_scale);
    check_threshold(options.threshold);
    if (!(options.fps > 0.0) || !std::isfinite(options.fps) || !(options.drag_radius >= 0.0) ||
        !std::isfinite(options.drag_radius)) {
        throw InvalidInput(fmt::format(
            "viewer: fps {} and drag radius {}, expected fps > 0 and a radius >= 0 (finite)",
            options.fps, options.drag_radius));
    }
    if (source.empty()) {
        throw InvalidInput("viewer: the volume is empty (no voxels)");
    }
    m_is_rgba = volume::channels(source.type()) == 4;
    if (m_is_rgba) {
        m_original = std::move(source);
        m_source = m_original;
        if (options.threshold > 0.0) {
            volume::threshold_alpha(m_source, options.threshold);
        }
    } else {
        m_source = std::move(source);
        m_base_tf = io::load_transfer_function(options.tf, m_source);
        m_base_tf.validate();
        update_render_tf();
    }
    if (options.deform) {
        build_deformable();
    }
}

VolumeSession::~VolumeSession() = default;

void VolumeSession::update_render_tf() {
    volume::TransferFunction tf = volume::threshold_alpha(m_base_tf, m_options.threshold);
    const double unit =
        m_base_tf.opacity_unit > 0.0 ? m_base_tf.opacity_unit : volume::smallest_spacing(m_source);
    tf.opacity_unit = unit / m_options.opacity_scale;
    m_render_tf = std::move(tf);
    m_caster_dirty = true;
    ++m_generation;
}

void VolumeSession::build_deformable() {
    settle();
    m_deformable.reset();
    m_drag_vertex = -1;
    m_drag_changed = false;
    m_visibility_tf = m_base_tf;
    m_deformable = std::make_unique<pipeline::DeformableVolume>(
        m_source, m_is_rgba ? nullptr : &m_visibility_tf, m_options.grid, std::filesystem::path(),
        m_options.body);
    if (m_options.resample == pipeline::ResampleMode::exact) {
        m_targets[0] = m_deformable->target_like();
        m_targets[1] = m_deformable->target_like();
    }
    m_mapped.reset();
    m_caster_dirty = true;
    m_front = 0;
    apply_driver();
    resample_front();
}

void VolumeSession::fill(int buffer, const render::MappedRayCaster* caster, int octants) {
    const Stopwatch watch;
    const auto b = static_cast<std::size_t>(buffer);
    m_solver_stats.occupancy_ms = 0.0;
    if (m_options.resample == pipeline::ResampleMode::map) {
        m_deformable->build_map(m_maps[b]);
        m_solver_stats.resample_ms = watch.elapsed_ms();
        if (caster != nullptr) {
            caster->compute_map(m_maps[b], m_map_states[b], octants);
            m_solver_stats.occupancy_ms = m_map_states[b].ms();
        } else {
            m_map_states[b].clear();
        }
        return;
    }
    m_deformable->resample(m_targets[b]);
    m_solver_stats.resample_ms = watch.elapsed_ms();
}

std::shared_ptr<const render::MappedRayCaster> VolumeSession::frame_caster() const {
    if (!uses_map() || m_caster_dirty) {
        return nullptr;
    }
    return m_mapped;
}

std::shared_ptr<const render::MappedRayCaster> VolumeSession::step_caster() const {
    // The installed state's cost, whichever thread computed it (MappedRayCaster::map_ms()).
    const double state_ms = m_mapped ? m_mapped->map_ms() : 0.0;
    if (m_options.map_state == MapStatePlacement::balanced &&
        !(m_stats.step_ms + m_stats.resample_ms + state_ms < m_stats.render_ms)) {
        return nullptr;
    }
    return frame_caster();
}

void VolumeSession::resample_front() {
    fill(m_front, frame_caster().get(), m_octants);
    publish();
}

void VolumeSession::publish() {
    const pbd::SoftBody& body = m_deformable->body();
    m_positions.assign(body.positions().begin(), body.positions().end());
    m_time = body.time();
    m_stats.step_ms = m_solver_stats.step_ms;
    m_stats.resample_ms = m_solver_stats.resample_ms;
    m_stats.occupancy_ms = m_solver_stats.occupancy_ms;
    m_stats.volume_ratio = m_solver_stats.volume_ratio;
    m_stats.inverted_tets = m_solver_stats.inverted_tets;
    m_volume_changed = true;
    ++m_generation;
}

void VolumeSession::settle() {
    if (m_task.is_started()) {
        finish_step(true);
    }
}

void VolumeSession::apply_pending_drag() {
    if (!m_drag_changed || m_task.is_started()) {
        return;
    }
    pbd::SoftBody& body = m_deformable->body();
    if (m_drag_vertex >= 0) {
        body.set_drag(m_drag_vertex, vec3_cast<float>(m_drag_target),
                      static_cast<float>(m_drag_radius));
    } else {
        body.release_drag();
    }
    m_drag_changed = false;
}

void VolumeSession::apply_driver() {
    pbd::SoftBody& body = m_deformable->body();
    body.clear_drivers();
    switch (m_options.driver.kind) {
        case DriverKind::wave:
            body.add_driver(m_options.driver.wave);
            break;
        case DriverKind::twist:
            body.add_driver(m_options.driver.twist);
            break;
        case DriverKind::bubble:
            body.add_driver(m_options.driver.bubble);
            break;
        case DriverKind::none:
            break;
    }
}

void VolumeSession::set_transfer_function(const std::string& name_or_file) {
    if (m_is_rgba) {
        m_options.tf = name_or_file;  // RGBA volumes have their own colours: nothing to do
        return;
    }
    volume::TransferFunction tf = io::load_transfer_function(name_or_file, m_source);
    tf.validate();
    m_base_tf = std::move(tf);
    m_options.tf = name_or_file;
    update_render_tf();
    if (m_deformable) {
        build_deformable();
    }
}

void VolumeSession::set_opacity_scale(double scale) {
    check_scale(scale);
    m_options.opacity_scale = scale;
    if (m_is_rgba) {
        m_caster_dirty = true;
        ++m_generation;
    } else {
        update_render_tf();
    }
}

void VolumeSession::set_threshold(double threshold) {
    check_threshold(threshold);
    m_options.threshold = threshold;
    if (m_is_rgba) {
        settle();  // the resampler of a frame in flight reads m_source
        // In place: the resampler refers to m_source.
        std::copy(m_original.bytes().begin(), m_original.bytes().end(), m_source.bytes().begin());
        if (threshold > 0.0) {
            volume::threshold_alpha(m_source, threshold);
        }
        m_caster_dirty = true;
        ++m_generation;
    } else {
        update_render_tf();
    }
}

void VolumeSession::set_clip(const std::optional<render::ClipPlane>& clip) {
    prepare_caster();
    if (uses_map()) {
        m_mapped->set_clip(clip);  // validates
    } else {
        m_caster->set_clip(clip);  // validates
    }
    m_options.clip = clip;
    ++m_generation;
}

void VolumeSession::set_shading(bool shading) {
    if (shading != m_options.shading) {
        m_options.shading = shading;
        m_caster_dirty = true;
        ++m_generation;
    }
}

const pbd::SoftBody* VolumeSession::body() const {
    return m_deformable ? &m_deformable->body() : nullptr;
}

void VolumeSession::require_deformable(const char* what) const {
    if (!m_deformable) {
        throw InvalidInput(fmt::format("viewer: {} needs a deformable volume (--deform)", what));
    }
}

void VolumeSession::set_driver(const DriverSettings& driver) {
    require_deformable("a driver");
    settle();
    const bool restart = driver.kind != m_options.driver.kind;
    const DriverSettings previous = m_options.driver;
    m_options.driver = driver;
    try {
        if (restart) {
            m_deformable->reset_body();
            m_drag_vertex = -1;
            m_drag_changed = false;
        }
        apply_driver();
    } catch (const InvalidInput&) {
        m_options.driver = previous;
        apply_driver();
        throw;
    }
    if (restart) {
        resample_front();
    }
}

void VolumeSession::set_stiffness(double stiffness) {
    require_deformable("stiffness");
    settle();
    m_deformable->body().set_stiffness(stiffness);
    m_options.body.stiffness = stiffness;
}

void VolumeSession::set_drag_radius(double box_units) {
    if (!(box_units >= 0.0) || !std::isfinite(box_units)) {
        throw InvalidInput(
            fmt::format("viewer: drag radius {}, expected a finite value >= 0", box_units));
    }
    m_options.drag_radius = box_units;
}

void VolumeSession::step() {
    require_deformable("stepping");
    settle();
    // On the caller with every thread: the same frame as start_step's (deterministic stages).
    run_frame(1 - m_front, frame_caster().get(), m_octants);
    m_front = 1 - m_front;
    publish();
    apply_pending_drag();
}

void VolumeSession::run_frame(int buffer, const render::MappedRayCaster* caster, int octants) {
    pbd::SoftBody& body = m_deformable->body();
    body.step(1.0 / m_options.fps);
    const pbd::SoftBodyStats stats = body.stats();
    m_solver_stats.step_ms = stats.step_ms;
    m_solver_stats.volume_ratio = stats.volume_ratio;
    m_solver_stats.inverted_tets = stats.inverted_tets;
    fill(buffer, caster, octants);
}

bool VolumeSession::start_step() {
    require_deformable("stepping");
    if (m_task.is_started()) {
        return false;
    }
    apply_pending_drag();
    const int back = 1 - m_front;
    // The frame holds the caster it computes the map state with: one rebuilt meanwhile on this
    // thread leaves it alive until the frame ends (its state is then not installed).
    m_task.start([this, back, caster = step_caster(), octants = m_octants] {
        run_frame(back, caster.get(), octants);
    });
    return true;
}

bool VolumeSession::finish_step(bool block) {
    if (!m_task.is_started() || (!block && !m_task.is_done())) {
        return false;
    }
    m_task.wait();
    m_front = 1 - m_front;
    publish();
    apply_pending_drag();
    return true;
}

void VolumeSession::reset_deformation() {
    require_deformable("reset");
    settle();
    m_deformable->reset_body();
    m_drag_vertex = -1;
    m_drag_changed = false;
    apply_driver();
    resample_front();
}

bool VolumeSession::begin_drag(const render::Camera& camera, double x, double y) {
    if (!m_deformable) {
        return false;
    }
    const std::int32_t vertex =
        pick_point(camera, m_positions, x, y, DRAG_PICK_PIXELS, m_options.clip);
    if (vertex < 0) {
        return false;
    }
    m_drag_vertex = vertex;
    m_drag_anchor = vec3_cast<double>(m_positions[static_cast<std::size_t>(vertex)]);
    m_drag_target = m_drag_anchor;
    const Vec3d extent = m_source.bounds().extent();
    m_drag_radius = m_options.drag_radius * std::max({extent.x, extent.y, extent.z});
    m_drag_changed = true;
    apply_pending_drag();
    return true;
}

void VolumeSession::drag(const render::Camera& camera, double x, double y) {
    if (m_drag_vertex < 0) {
        return;
    }
    m_drag_target = drag_target(camera, x, y, m_drag_anchor);
    m_drag_changed = true;
    apply_pending_drag();
}

void VolumeSession::end_drag() {
    if (m_drag_vertex >= 0) {
        m_drag_vertex = -1;
        m_drag_changed = true;
        apply_pending_drag();
    }
}

render::RayCastOptions VolumeSession::caster_options() const {
    render::RayCastOptions options;
    options.step = m_options.step;
    options.shading = m_options.shading;
    options.clip = m_options.clip;
    options.thin_levels = m_options.thin_levels;
    options.background = m_options.background;
    if (m_is_rgba) {
        options.opacity_unit = volume::smallest_spacing(m_source) / m_options.opacity_scale;
    }
    return options;
}

void VolumeSession::prepare_caster() {
    if (uses_map()) {
        const volume::InverseMap& map = m_maps[static_cast<std::size_t>(m_front)];
        if (m_caster_dirty || !m_mapped) {
            const render::RayCastOptions options = caster_options();
            m_mapped = std::make_shared<render::MappedRayCaster>(
                m_source, m_is_rgba ? nullptr : &m_render_tf, m_source, options);
            m_mapped->set_map(map);
            m_stats.prepare_ms = m_mapped->prepare_ms() + m_mapped->map_ms();
        } else if (m_volume_changed) {
            // The state the frame computed with this caster (O(1)), else computed here.
            render::MapOccupancy& state = m_map_states[static_cast<std::size_t>(m_front)];
            const Stopwatch watch;
            if (m_mapped->is_own(state) && state.map() == &map) {
                m_mapped->install_map(state);
            } else {
                m_mapped->set_map(map);
            }
            m_stats.prepare_ms = watch.elapsed_ms();
        } else {
            return;
        }
        m_stats.prepared = true;
        m_caster_dirty = false;
        m_volume_changed = false;
        return;
    }
    const volume::Volume& shown = m_deformable ? m_targets[m_front] : m_source;
    if (m_caster && !m_caster_dirty && m_volume_changed) {
        // A new deformed frame, same options: the caster's arrays are reused.
        m_caster->update(shown, m_is_rgba ? nullptr : &m_render_tf);
        m_stats.prepare_ms = m_caster->prepare_ms();
        m_stats.prepared = true;
        m_volume_changed = false;
        return;
    }
    if (m_caster_dirty || !m_caster) {
        const render::RayCastOptions options = caster_options();
        m_caster =
            std::make_unique<render::RayCaster>(shown, m_is_rgba ? nullptr : &m_render_tf, options);
        m_stats.prepare_ms = m_caster->prepare_ms();
        m_stats.prepared = true;
        m_caster_dirty = false;
        m_volume_changed = false;
    }
}

render::RayCastStats VolumeSession::render(const render::Camera& camera, render::Image& image) {
    m_stats.prepared = false;
    prepare_caster();
    if (uses_map()) {
        m_octants = m_mapped->octants_of(camera);
    }
    const render::RayCastStats stats =
        uses_map() ? m_mapped->render(camera, image) : m_caster->render(camera, image);
    m_stats.render_ms = stats.ms;
    m_stats.samples = stats.samples;
    return stats;
}

}  // namespace pliant::viewer
