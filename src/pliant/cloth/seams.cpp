#include "pliant/cloth/seams.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "pliant/core/error.hpp"

namespace pliant::cloth {

void Seams::add(std::span<const std::int32_t> a, std::span<const std::int32_t> b, double seconds,
                double gap, std::span<const Vec3d> positions) {
    if (a.size() != b.size()) {
        throw InvalidInput(
            fmt::format("seam: expected as many vertices on side b as on side a, got {} and {}",
                        a.size(), b.size()));
    }
    if (a.empty()) {
        throw InvalidInput("seam: expected at least one vertex pair, got none");
    }
    if (!(seconds > 0.0) || !std::isfinite(seconds) || !(gap >= 0.0) || !std::isfinite(gap)) {
        throw InvalidInput(fmt::format(
            "seam: expected seconds > 0 and gap >= 0 (finite), got {} s and {} m", seconds, gap));
    }
    const auto n = static_cast<std::int64_t>(positions.size());
    std::vector<Pair> pairs;
    pairs.reserve(a.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
        for (const std::int32_t v : {a[k], b[k]}) {
            if (v < 0 || v >= n) {
                throw InvalidInput(fmt::format(
                    "seam: pair {}: vertex {} out of range, expected an index in [0, {})", k, v,
                    n));
            }
        }
        if (a[k] == b[k]) {
            throw InvalidInput(fmt::format("seam: pair {}: vertex {} is sewn to itself", k, a[k]));
        }
        const double start = norm(positions[static_cast<std::size_t>(a[k])] -
                                  positions[static_cast<std::size_t>(b[k])]);
        pairs.push_back({a[k], b[k], start, gap, seconds});
    }
    m_pairs.insert(m_pairs.end(), pairs.begin(), pairs.end());
}

double Seams::target(std::size_t k, double t) const {
    const Pair& p = m_pairs[k];
    const double f = std::clamp(t / p.seconds, 0.0, 1.0);
    return std::max(p.gap, p.start + (p.gap - p.start) * f);
}

void Seams::project(std::span<Vec3d> positions, std::span<const double> inverse_masses,
                    double t) const {
    for (std::size_t k = 0; k < m_pairs.size(); ++k) {
        const auto a = static_cast<std::size_t>(m_pairs[k].a);
        const auto b = static_cast<std::size_t>(m_pairs[k].b);
        const double wa = inverse_masses[a];
        const double wb = inverse_masses[b];
        if (wa + wb <= 0.0) {
            continue;
        }
        const Vec3d d = positions[a] - positions[b];
        const double length = norm(d);
        const double c = length - target(k, t);
        if (c <= 0.0 || length <= 0.0) {
            continue;  // a seam pulls, it never pushes apart
        }
        const Vec3d correction = d * (c / (length * (wa + wb)));
        positions[a] -= correction * wa;
        positions[b] += correction * wb;
    }
}

double Seams::max_opening(std::span<const Vec3d> positions) const {
    double worst = 0.0;
    for (const Pair& p : m_pairs) {
        const double length = norm(positions[static_cast<std::size_t>(p.a)] -
                                   positions[static_cast<std::size_t>(p.b)]);
        worst = std::max(worst, length - p.gap);
    }
    return worst;
}

}  // namespace pliant::cloth
