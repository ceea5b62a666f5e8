#include "pliant/cloth/solver.hpp"

namespace pliant::cloth {

ClothSolver::ClothSolver(const geometry::TriangleMeshD& rest_mesh, const ClothMaterial& material,
                         std::span<const std::int32_t> pinned)
    : m_model(rest_mesh, material, pinned), m_stepper(m_model) {}

}  // namespace pliant::cloth
