// StretchChains: the cloth's stretch constraints as chains of edges, each chain solved as a whole
// (material.stretch_solver = chains; material.hpp).
//
// Gauss-Seidel over single edges, one XPBD iteration per substep, moves a correction one edge
// per sweep: along the long paths of a hanging skirt it converges slowly, and cloth stretches
// under its own weight the more the fewer the substeps. Here the edges are cut into chains,
// paths through the mesh that go as straight as they can (on a grid sheet: its rows, columns and
// both diagonals), the chains are grouped into families whose chains share no vertex, and each
// chain is solved in one step: one linearized XPBD step for all its constraints at once,
// (J W Jᵀ + α̃) Δλ = −C, Δx = W Jᵀ Δλ (Macklin, Müller, Chentanez, "XPBD", MIG 2016, eq. 9 with
// λ = 0), tridiagonal for a chain and solved in linear time by the Thomas algorithm (as Deul,
// Kugelstadt, Weiler and Bender, "Direct Position-Based Solver for Stiff Rods", CGF 2018, solve
// trees of rod constraints), with a Levenberg-Marquardt damping that grows with each edge's strain
// (detail/constraint_kernels.hpp has the system; the constants below say why). The families follow
// each other (block Gauss-Seidel); then the solver's sweep over the single edges runs as XPBD's
// second iteration from the chains' λ, spreading what the families leave on each other.
//
// Where pins ask for more length than the cloth has (the twist scene) chains do worse than single
// edges: the cloth, holding its length, is squeezed into more self-contact. Measured against
// single edges: docs/performance.md ("Cloth") and docs/journal/2026-11-28-stretch-chains.md.
//
// Decomposition (once per mesh, from the rest shape): at every vertex the incident edges are
// paired greedily, most nearly opposite first (at least 120° apart); a chain continues through a
// vertex along its pair. Chains are followed from their ends, then around cycles (cut where they
// start), and cut where they would visit a vertex twice; they are coloured greedily, longest
// first (constraint_coloring.hpp), so that the chains of a colour (a family) share no vertex.
// Deterministic: every choice is made in index order. Within a family the chains, longest first,
// are laid out four by four as the kernel's packets (detail::ChainPacket): a shorter chain repeats
// its last vertex, a missing one uses the padding vertex (index num_vertices: the caller's vertex
// array has one more record, with inverse mass 0, that no chain uses). Only a family's last packet
// has missing chains, and families run one after the other, so no two threads write the padding
// vertex.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

// The chains' Levenberg-Marquardt damping (detail/constraint_kernels.hpp): the diagonal
// w_k + w_{k+1} of edge k's row is scaled by 1 + ε + κ |C_k| / ℓ_k. Undamped, a chain's exact
// step is too bold where the constraints cannot all hold: a straight chain between two fixed
// vertices is singular (a uniform tension changes no length to first order), and in a sheet
// pulled taut the families' full steps undo one another, so a small uniform ε lets such a sheet
// jitter; a large uniform ε also damps the long chains of a hanging sheet, which then stretches.
// Damping where the edges are strained keeps both: with ε = 0.01 and κ = 1 a sheet pulled 1 % to
// 50 % beyond its width between pins comes to rest
// (StretchChains.ASheetPulledTautBetweenPinsComesToRest) and a hanging sheet keeps its length
// (bench_cloth). The values tried: docs/journal/2026-11-28-stretch-chains.md.
inline constexpr double CHAIN_REGULARIZATION = 0.01;
inline constexpr double CHAIN_STRAIN_REGULARIZATION = 1.0;

class StretchChains {
public:
    StretchChains() = default;
    // edges[i] = {a, b} (vertices in [0, #positions), rest.size() = edges.size()) with rest
    // length rest[i] (m); positions: the rest shape, for the pairing's angles. Every edge is in
    // exactly one chain. O(E log E). InvalidInput when a chain's vertices already lie on chains
    // of 64 families (color_constraints' limit; a grid needs 4, jittered grids and icospheres of
    // up to 163,842 vertices needed at most 13).
    StretchChains(std::span<const std::array<std::int32_t, 2>> edges, std::span<const double> rest,
                  std::span<const Vec3d> positions);

    std::int32_t num_families() const {
        return static_cast<std::int32_t>(m_family_packets.size()) - 1;
    }
    // Packets [first_packet(f), first_packet(f + 1)) make family f.
    std::int32_t first_packet(std::int32_t f) const {
        return m_family_packets[static_cast<std::size_t>(f)];
    }
    std::int32_t num_packets() const { return static_cast<std::int32_t>(m_edge_rows.size()) - 1; }
    detail::ChainPacket packet(std::int32_t p) const;
    // The scratch packet p uses: its slice of CHAIN_SCRATCH_PER_ROW doubles per edge row.
    std::int64_t scratch_offset(std::int32_t p) const {
        return static_cast<std::int64_t>(m_edge_rows[static_cast<std::size_t>(p)]) *
               detail::CHAIN_SCRATCH_PER_ROW;
    }
    std::int64_t scratch_size() const {
        return static_cast<std::int64_t>(m_edge_rows.back()) * detail::CHAIN_SCRATCH_PER_ROW;
    }
    std::int32_t num_chains() const { return static_cast<std::int32_t>(m_chains.size()); }
    // Chain c's vertices in order (chains numbered family by family, longest first).
    std::span<const std::int32_t> chain(std::int32_t c) const {
        return m_chains[static_cast<std::size_t>(c)];
    }
    std::int32_t padding_vertex() const { return m_padding_vertex; }

private:
    std::vector<std::vector<std::int32_t>> m_chains;
    std::vector<std::int32_t> m_family_packets{0};
    std::vector<std::int32_t> m_edge_rows{0};  // packet p: edge rows [m_edge_rows[p], [p + 1])
    std::vector<std::int32_t> m_vertex_rows;  // 4 per row; packet p's start at row edge_rows[p] + p
    std::vector<double> m_rest_rows;          // 4 per edge row, −1 for padding
    std::vector<std::int32_t> m_edge_index_rows;  // 4 per edge row: the edge's index, −1: padding
    std::int32_t m_padding_vertex = 0;
};

}  // namespace pliant::cloth
