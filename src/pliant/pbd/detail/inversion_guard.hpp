// The soft body's inversion guard (soft_body.hpp, "Inversion guard"), after each substep's volume
// sweep: the tets the sweep flagged at risk (volume below AT_RISK_RATIO · V0 before their
// projection) get the hard unilateral constraint C = V − GUARD_RATIO · V0 ≥ 0 (projection.hpp's
// guard_tet), in colour order on one thread, in passes until one moves nothing (GUARD_PASSES at
// most). Deterministic: the flags are set by index, the guard runs serially in a fixed order.
#pragma once

#include <cstdint>
#include <vector>

#include "pliant/pbd/detail/constraint_layout.hpp"
#include "pliant/pbd/detail/projection.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"

namespace pliant::pbd::detail {

// The tets at risk of inversion, written by project_tets (constraint_sweep.hpp) and read and
// cleared by guard_flagged_tets. Invariant: colour_at_risk[c] = 1 exactly when a tet of colour c
// has tet_at_risk = 1 (the guard skips the other colours).
struct InversionFlags {
    std::vector<std::uint8_t> tet_at_risk;     // #T, colour order: 1 = at risk
    std::vector<std::uint8_t> colour_at_risk;  // #tet colours: 1 = a tet of the colour is
    std::vector<std::int64_t> guarded;         // scratch: the flagged tets, colour order
};

// Flags sized for `tets`, nothing flagged.
InversionFlags unflagged(const TetConstraints& tets);

// The guard on x (#V, world units, packed with the substep's inverse masses; read and written):
// collects the flagged tets colour by colour (clearing their flags), projects guard_tet over them
// in passes, then flags again, for the next substep, those still below AT_RISK_RATIO · V0 (V0 the
// current rest volume): their own projection may lift them above the kernels' threshold before
// later colours push them back. O(flagged tets + tet colours); one thread.
void guard_flagged_tets(Float4* x, const TetConstraints& tets, InversionFlags& flags);

// The same guard on positions held as arrays in a solver order (lattice_sweep.hpp): vertex v at
// p's index solver_index[v]. The same arithmetic on the same values: the same bits as the guard
// on x holding those positions.
void guard_flagged_tets(const SoaPositions& p, const std::int32_t* solver_index,
                        const TetConstraints& tets, InversionFlags& flags);

}  // namespace pliant::pbd::detail
