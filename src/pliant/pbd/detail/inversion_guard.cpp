#include "pliant/pbd/detail/inversion_guard.hpp"

#include <algorithm>
#include <cstddef>

namespace pliant::pbd::detail {

InversionFlags unflagged(const TetConstraints& tets) {
    InversionFlags flags;
    flags.tet_at_risk.assign(tets.vertices.size(), 0);
    flags.colour_at_risk.assign(static_cast<std::size_t>(tets.coloring.num_colors()), 0);
    return flags;
}

void guard_flagged_tets(Float4* x, const TetConstraints& tets, InversionFlags& flags) {
    const ConstraintColoring& coloring = tets.coloring;
    // Step 1: the flagged tets in colour order, flags cleared.
    flags.guarded.clear();
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        if (flags.colour_at_risk[static_cast<std::size_t>(c)] == 0) {
            continue;
        }
        flags.colour_at_risk[static_cast<std::size_t>(c)] = 0;
        for (std::int64_t k = coloring.offsets[static_cast<std::size_t>(c)];
             k < coloring.offsets[static_cast<std::size_t>(c) + 1]; ++k) {
            if (flags.tet_at_risk[static_cast<std::size_t>(k)] != 0) {
                flags.tet_at_risk[static_cast<std::size_t>(k)] = 0;
                flags.guarded.push_back(k);
            }
        }
    }
    // Step 2: passes of guard_tet over them in that order until one moves none.
    for (int pass = 0; pass < GUARD_PASSES && !flags.guarded.empty(); ++pass) {
        bool moved = false;
        for (const std::int64_t k : flags.guarded) {
            moved = guard_tet(x, tets.vertices[static_cast<std::size_t>(k)],
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
        if (tet_volume(x, tets.vertices[i]) < tets.rest_volumes[i] * AT_RISK_RATIO) {
            flags.tet_at_risk[i] = 1;
            const auto colour =
                std::upper_bound(coloring.offsets.begin(), coloring.offsets.end(), k) -
                coloring.offsets.begin() - 1;
            flags.colour_at_risk[static_cast<std::size_t>(colour)] = 1;
        }
    }
}

}  // namespace pliant::pbd::detail
