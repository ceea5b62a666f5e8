#include "pliant/pbd/detail/inversion_guard.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace pliant::pbd::detail {

InversionFlags unflagged(const TetConstraints& tets) {
    InversionFlags flags;
    flags.tet_at_risk.assign(tets.vertices.size(), 0);
    flags.colour_at_risk.assign(static_cast<std::size_t>(tets.coloring.num_colors()), 0);
    return flags;
}

namespace {

// The guard's access to the vertices: on Float4s by vertex index.
struct PackedVertices {
    Float4* x;
    bool guard(const geometry::Tet& t, float rest_volume) const {
        return guard_tet(x, t, rest_volume);
    }
    float volume(const geometry::Tet& t) const { return tet_volume(x, t); }
};

// On arrays in a solver order: the tet's 4 vertices gathered into Float4s, guard_tet on them, the
// positions scattered back when it moved them.
struct SolverOrderVertices {
    const SoaPositions& p;
    const std::int32_t* solver_index;
    void gather(const geometry::Tet& t, Float4 (&q)[4]) const {
        for (std::size_t k = 0; k < 4; ++k) {
            const auto i = static_cast<std::size_t>(solver_index[t[k]]);
            q[k] = {p.x[i], p.y[i], p.z[i], p.w[i]};
        }
    }
    bool guard(const geometry::Tet& t, float rest_volume) const {
        Float4 q[4];
        gather(t, q);
        if (!guard_tet(q, LOCAL, rest_volume)) {
            return false;
        }
        for (std::size_t k = 0; k < 4; ++k) {
            const auto i = static_cast<std::size_t>(solver_index[t[k]]);
            p.x[i] = q[k].x;
            p.y[i] = q[k].y;
            p.z[i] = q[k].z;
        }
        return true;
    }
    float volume(const geometry::Tet& t) const {
        Float4 q[4];
        gather(t, q);
        return tet_volume(q, LOCAL);
    }
    static constexpr geometry::Tet LOCAL{0, 1, 2, 3};
};

template <typename Vertices>
void guard_flagged(Vertices& x, const TetConstraints& tets, InversionFlags& flags) {
    const ConstraintColoring& coloring = tets.coloring;
    // Step 1: the flagged tets in colour order, flags cleared.
    flags.guarded.clear();
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        if (flags.colour_at_risk[static_cast<std::size_t>(c)] == 0) {
            continue;
        }
        flags.colour_at_risk[static_cast<std::size_t>(c)] = 0;
        // Few flags among many tets: 8 flags at a time skipped while all are 0.
        std::uint8_t* at_risk = flags.tet_at_risk.data();
        const std::int64_t end = coloring.offsets[static_cast<std::size_t>(c) + 1];
        for (std::int64_t k = coloring.offsets[static_cast<std::size_t>(c)]; k < end;) {
            std::uint64_t eight = 0;
            if (k + 8 <= end) {
                std::memcpy(&eight, at_risk + k, sizeof eight);
                if (eight == 0) {
                    k += 8;
                    continue;
                }
            }
            if (at_risk[k] != 0) {
                at_risk[k] = 0;
                flags.guarded.push_back(k);
            }
            ++k;
        }
    }
    // Step 2: passes of guard_tet over them in that order until one moves none.
    for (int pass = 0; pass < GUARD_PASSES && !flags.guarded.empty(); ++pass) {
        bool moved = false;
        for (const std::int64_t k : flags.guarded) {
            moved = x.guard(tets.vertices[static_cast<std::size_t>(k)],
                            tets.rest_volumes[static_cast<std::size_t>(k)]) ||
                    moved;
        }
        if (!moved) {
            break;
        }
    }
    // Step 3: those still below AT_RISK_RATIO · V0 stay flagged for the next substep (an earlier
    // colour sharing their vertices can have lifted them above the threshold in the sweep too).
    for (const std::int64_t k : flags.guarded) {
        const auto i = static_cast<std::size_t>(k);
        if (x.volume(tets.vertices[i]) < tets.rest_volumes[i] * AT_RISK_RATIO) {
            flags.tet_at_risk[i] = 1;
            const auto colour =
                std::upper_bound(coloring.offsets.begin(), coloring.offsets.end(), k) -
                coloring.offsets.begin() - 1;
            flags.colour_at_risk[static_cast<std::size_t>(colour)] = 1;
        }
    }
}

}  // namespace

void guard_flagged_tets(Float4* x, const TetConstraints& tets, InversionFlags& flags) {
    PackedVertices vertices{x};
    guard_flagged(vertices, tets, flags);
}

void guard_flagged_tets(const SoaPositions& p, const std::int32_t* solver_index,
                        const TetConstraints& tets, InversionFlags& flags) {
    SolverOrderVertices vertices{p, solver_index};
    guard_flagged(vertices, tets, flags);
}

}  // namespace pliant::pbd::detail
