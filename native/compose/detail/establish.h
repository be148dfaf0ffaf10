// compose/detail/establish.h — establish_contact that also hands over the organic cell.
#pragma once
#include "compose/compose.h"
#include "compose/detail/exact.h"

namespace genbrep::detail {

// §7.2–7.3 for one sheet; on success *cell is Q_c (and T_c) for the composition.
ComponentContact establish(const OrganicSheet& sheet, const SolidSet& solids,
                           const ComposeOptions& options, OrganicCell* cell);

}  // namespace genbrep::detail
