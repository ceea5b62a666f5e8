// The per-ray kernels of the voxel radiance field: sampling, trilinear interpolation with
// post-activation, front-to-back compositing (forward) and its analytic reverse pass (backward).
// Pure functions over trivially copyable views (GPU-style, no allocation, no exceptions).
//
// Coordinates: rays are in *normalized* scene coordinates u = (p − box.lo) / scale, scale = the
// box's largest side, so the grid covers [0, e] with e = extent / scale (max e = 1). Grid
// coordinate along axis a: g = u · (dims_a / e_a) − 0.5, so voxel i's value sits at its centre
// g = i (the Volume convention); g is clamped to [0, dims − 1] (clamp-to-edge in the half voxel
// at the faces). dims ≥ 2 per axis.
//
// Field (post-activation, as in DVGO and ReLU fields: interpolate the raw values, then activate):
//   s, (a_r, a_g, a_b) = trilinear interpolation of the 8 surrounding voxels' raw parameters
//   σ = softplus(s) · DENSITY_SCALE      (density per normalized unit; softplus(s) is the
//                                          density per 1/DENSITY_SCALE of the box's largest side)
//   c = sigmoid(a)                        (straight colour, view independent)
// Softplus, not ReLU: it has a gradient everywhere, so no voxel is dead after initialization.
//
// Rendering (Max 1995; NeRF, Mildenhall et al. 2020, eq. 3): the clipped chord [t0, t1] is cut
// into segments of length δ (the last one shortened to ℓ ≤ δ), each represented by its midpoint
// sample k, exactly as render::raycast samples:
//   α_k = 1 − exp(−σ_k δ_k),  T_k = Π_{j<k} (1 − α_j),  w_k = T_k α_k,
//   C = Σ_k w_k c_k + T_end · background,
// stopping after the sample at which T falls below min_transmittance (early termination).
// Samples in cells whose occupancy byte is 0 are skipped (σ treated as 0): the occupancy grid
// marks cells where some corner's σ exceeds a threshold, and trilinear interpolation of the raw
// value never exceeds its largest corner (softplus is monotone), so a skipped sample has σ under
// the threshold.
//
// Backward (the standard reverse pass with running sums; O(1) extra memory beyond the samples'
// records): with g = ∂L/∂C and the suffix S_k = Σ_{j>k} w_j c_j + T_end · bg = C − Σ_{j≤k} w_j c_j,
//   ∂L/∂c_k = w_k g,
//   ∂L/∂σ_k = δ_k (T_{k+1} (c_k · g) − S_k · g)        (∂α_k/∂σ_k = δ_k (1 − α_k), ∂T_j/∂σ_k =
//                                                         −δ_k T_j for j > k),
//   ∂L/∂s_k = ∂L/∂σ_k · DENSITY_SCALE · sigmoid(s_k),   ∂L/∂a_k = ∂L/∂c_k ⊙ c_k (1 − c_k),
// each scattered to the 8 corners with the trilinear weights.
#pragma once

#include <cmath>
#include <cstdint>

#include "pliant/core/host_device.hpp"

namespace pliant::nerf::detail {

// σ = softplus(s) · DENSITY_SCALE per normalized unit.
inline constexpr float DENSITY_SCALE = 256.0f;

struct GridView {
    const float* params = nullptr;  // 4 per voxel: s, a_r, a_g, a_b
    const std::uint8_t* occupied =
        nullptr;  // per cell (indexed by its lower corner voxel), or null
    int dims[3] = {2, 2, 2};
    float to_grid[3] = {1, 1, 1};  // dims_a / e_a
    float extent[3] = {1, 1, 1};   // e_a, normalized
};

// A sample's position in the grid: the lower corner voxel and the fractions.
struct Corner {
    std::int32_t base = 0;  // voxel index of the lower corner
    float f[3] = {0, 0, 0};
};

struct SampleRecord {
    Corner corner;
    float s = 0.0f;       // interpolated raw density
    float alpha = 0.0f;   // 1 − exp(−σ δ_k)
    float length = 0.0f;  // δ_k
    float t = 0.0f;       // the sample's distance along the ray (normalized units)
    float c[3] = {0, 0, 0};
};

struct RayOutput {
    float rgb[3] = {0, 0, 0};
    float transmittance = 1.0f;  // T after the last sample
    int samples = 0;             // samples evaluated (not skipped)
};

PLIANT_HOST_DEVICE inline float softplus(float s) {
    return s > 20.0f ? s : std::log1p(std::exp(s));
}
PLIANT_HOST_DEVICE inline float sigmoid(float s) {
    return 1.0f / (1.0f + std::exp(-s));
}

PLIANT_HOST_DEVICE inline Corner locate(const GridView& g, const float u[3]) {
    Corner c;
    int idx[3];
    for (int a = 0; a < 3; ++a) {
        float x = u[a] * g.to_grid[a] - 0.5f;
        const float hi = static_cast<float>(g.dims[a] - 1);
        x = x < 0.0f ? 0.0f : (x > hi ? hi : x);
        int i = static_cast<int>(x);
        if (i > g.dims[a] - 2) {
            i = g.dims[a] - 2;
        }
        idx[a] = i;
        c.f[a] = x - static_cast<float>(i);
    }
    c.base = idx[0] + g.dims[0] * (idx[1] + g.dims[1] * idx[2]);
    return c;
}

// The 8 trilinear weights in the order (dx, dy, dz) = (0,0,0), (1,0,0), (0,1,0), (1,1,0), …
PLIANT_HOST_DEVICE inline void corner_weights(const Corner& c, float w[8]) {
    const float x1 = c.f[0], y1 = c.f[1], z1 = c.f[2];
    const float x0 = 1.0f - x1, y0 = 1.0f - y1, z0 = 1.0f - z1;
    w[0] = x0 * y0 * z0;
    w[1] = x1 * y0 * z0;
    w[2] = x0 * y1 * z0;
    w[3] = x1 * y1 * z0;
    w[4] = x0 * y0 * z1;
    w[5] = x1 * y0 * z1;
    w[6] = x0 * y1 * z1;
    w[7] = x1 * y1 * z1;
}

PLIANT_HOST_DEVICE inline void corner_offsets(const GridView& g, std::int32_t o[8]) {
    const std::int32_t sy = g.dims[0], sz = g.dims[0] * g.dims[1];
    o[0] = 0;
    o[1] = 1;
    o[2] = sy;
    o[3] = sy + 1;
    o[4] = sz;
    o[5] = sz + 1;
    o[6] = sz + sy;
    o[7] = sz + sy + 1;
}

// Raw parameters (s, a_r, a_g, a_b) at corner c.
PLIANT_HOST_DEVICE inline void interpolate(const GridView& g, const Corner& c, float out[4]) {
    float w[8];
    std::int32_t o[8];
    corner_weights(c, w);
    corner_offsets(g, o);
    out[0] = out[1] = out[2] = out[3] = 0.0f;
    for (int k = 0; k < 8; ++k) {
        const float* p = g.params + 4 * static_cast<std::int64_t>(c.base + o[k]);
        out[0] += w[k] * p[0];
        out[1] += w[k] * p[1];
        out[2] += w[k] * p[2];
        out[3] += w[k] * p[3];
    }
}

// Clips the ray o + t d (d unit length) to the grid's box [0, e]; false when it misses.
PLIANT_HOST_DEVICE inline bool clip_ray(const GridView& g, const float o[3], const float d[3],
                                        float& t0, float& t1) {
    t0 = 0.0f;
    t1 = 3.0e38f;
    for (int a = 0; a < 3; ++a) {
        if (std::fabs(d[a]) < 1e-12f) {
            if (o[a] < 0.0f || o[a] > g.extent[a]) {
                return false;
            }
            continue;
        }
        const float inv = 1.0f / d[a];
        float ta = (0.0f - o[a]) * inv, tb = (g.extent[a] - o[a]) * inv;
        if (ta > tb) {
            const float tmp = ta;
            ta = tb;
            tb = tmp;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    return t1 > t0;
}

// Forward pass of one ray. record(const SampleRecord&) is called for every evaluated sample in
// order (a no-op for plain rendering; the trainer stores them for backward()).
template <typename Record>
PLIANT_HOST_DEVICE RayOutput march(const GridView& g, const float o[3], const float d[3],
                                   float step, const float background[3], float min_transmittance,
                                   Record&& record) {
    RayOutput out;
    float t0 = 0.0f, t1 = 0.0f;
    float T = 1.0f;
    float acc[3] = {0, 0, 0};
    if (clip_ray(g, o, d, t0, t1)) {
        const float chord = t1 - t0;
        const int n = static_cast<int>(std::ceil(chord / step));
        for (int k = 0; k < n; ++k) {
            const float ts = t0 + static_cast<float>(k) * step;
            const float len = k + 1 < n ? step : t1 - ts;
            if (!(len > 0.0f)) {
                break;
            }
            const float t = ts + 0.5f * len;
            const float u[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
            SampleRecord r;
            r.corner = locate(g, u);
            if (g.occupied != nullptr && g.occupied[r.corner.base] == 0) {
                continue;
            }
            float raw[4];
            interpolate(g, r.corner, raw);
            r.s = raw[0];
            const float sigma = softplus(raw[0]) * DENSITY_SCALE;
            r.alpha = 1.0f - std::exp(-sigma * len);
            r.length = len;
            r.t = t;
            r.c[0] = sigmoid(raw[1]);
            r.c[1] = sigmoid(raw[2]);
            r.c[2] = sigmoid(raw[3]);
            const float w = T * r.alpha;
            acc[0] += w * r.c[0];
            acc[1] += w * r.c[1];
            acc[2] += w * r.c[2];
            T *= 1.0f - r.alpha;
            ++out.samples;
            record(r);
            if (T < min_transmittance) {
                break;
            }
        }
    }
    for (int c = 0; c < 3; ++c) {
        out.rgb[c] = acc[c] + T * background[c];
    }
    out.transmittance = T;
    return out;
}

// ∂(raw parameters)/∂u contracted with d_raw = ∂L/∂(s, a_r, a_g, a_b) at a sample: the spatial
// gradient of the trilinear interpolation, ∂L/∂u_a = to_grid_a Σ_ch d_raw_ch Σ_q p_q,ch ∂w_q/∂f_a
// (the clamp at the faces' half voxels is not differentiated). Used to refine camera poses.
PLIANT_HOST_DEVICE inline void position_gradient(const GridView& g, const Corner& c,
                                                 const float d_raw[4], float out[3]) {
    std::int32_t o[8];
    corner_offsets(g, o);
    float dot[8];
    for (int q = 0; q < 8; ++q) {
        const float* p = g.params + 4 * static_cast<std::int64_t>(c.base + o[q]);
        dot[q] = d_raw[0] * p[0] + d_raw[1] * p[1] + d_raw[2] * p[2] + d_raw[3] * p[3];
    }
    const float x1 = c.f[0], y1 = c.f[1], z1 = c.f[2];
    const float x0 = 1.0f - x1, y0 = 1.0f - y1, z0 = 1.0f - z1;
    // Corner q = dx + 2 dy + 4 dz (corner_weights' order).
    out[0] = ((dot[1] - dot[0]) * y0 * z0 + (dot[3] - dot[2]) * y1 * z0 +
              (dot[5] - dot[4]) * y0 * z1 + (dot[7] - dot[6]) * y1 * z1) *
             g.to_grid[0];
    out[1] = ((dot[2] - dot[0]) * x0 * z0 + (dot[3] - dot[1]) * x1 * z0 +
              (dot[6] - dot[4]) * x0 * z1 + (dot[7] - dot[5]) * x1 * z1) *
             g.to_grid[1];
    out[2] = ((dot[4] - dot[0]) * x0 * y0 + (dot[5] - dot[1]) * x1 * y0 +
              (dot[6] - dot[2]) * x0 * y1 + (dot[7] - dot[3]) * x1 * y1) *
             g.to_grid[2];
}

// Backward pass of one ray: the samples march() recorded (n of them, in order), the ray's
// output colour C (with background) and g = ∂L/∂C. scatter(voxel, d[4]) receives ∂L/∂(raw
// parameters) of each corner voxel (8 calls per sample); per_sample(record, d_raw[4]) receives
// ∂L/∂(interpolated raw parameters) of each sample, before the scatter.
template <typename Scatter, typename PerSample>
PLIANT_HOST_DEVICE void backward(const GridView& g, const SampleRecord* samples, int n,
                                 const float C[3], const float grad_c[3], Scatter&& scatter,
                                 PerSample&& per_sample) {
    std::int32_t o[8];
    corner_offsets(g, o);
    // Running sums in double: S_k = C − prefix cancels.
    double T = 1.0;
    double prefix[3] = {0, 0, 0};
    for (int k = 0; k < n; ++k) {
        const SampleRecord& r = samples[k];
        const double w = T * r.alpha;
        prefix[0] += w * r.c[0];
        prefix[1] += w * r.c[1];
        prefix[2] += w * r.c[2];
        const double T_next = T * (1.0 - r.alpha);
        double cg = 0.0, sg = 0.0;
        for (int c = 0; c < 3; ++c) {
            cg += static_cast<double>(r.c[c]) * grad_c[c];
            sg += (static_cast<double>(C[c]) - prefix[c]) * grad_c[c];
        }
        const double d_sigma = r.length * (T_next * cg - sg);
        float d[4];
        d[0] = static_cast<float>(d_sigma * DENSITY_SCALE * sigmoid(r.s));
        for (int c = 0; c < 3; ++c) {
            d[1 + c] = static_cast<float>(w * grad_c[c] * r.c[c] * (1.0 - r.c[c]));
        }
        per_sample(r, d);
        float wt[8];
        corner_weights(r.corner, wt);
        for (int q = 0; q < 8; ++q) {
            const float dq[4] = {wt[q] * d[0], wt[q] * d[1], wt[q] * d[2], wt[q] * d[3]};
            scatter(r.corner.base + o[q], dq);
        }
        T = T_next;
    }
}

// backward() without the per-sample callback.
template <typename Scatter>
PLIANT_HOST_DEVICE void backward(const GridView& g, const SampleRecord* samples, int n,
                                 const float C[3], const float grad_c[3], Scatter&& scatter) {
    backward(g, samples, n, C, grad_c, scatter, [](const SampleRecord&, const float*) {});
}

}  // namespace pliant::nerf::detail
