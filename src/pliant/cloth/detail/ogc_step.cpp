#include "pliant/cloth/detail/ogc_step.hpp"

#include <algorithm>
#include <utility>

#include "pliant/core/parallel.hpp"

namespace pliant::cloth::detail {

namespace {
constexpr std::int64_t TRUNCATE_GRAIN = 2048;
}  // namespace

std::unique_ptr<OgcContact> make_ogc_contact(const ClothModel& model, const OgcOptions& options,
                                             double default_stiffness) {
    return std::make_unique<OgcContact>(
        model.triangles(), model.num_vertices(), options,
        options.radius > 0.0 ? options.radius : model.material().thickness,
        options.stiffness > 0.0 ? options.stiffness : default_stiffness);
}

std::int64_t truncate_moves(const OgcContact& ogc, std::span<const Vec3d> from, std::span<Vec3d> x,
                            std::span<const double> inverse_masses, std::int64_t* ball_held) {
    using Counts = std::pair<std::int64_t, std::int64_t>;  // held back, by the ball
    const Counts counts = parallel_reduce(
        static_cast<std::int64_t>(x.size()), Counts{0, 0},
        [&](std::int64_t begin, std::int64_t end) {
            Counts c{0, 0};
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                if (inverse_masses[v] > 0.0 && ogc.truncate(v, from[v], x[v])) {
                    ++c.first;
                    c.second += ogc.at_ball(v, x[v]) ? 1 : 0;
                }
            }
            return c;
        },
        [](const Counts& a, const Counts& b) {
            return Counts{a.first + b.first, a.second + b.second};
        },
        TRUNCATE_GRAIN);
    if (ball_held != nullptr) {
        *ball_held += counts.second;
    }
    return counts.first;
}

bool pins_left_sets(const OgcContact& ogc, std::span<const Vec3d> x,
                    std::span<const double> inverse_masses) {
    return parallel_reduce(
               static_cast<std::int64_t>(x.size()), std::int64_t{0},
               [&](std::int64_t begin, std::int64_t end) {
                   std::int64_t count = 0;
                   for (std::int64_t i = begin; i < end; ++i) {
                       const auto v = static_cast<std::size_t>(i);
                       if (!(inverse_masses[v] > 0.0) && !ogc.feasible(v, x[v])) {
                           ++count;
                       }
                   }
                   return count;
               },
               [](std::int64_t a, std::int64_t b) { return a + b; }, TRUNCATE_GRAIN) > 0;
}

void pin_detection_positions(std::span<const Vec3d> start, std::span<const Vec3d> x,
                             std::span<const double> inverse_masses, std::vector<Vec3d>& out) {
    out.resize(x.size());
    for (std::size_t v = 0; v < x.size(); ++v) {
        out[v] = inverse_masses[v] > 0.0 ? start[v] : x[v];
    }
}

OgcStepStart begin_ogc_step(const OgcContact& ogc, std::span<const Vec3d> positions,
                            std::span<const double> inverse_masses, std::vector<Vec3d>& audit_start,
                            std::int64_t& num_free) {
    audit_start.assign(positions.begin(), positions.end());
    num_free = std::count_if(inverse_masses.begin(), inverse_masses.end(),
                             [](double w) { return w > 0.0; });
    return {ogc.detections(), ogc.detect_ms()};
}

bool audit_ogc_window(SelfCollision& self_collision, std::vector<Vec3d>& audit_start,
                      std::span<Vec3d> x, std::span<Vec3d> velocities) {
    const std::int64_t reverted = self_collision.stats().reverted_vertices;
    self_collision.enforce(audit_start, x, velocities);
    audit_start.assign(x.begin(), x.end());
    return self_collision.stats().reverted_vertices != reverted;
}

void ogc_step_stats(const OgcContact& ogc, const OgcStepStart& start, std::int64_t truncated,
                    ClothStepStats& stats) {
    stats.has_ogc = true;
    stats.ogc_detections = ogc.detections() - start.detections;
    stats.ogc_detect_ms = ogc.detect_ms() - start.detect_ms;
    stats.ogc_truncated = truncated;
    stats.ogc_pairs = static_cast<std::int64_t>(ogc.num_pairs());
    stats.ogc_close_pairs = ogc.close_pairs();
}

}  // namespace pliant::cloth::detail
