// core/cage.h — the quad control cage that crosses quad/ → fit/ → pull/ → compose/ and
// the binding. A cage is the Catmull–Clark control mesh of one organic component; its
// limit surface (OpenSubdiv, boundary interpolation EDGE_ONLY = Blender's Subdivision
// Surface boundary_smooth 'ALL', use_limit_surface on) approximates that component.
#pragma once
#include <vector>

#include "core/types.h"

namespace genbrep {

using Quads = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;

// How Blender's Subdivision Surface modifier must be set to show exactly the surface
// the fitter used (DESIGN.md, "Blender facts").
struct SubdivisionScheme {
  bool boundary_smooth_all = true;  // true: 'ALL' = OpenSubdiv VTX_BOUNDARY_EDGE_ONLY;
                                    // false: 'PRESERVE_CORNERS' = EDGE_AND_CORNER
  bool use_limit_surface = true;
  int quality = 3;
  int levels = 2;                   // viewport levels written on the modifier
};

struct QuadCage {
  int component = -1;               // organic component of the partition
  Vertices vertices;                // control points, design units
  Quads quads;                      // counter-clockwise seen from outside the design
  // One closed chain of cage vertices per partition boundary loop of the component,
  // ordered like the loop (organic side on the left).
  std::vector<std::vector<int>> boundary_chains;
  std::vector<int> chain_loop;      // partition loop index of each chain
  // Edge sharpness (Blender crease in [0, 1]) on cage edges, as vertex pairs.
  std::vector<std::array<int, 2>> crease_edges;
  std::vector<float> crease_values;
  SubdivisionScheme scheme;
};

}  // namespace genbrep
