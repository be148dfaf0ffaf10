// relax/detail/relax_detail.h — internals of the relax stage, shared by its .cpp files.
// The geometric queries hide CGAL behind a pointer to an implementation, so only the
// relax sources that define them include CGAL.
#pragma once
#include <memory>
#include <utility>
#include <vector>

#include "core/context.h"
#include "core/types.h"
#include "partition/partition.h"
#include "relax/relax.h"

namespace genbrep::relax_detail {

// Closest points on the ORIGINAL design (an AABB tree of its triangles), with the
// design's unit normal at the hit: every vertex the stage moves or creates goes through
// nearest(), which is what keeps the result on the design surface.
class SurfaceProjector {
 public:
  explicit SurfaceProjector(const TriangleMesh& design);
  ~SurfaceProjector();
  struct Hit {
    Vec3 point;
    int triangle = -1;
  };
  Hit nearest(const Vec3& p) const;
  // Unit normal of design triangle t; for a degenerate (zero-area) triangle the mean of
  // its corners' area-weighted vertex normals.
  const Vec3& normal(int triangle) const { return normals_[triangle]; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<Vec3> normals_;
};

// Distance to a set of segments (the original loops), with the nearest point and the
// segment's tag (its loop).
class PolylineDistance {
 public:
  struct Segment {
    Vec3 a, b;
    int tag = -1;
  };
  explicit PolylineDistance(std::vector<Segment> segments);
  ~PolylineDistance();
  struct Hit {
    Vec3 point;
    double distance = 0;
    int tag = -1;
  };
  Hit nearest(const Vec3& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Step (a): CGAL isotropic remeshing of the triangles with in_channel[t] != 0, at a
// uniform target edge length, label borders as sliding constraints, interior vertices
// projected with `projector`. Returns the new arrays (triangle_source left empty) and a
// label per new triangle. Throws Error{Internal} if CGAL rejects the input.
struct LabelledMesh {
  TriangleMesh mesh;
  std::vector<int> labels;
};
LabelledMesh remesh_channel(const TriangleMesh& mesh, const std::vector<int>& labels,
                            const std::vector<char>& in_channel, double target_edge_length,
                            int iterations, const SurfaceProjector& projector);

// Step (b): Taubin curve smoothing of `loops` on `mesh` (positions change, connectivity
// does not), then tangential relaxation of the channel vertices off label borders.
// `labels` per triangle; `original` the loops before relaxation; d the displacement cap.
struct Smoothing {
  int accepted_moves = 0;
  int skipped_moves = 0;   // loop moves refused (a flip, a collapse, or beyond d)
  int fixed_vertices = 0;  // loop vertices where several label borders meet: kept in place
};
Smoothing smooth_loops(TriMesh& mesh, const std::vector<int>& labels,
                       const std::vector<BoundaryLoop>& loops, const SurfaceProjector& projector,
                       const PolylineDistance& original, double d, const RelaxOptions& options,
                       const Context& context);

// After the remesh: triangles facing against the design (folded caps CGAL can leave
// where a border vertex slid past a neighbour) are unfolded by flipping their longest
// edge (not a label border) or moving a corner off the label borders to its neighbours'
// mean, each kept only if it improves. Triangles with origin[t] >= 0 are untouched
// design triangles and are not examined.
struct FoldRepair {
  int folded = 0;     // triangles found folded
  int remaining = 0;  // still folded after the repair
};
FoldRepair repair_folds(TriMesh& mesh, const std::vector<int>& labels,
                        const std::vector<int>& origin, const SurfaceProjector& projector);

// How well triangle (a, b, c) faces along the design: cos of the angle between its
// normal and the design normal at the projection of its centroid (≤ 0: facing against
// the design, "flipped"), and the best such cos over its centroid and corners (a good
// triangle straddling a crease agrees well with one side); both -2 for a triangle
// without area relative to its size. `corner_normals`, if given, are the design normals
// at the corners' projections (saves three queries).
struct Agreement {
  double centroid = -2;
  double best = -2;
};
Agreement normal_agreement(const Vec3& a, const Vec3& b, const Vec3& c,
                           const SurfaceProjector& projector, const Vec3* corner_normals = nullptr);

// Vertices within `rings` rings of the given seed vertices (seeds included).
std::vector<char> vertex_rings(const TriMesh& mesh, const std::vector<int>& seeds, int rings);

}  // namespace genbrep::relax_detail
