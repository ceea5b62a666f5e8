#include "pliant/nerf/environment_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"
#include "pliant/nerf/detail/field_kernel.hpp"

namespace pliant::nerf {

EnvironmentMap::EnvironmentMap(int width, float color_raw) {
    if (width < 2 || width > 4096 || width % 2 != 0) {
        throw InvalidInput(fmt::format(
            "nerf::EnvironmentMap: width {}, expected an even value in [2, 4096]", width));
    }
    m_width = width;
    m_height = width / 2;
    m_params.assign(static_cast<std::size_t>(3 * num_texels()), color_raw);
}

EnvironmentTexels EnvironmentMap::locate(const float d[3]) const {
    constexpr float PI = std::numbers::pi_v<float>;
    const float phi = std::atan2(d[1], d[0]);
    const float theta = std::acos(std::clamp(d[2], -1.0f, 1.0f));
    float u = (phi + PI) / (2.0f * PI) * static_cast<float>(m_width) - 0.5f;
    float v = theta / PI * static_cast<float>(m_height) - 0.5f;
    v = std::clamp(v, 0.0f, static_cast<float>(m_height - 1));
    const float uf = std::floor(u);
    const float fu = u - uf;
    int i0 = static_cast<int>(uf) % m_width;
    if (i0 < 0) {
        i0 += m_width;
    }
    const int i1 = (i0 + 1) % m_width;
    const int j0 = std::min(static_cast<int>(v), m_height - 2 < 0 ? 0 : m_height - 2);
    const int j1 = std::min(j0 + 1, m_height - 1);
    const float fv = v - static_cast<float>(j0);
    EnvironmentTexels t;
    t.index = {i0 + m_width * j0, i1 + m_width * j0, i0 + m_width * j1, i1 + m_width * j1};
    t.weight = {(1.0f - fu) * (1.0f - fv), fu * (1.0f - fv), (1.0f - fu) * fv, fu * fv};
    return t;
}

void EnvironmentMap::color(const EnvironmentTexels& t, float rgb[3]) const {
    float raw[3] = {0, 0, 0};
    for (int q = 0; q < 4; ++q) {
        const float* p = m_params.data() + 3 * static_cast<std::int64_t>(t.index[q]);
        for (int c = 0; c < 3; ++c) {
            raw[c] += t.weight[q] * p[c];
        }
    }
    for (int c = 0; c < 3; ++c) {
        rgb[c] = detail::sigmoid(raw[c]);
    }
}

void EnvironmentMap::save_state(ByteWriter& out) const {
    out.put(m_width);
    out.put_vector(m_params);
}

void EnvironmentMap::load_state(ByteReader& in, int width) {
    const int stored = in.get<int>("environment.width");
    if (stored != width) {
        throw InvalidInput(fmt::format("{}: environment map of width {}, expected {}", in.source(),
                                       stored, width));
    }
    EnvironmentMap map(width, 0.0f);
    in.get_vector("environment.params", map.m_params,
                  static_cast<std::int64_t>(map.m_params.size()));
    *this = std::move(map);
}

}  // namespace pliant::nerf
