#include "pliant/cloth/detail/ogc_step.hpp"

#include <algorithm>

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
                            std::span<const double> inverse_masses) {
    return parallel_reduce(
        static_cast<std::int64_t>(x.size()), std::int64_t{0},
        [&](std::int64_t begin, std::int64_t end) {
            std::int64_t count = 0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                if (inverse_masses[v] > 0.0 && ogc.truncate(v, from[v], x[v])) {
                    ++count;
                }
            }
            return count;
        },
        [](std::int64_t a, std::int64_t b) { return a + b; }, TRUNCATE_GRAIN);
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
