// MeshAnimation: a deforming triangle mesh given as a sequence of frames (vertex positions of one
// topology) at its own frame rate, linearly interpolated in time; what a deforming mesh obstacle
// (an animated body) follows.
//
//   MeshAnimation body(std::move(frames), 24.0, /*loop=*/true);   // frames[k]: #V positions
//   body.positions_at(t, out);                                    // out: #V positions at t (s)
//
// Time: frame k is at k / fps seconds. Between frames k and k + 1 the positions are
// (1 - w) frames[k] + w frames[k + 1], w = t fps - k. Without loop, times before 0 hold frame 0
// and times after (N - 1) / fps hold the last frame; with loop, the animation repeats with period
// N / fps and the last frame blends back into frame 0 (so the sequence should not repeat frame 0
// at its end). One frame: a static mesh.
//
// Units: metres, seconds. Thread safety: const member functions may run concurrently.
#pragma once

#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

class MeshAnimation {
public:
    // frames: N ≥ 1 frames of #V ≥ 1 positions each. InvalidInput naming the frame and vertex for
    // no frames, an empty frame, a frame whose vertex count differs from frame 0's, a non-finite
    // coordinate; and for fps not finite and > 0.
    MeshAnimation(std::vector<std::vector<Vec3d>> frames, double fps, bool loop);

    std::size_t num_frames() const { return m_frames.size(); }
    std::size_t num_vertices() const { return m_frames.front().size(); }
    double fps() const { return m_fps; }
    bool loops() const { return m_loop; }
    std::span<const Vec3d> frame(std::size_t k) const { return m_frames[k]; }

    // The positions at time t (s; finite) into out (#V entries, else InvalidInput). Exact at
    // frame times (t = k / fps gives frames[k] bit for bit).
    void positions_at(double t, std::span<Vec3d> out) const;
    // Vertex v (< #V) at time t: positions_at's value for it.
    Vec3d position_at(std::size_t v, double t) const;

    // The farthest any vertex moves in h seconds (h > 0), over the whole animation (m): the
    // largest vertex displacement between consecutive frames times min(1, h fps). With loop, the
    // wrap from the last frame to frame 0 counts.
    double max_vertex_step(double h) const;

private:
    // Time t as frames a and b = a + 1 (wrapped) and the weight w ∈ [0, 1) of b.
    struct Blend {
        std::size_t a;
        std::size_t b;
        double w;
    };
    Blend blend(double t) const;

    std::vector<std::vector<Vec3d>> m_frames;
    double m_fps;
    bool m_loop;
};

}  // namespace pliant::cloth
