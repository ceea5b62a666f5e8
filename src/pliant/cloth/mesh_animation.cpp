#include "pliant/cloth/mesh_animation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "pliant/core/error.hpp"

namespace pliant::cloth {

MeshAnimation::MeshAnimation(std::vector<std::vector<Vec3d>> frames, double fps, bool loop)
    : m_frames(std::move(frames)), m_fps(fps), m_loop(loop) {
    if (m_frames.empty()) {
        throw InvalidInput("cloth::MeshAnimation: no frames; expected at least one");
    }
    if (!(std::isfinite(fps) && fps > 0.0)) {
        throw InvalidInput(
            fmt::format("cloth::MeshAnimation: fps {}: expected a finite number > 0", fps));
    }
    const std::size_t num_vertices = m_frames.front().size();
    if (num_vertices == 0) {
        throw InvalidInput("cloth::MeshAnimation: frame 0 has no vertices");
    }
    for (std::size_t k = 0; k < m_frames.size(); ++k) {
        if (m_frames[k].size() != num_vertices) {
            throw InvalidInput(fmt::format(
                "cloth::MeshAnimation: frame {} has {} vertices, frame 0 has {}: expected the "
                "same topology in every frame",
                k, m_frames[k].size(), num_vertices));
        }
        for (std::size_t v = 0; v < num_vertices; ++v) {
            if (!is_finite(m_frames[k][v])) {
                throw InvalidInput(fmt::format(
                    "cloth::MeshAnimation: frame {}, vertex {}: expected finite coordinates, got "
                    "({}, {}, {})",
                    k, v, m_frames[k][v].x, m_frames[k][v].y, m_frames[k][v].z));
            }
        }
    }
}

MeshAnimation::Blend MeshAnimation::blend(double t) const {
    const auto n = static_cast<double>(m_frames.size());
    double s = t * m_fps;  // in frames
    if (m_loop) {
        s -= n * std::floor(s / n);
        s = s >= n ? 0.0 : s;  // rounding of the floor at a period's end
    } else {
        s = std::clamp(s, 0.0, n - 1.0);
    }
    const double k = std::floor(s);
    const auto a = static_cast<std::size_t>(k);
    return {a, (a + 1) % m_frames.size(), s - k};
}

void MeshAnimation::positions_at(double t, std::span<Vec3d> out) const {
    if (out.size() != num_vertices()) {
        throw InvalidInput(fmt::format(
            "cloth::MeshAnimation::positions_at: out.size() ({}) != the vertex count ({})",
            out.size(), num_vertices()));
    }
    const Blend at = blend(t);
    const std::vector<Vec3d>& fa = m_frames[at.a];
    if (at.w == 0.0) {
        std::copy(fa.begin(), fa.end(), out.begin());
        return;
    }
    const std::vector<Vec3d>& fb = m_frames[at.b];
    for (std::size_t v = 0; v < fa.size(); ++v) {
        out[v] = fa[v] + (fb[v] - fa[v]) * at.w;
    }
}

Vec3d MeshAnimation::position_at(std::size_t v, double t) const {
    const Blend at = blend(t);
    const Vec3d& pa = m_frames[at.a][v];
    return at.w == 0.0 ? pa : pa + (m_frames[at.b][v] - pa) * at.w;
}

double MeshAnimation::max_vertex_step(double h) const {
    double largest = 0.0;
    const std::size_t pairs = m_loop ? m_frames.size() : m_frames.size() - 1;
    for (std::size_t k = 0; k < pairs && m_frames.size() > 1; ++k) {
        const std::vector<Vec3d>& fa = m_frames[k];
        const std::vector<Vec3d>& fb = m_frames[(k + 1) % m_frames.size()];
        for (std::size_t v = 0; v < fa.size(); ++v) {
            largest = std::max(largest, norm(fb[v] - fa[v]));
        }
    }
    return largest * std::min(1.0, h * m_fps);
}

}  // namespace pliant::cloth
