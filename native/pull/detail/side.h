// pull/detail/side.h — helpers shared by the sheet pull (pull.cpp) and the cage pull
// (cage.cpp): vertex adjacency of a triangle sheet, σ, the side of a loop's solids the
// organic surface lies on (§7.1), and the fade of the boundary move into the interior.
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

// Ring distances over `adjacency`: `ring` holds 0 at the seeds and -1 elsewhere on entry;
// every vertex reachable from a seed gets its graph distance (multi-source BFS).
void fill_rings(const std::vector<std::vector<int>>& adjacency, std::vector<int>* ring);

// Linear fade over k rings: ring r moves by (1 − r/(k+1)) of its ring r−1 neighbours' mean
// move, rescaled. `move` holds the ring-0 moves on entry (other entries are overwritten for
// rings 1..k and left as they are beyond).
void fade_over_rings(const std::vector<std::vector<int>>& adjacency, const std::vector<int>& ring,
                     int k, std::vector<Vec3>* move);

}  // namespace genbrep::detail
