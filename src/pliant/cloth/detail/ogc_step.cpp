#include "pliant/cloth/detail/ogc_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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
                            std::span<const double> inverse_masses, OgcAuditWindow& audit,
                            std::int64_t& num_free) {
    audit.start.assign(positions.begin(), positions.end());
    audit.detections = ogc.detections();
    audit.shift = ogc.shift();
    audit.pair_audits = 0;
    audit.full_audits = 0;
    num_free = std::count_if(inverse_masses.begin(), inverse_masses.end(),
                             [](double w) { return w > 0.0; });
    return {ogc.detections(), ogc.wide_detections(), ogc.detect_ms()};
}

namespace {

// Per vertex v, the larger of its deviations at the window's ends, |a_v − D_v − T_0| and
// |x_v − D_v − T_1| (ogc_pairs_cover_window's terms; a non-finite one counts as infinite), into
// `deviations`; returns their largest.
double window_deviations(const OgcContact& ogc, const OgcAuditWindow& audit,
                         std::span<const Vec3d> x, std::vector<double>& deviations) {
    const std::span<const Vec3d> detected = ogc.detected_positions();
    const Vec3d shift_end = ogc.shift();
    const Vec3d shift_start =
        audit.detections == ogc.detections() ? audit.shift : Vec3d{0.0, 0.0, 0.0};
    const auto finite_or_inf = [](double d) {
        return std::isfinite(d) ? d : std::numeric_limits<double>::infinity();
    };
    deviations.resize(x.size());
    return parallel_reduce(
        static_cast<std::int64_t>(x.size()), 0.0,
        [&](std::int64_t begin, std::int64_t end) {
            double largest = 0.0;
            for (std::int64_t i = begin; i < end; ++i) {
                const auto v = static_cast<std::size_t>(i);
                const double d =
                    std::max(finite_or_inf(norm(audit.start[v] - detected[v] - shift_start)),
                             finite_or_inf(norm(x[v] - detected[v] - shift_end)));
                deviations[v] = d;
                largest = std::max(largest, d);
            }
            return largest;
        },
        [](double a, double b) { return std::max(a, b); }, TRUNCATE_GRAIN);
}

bool covers_window(const OgcContact& ogc, const OgcAuditWindow& audit, std::span<const Vec3d> x,
                   std::vector<double>& deviations) {
    const std::size_t n = x.size();
    if (!ogc.has_detection() || ogc.detected_positions().size() != n || audit.start.size() != n ||
        static_cast<std::int64_t>(ogc.num_pairs()) > CCDFailSafe::pair_budget(n)) {
        return false;
    }
    const double deviation = window_deviations(ogc, audit, x, deviations);
    const double margin = 1e-9 * (1.0 + largest_coordinate(audit.start, x));
    return 2.0 * deviation < ogc.query_radius() - margin;
}

// The detection's pairs the CCD must test over the window from audit.start to x, into
// audit.pairs, given each vertex's larger deviation at the window's ends (window_deviations):
// those with a vertex whose deviation reaches its slack (OgcContact::slacks(): half the least
// margin d − r of its pairs at D, less a rounding margin). A pair whose vertices all stay within
// their slacks stays at least r apart over the whole window (the deviations are convex in τ, a
// feature's distance moves by at most its vertices' largest deviation), and the CCD's hits need
// its features within the CCD's tolerance of each other, far below r: the CCD finds nothing
// there. A vertex the CCD puts back returns to its start, within its slack too.
void audit_pairs(const OgcContact& ogc, std::span<const double> deviations, OgcAuditWindow& audit) {
    const std::span<const double> slacks = ogc.slacks();
    const auto hot = [&](std::int32_t v) {
        const auto u = static_cast<std::size_t>(v);
        return !(deviations[u] < slacks[u]);
    };
    audit.pairs.clear();
    for (const OgcContact::Pair& p : ogc.pairs()) {
        if (hot(p.v[0]) || hot(p.v[1]) || hot(p.v[2]) || hot(p.v[3])) {
            audit.pairs.push_back(
                FeatureVertices{{p.v[0], p.v[1], p.v[2], p.v[3]}, p.is_edge_edge ? 2U : 1U});
        }
    }
}

}  // namespace

bool ogc_pairs_cover_window(const OgcContact& ogc, const OgcAuditWindow& audit,
                            std::span<const Vec3d> x) {
    std::vector<double> deviations;
    return covers_window(ogc, audit, x, deviations);
}

bool audit_ogc_window(SelfCollision& self_collision, const OgcContact& ogc, OgcAuditWindow& audit,
                      std::span<Vec3d> x, std::span<Vec3d> velocities, bool use_pairs) {
    const std::int64_t reverted = self_collision.stats().reverted_vertices;
    if (!std::equal(audit.start.begin(), audit.start.end(), x.begin(), x.end())) {
        if (use_pairs && covers_window(ogc, audit, x, audit.deviations)) {
            audit_pairs(ogc, audit.deviations, audit);
            self_collision.enforce_pairs(audit.pairs, audit.start, x, velocities);
            ++audit.pair_audits;
            if (self_collision.stats().reverted_vertices != reverted &&
                !covers_window(ogc, audit, x, audit.deviations)) {
                // The vertices put back stand at their starts, off the moving frame: on the
                // changed motion the pairs may no longer cover every contact.
                self_collision.enforce(audit.start, x, velocities);
                ++audit.full_audits;
            }
        } else {
            self_collision.enforce(audit.start, x, velocities);
            ++audit.full_audits;
        }
    }
    audit.start.assign(x.begin(), x.end());
    audit.detections = ogc.detections();
    audit.shift = ogc.shift();
    return self_collision.stats().reverted_vertices != reverted;
}

void ogc_step_stats(const OgcContact& ogc, const OgcStepStart& start, std::int64_t truncated,
                    const OgcAuditWindow& audit, ClothStepStats& stats) {
    stats.ogc_pair_audits = audit.pair_audits;
    stats.ogc_full_audits = audit.full_audits;
    stats.has_ogc = true;
    stats.ogc_detections = ogc.detections() - start.detections;
    stats.ogc_wide_detections = ogc.wide_detections() - start.wide_detections;
    stats.ogc_detect_ms = ogc.detect_ms() - start.detect_ms;
    stats.ogc_truncated = truncated;
    stats.ogc_pairs = static_cast<std::int64_t>(ogc.num_pairs());
    stats.ogc_close_pairs = ogc.close_pairs();
}

}  // namespace pliant::cloth::detail
