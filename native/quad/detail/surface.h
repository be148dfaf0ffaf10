// quad/detail/surface.h — internals of quad/: one organic component as the layout sees it (the
// surface, its field and its refinement for tracing), and how a step reports and stops.
#pragma once
#include <atomic>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/numbers.h"
#include "core/types.h"
#include "field/field.h"
#include "partition/partition.h"
#include "quad/quad.h"

namespace genbrep::quad_detail {

// Set by the layout search once an attempt's result can no longer be used (an earlier
// choice of the same batch made the search stop, quad.cpp): the attempt gives up at its
// next check (between phases, sweeps, rounds) instead of running to its end. Default: never.
class Dropped {
 public:
  Dropped() = default;
  explicit Dropped(const std::atomic<bool>* flag) : flag_(flag) {}
  // Throws Error{StageFailure} once the attempt is dropped.
  void check() const {
    GENBREP_CHECK(!stopped(), Code::StageFailure,
                  "quad: a layout choice dropped (the search stopped before it)");
  }
  bool stopped() const { return flag_ && flag_->load(std::memory_order_relaxed); }

 private:
  const std::atomic<bool>* flag_ = nullptr;
};


// What a step says about its work, as QuadResult splits it: `warnings` where the cage
// falls short of what was asked (a repair, a squeezed quad, a fallback), `notes` on how it
// was made (refinement, collapsed slivers, the layout choice kept).
struct Messages {
  Diagnostics warnings;
  Diagnostics notes;
  void append(const Messages& other) {
    warnings.insert(warnings.end(), other.warnings.begin(), other.warnings.end());
    notes.insert(notes.end(), other.notes.begin(), other.notes.end());
  }
};

// The design with one component's triangles split round its singular vertices (two edges
// per separatrix at each) and then `levels` (≥ 0) times (refine.cpp): the same surface,
// finer for tracing; vertex indices and the first child of every triangle keep their
// index, so loops and singularities carry over unchanged. Empty (no faces) where nothing
// needed splitting.
// Separatrices follow mesh edges: a component is refined for tracing (at most
// QuadOptions::max_refine_levels times) until a target cage edge spans at least this many
// mesh edges, so that a traced curve can stay near its field line.
constexpr double kTraceEdgesPerCageEdge = 4.0;
struct RefinedDesign {
  TriMesh mesh;
  Partition partition;
  CrossField field;
  int levels = 0;
};
RefinedDesign refine_component(const TriMesh& design, const Partition& partition,
                               const CrossField& field, int component, int levels);

// Read-only geometry of one organic component with the field on it.
struct Surface {
  Surface(const TriMesh& mesh, const Partition& partition, const CrossField& field,
          int component);
  const TriMesh& mesh;
  const Partition& partition;
  const CrossField& field;
  int component;
  std::vector<Vec3> point;          // per vertex
  std::vector<Vec3> face_normal;    // per face (unit)
  std::vector<Vec3> vertex_normal;  // per vertex, from the component's faces only
  std::vector<double> vertex_size;  // mean target edge length of the component faces around
  std::vector<int> vertices;        // vertices touched by the component's faces
  bool in(int face) const { return face >= 0 && partition.face_component[face] == component; }
  // Face of the halfedge (-1 at a mesh border). Inline: the layout's flood fill and
  // patch examination call these for every halfedge of the component, every round.
  int face(int halfedge) const {
    const auto fh = mesh.face_handle(mesh.halfedge_handle(halfedge));
    return fh.is_valid() ? fh.idx() : -1;
  }
  int from(int halfedge) const {
    return mesh.from_vertex_handle(mesh.halfedge_handle(halfedge)).idx();
  }
  int to(int halfedge) const { return mesh.to_vertex_handle(mesh.halfedge_handle(halfedge)).idx(); }
  int opposite(int halfedge) const { return halfedge ^ 1; }
  // Next outgoing halfedge counter-clockwise around from(h): the face between them is face(h).
  int ccw(int halfedge) const;
  double corner_angle(int halfedge) const;  // angle at from(h) inside face(h)
  // The cross direction of `face` closest to `d` (one of its four rotations).
  Vec3 snap(int face, const Vec3& d) const;
  // Target edge length along direction d on `face` (size_u or size_v, whichever arm d follows).
  double size_along(int face, const Vec3& d) const;
  Vec3 tangent(int vertex, const Vec3& d) const;  // d projected into the vertex tangent plane
  // Quads the field's sizes put on a component face at density 1: area / (size_u · size_v).
  double face_quads(int face) const { return quads_on_face[face]; }
  std::vector<double> quads_on_face;  // per face; 0 off the component
};

}  // namespace genbrep::quad_detail
