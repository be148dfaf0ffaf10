// compose/detail/establish.h — establish_contact that also hands over the organic cell.
#pragma once
#include <functional>

#include "compose/compose.h"
#include "compose/detail/exact.h"

namespace genbrep::detail {

// §7.2–7.3 for one sheet; on success *cell is Q_c (and T_c) for the composition. The
// sheet is pulled into `solids` and cut at the union of `cut_solids` bordering its loops:
// the solids as the Booleans take them (compose grows them), so that the caps lie on
// their faces exactly; the same solids with other positions.
ComponentContact establish(const OrganicSheet& sheet, const SolidSet& solids, const SolidSet& cut_solids,
                           const ComposeOptions& options, OrganicCell* cell);

// The η-doubling loop with any pull: `pull(η)` returns the pulled sheet (same loops as
// `sheet`, the unpulled surface that sets η₀ and names the gaps).
using SheetPuller = std::function<SheetPull(double eta)>;
ComponentContact establish_with(const OrganicSheet& sheet, const SheetPuller& pull, const SolidSet& solids,
                                const SolidSet& cut_solids, const ComposeOptions& options, OrganicCell* cell);

// The same for a cage (pull_cage); contact.cage is the pulled cage that was established.
// `sides`: σ per chain when known (pull_cage).
ComponentContact establish_cage(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                                const SolidSet& solids, const SolidSet& cut_solids, const ComposeOptions& options,
                                OrganicCell* cell, const std::vector<int>& sides = {});

}  // namespace genbrep::detail
