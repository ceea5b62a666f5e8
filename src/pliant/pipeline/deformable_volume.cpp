#include "pliant/pipeline/deformable_volume.hpp"

#include <fmt/format.h>

#include <string>

#include "pliant/core/error.hpp"
#include "pliant/io/tetgen.hpp"

namespace pliant::pipeline {

DeformableVolume::DeformableVolume(const volume::Volume& source, const volume::TransferFunction* tf,
                                   const pbd::TetGridOptions& grid_options,
                                   const std::filesystem::path& mesh,
                                   const pbd::SoftBodyOptions& body_options)
    : m_source(&source) {
    if (mesh.empty()) {
        pbd::TetGridOptions options = grid_options;
        options.tf = tf;
        m_grid = std::make_unique<pbd::TetGrid>(pbd::build_tet_grid(source, options));
        if (m_grid->mesh.tets.empty()) {
            throw InvalidInput(fmt::format(
                "no visible voxel under the transfer function '{}', so no tet to deform (use "
                "--full-box or another --tf)",
                tf != nullptr ? tf->name : std::string("alpha > 0")));
        }
        m_body = std::make_unique<pbd::SoftBody>(*m_grid, body_options);
    } else {
        m_mesh = io::read_tetgen(mesh);
        if (m_mesh.tets.empty()) {
            throw InvalidInput(mesh.string() + ": the mesh has no tets");
        }
        m_body = std::make_unique<pbd::SoftBody>(m_mesh, body_options);
    }
    m_resampler = std::make_unique<volume::Resampler>(source, rest().tets, rest().positions,
                                                      volume::ResampleOptions{.tf = tf});
}

DeformableVolume::~DeformableVolume() = default;

void DeformableVolume::reset_body() {
    const pbd::SoftBodyOptions options = m_body->options();
    m_body = m_grid ? std::make_unique<pbd::SoftBody>(*m_grid, options)
                    : std::make_unique<pbd::SoftBody>(m_mesh, options);
}

volume::Volume DeformableVolume::target_like() const {
    return volume::Volume::allocate(m_source->dims(), m_source->type(), m_source->spacing(),
                                    m_source->origin());
}

volume::InverseMapStats DeformableVolume::build_map(volume::InverseMap& map) const {
    return build_map(m_body->positions(), map);
}

volume::InverseMapStats DeformableVolume::build_map(std::span<const Vec3f> positions,
                                                    volume::InverseMap& map) const {
    return map.build(*m_source, *m_source, rest().tets, rest().positions, positions,
                     {.node_voxels = m_grid ? m_grid->cell_voxels : 4});
}

ResampleMode parse_resample_mode(const std::string& text) {
    if (text == "exact") {
        return ResampleMode::exact;
    }
    if (text == "map") {
        return ResampleMode::map;
    }
    throw InvalidInput(fmt::format("resample mode '{}' is not one of exact, map", text));
}

const char* name(ResampleMode mode) {
    return mode == ResampleMode::map ? "map" : "exact";
}

volume::ResampleStats DeformableVolume::resample(volume::Volume& target) const {
    return resample(m_body->positions(), target);
}

volume::ResampleStats DeformableVolume::resample(std::span<const Vec3f> positions,
                                                 volume::Volume& target) const {
    return m_resampler->resample(positions, target);
}

}  // namespace pliant::pipeline
