// pull/detail/side.h — helpers shared by the sheet pull (pull.cpp) and the cage pull
// (cage.cpp): vertex adjacency of a triangle sheet and σ, the side of a loop's solids the
// organic surface lies on (§7.1).
#pragma once
#include <vector>

#include "pull/pull.h"

namespace genbrep::detail {

// Sorted, unique vertex neighbours of every vertex of `mesh`.
std::vector<std::vector<int>> vertex_adjacency(const TriangleMesh& mesh);

// σ of a loop: the majority side of the sheet vertices two and three rings in from the
// loop (ties: outside, +1). `distance` must have side +1.
int organic_side(const OrganicSheet& sheet, const SheetLoop& loop,
                 const std::vector<std::vector<int>>& adjacency, const SideDistance& distance);

}  // namespace genbrep::detail
