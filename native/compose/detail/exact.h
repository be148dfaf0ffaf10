// compose/detail/exact.h — the exact-construction meshes compose/ works on (internal).
// Everything from contact curves to the final Booleans runs on CGAL's Epeck kernel: the
// contact vertices are constructed exactly on the solid's planes, so the caps cut out of
// ∂S coincide exactly with ∂S and corefinement resolves them as coplanar faces instead of
// nearly coincident ones (the failure mode §8.1 warns of). Input vertices are doubles and
// convert back to the same doubles: faces from input solids keep the input's positions.
#pragma once
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <string>
#include <vector>

#include "core/types.h"
#include "pull/pull.h"

namespace genbrep::detail {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using ExactPoint = Exact::Point_3;
using ExactMesh = CGAL::Surface_mesh<ExactPoint>;

ExactMesh to_exact(const TriangleMesh& mesh);
// The same mesh in the double kernel (exact predicates, inexact constructions), vertex and
// face indices as in `mesh`: for tests on meshes whose points are doubles.
using InexactMesh = CGAL::Surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel::Point_3>;
InexactMesh to_inexact(const TriangleMesh& mesh);
// Rounds to doubles; vertex order is the mesh's.
TriangleMesh to_double(const ExactMesh& mesh);

// The exact composition rounded to doubles (round.cpp). Corefining operands that nearly
// coincide (a bolt in its bore exported separately: faces 1e-16 apart) gives edges far
// shorter than double precision; rounding their ends independently folds the slivers
// between them over their neighbours. Edges shorter than `tolerance` are first collapsed
// in exact arithmetic onto the end that is an input vertex (exactly a double) when one is,
// skipping collapses that would pinch the surface. No vertex moves by more than
// `tolerance`; the caller checks the rounded mesh (closed, no self-intersections).
struct Rounded {
  TriangleMesh mesh;          // triangle_source = face index, as to_double
  int collapsed = 0;          // edges collapsed
  int blocked = 0;            // short edges left: collapsing them would pinch the surface
  double longest = 0;         // longest edge collapsed, design units
  std::vector<Vec3> where;    // kept ends of the first collapsed edges
  int refined = 0;            // round_robustly: autorefinement rounds
  bool repaired = false;      // round_robustly: CGAL's local self-intersection repair ran
  bool intersecting = false;  // round_robustly: the result still crosses itself
};
Rounded round_to_doubles(ExactMesh mesh, double tolerance);

// round_to_doubles at 1e-10 × `scale`; where the rounded mesh crosses itself, at most 2
// rounds of: back to exact, autorefined, the cut-off patches removed, rounded again; what
// still crosses then gets CGAL's local repair of the crossing faces (round.cpp).
Rounded round_robustly(const ExactMesh& exact, double scale);

// Why `mesh` may not enter corefinement (operand.cpp), in words after its name ("is not
// closed", "intersects itself (3 triangle pairs)"); empty when it may. `closed`: as a
// Boolean operand (closed and bounding a volume), else as a corefinement surface.
std::string unusable_operand(const ExactMesh& mesh, bool closed);
// The same after removing zero-area triangles (PMP::remove_degenerate_faces, exact: the
// surface keeps its shape), which the mesh stage accepts and CGAL does not.
std::string make_usable(ExactMesh* mesh, bool closed);

// `solid` (closed, outward) grown by `delta`: each vertex moved outward along its
// angle-weighted normal, far enough that every face around it moves by at least `delta`
// (at most 5 delta along the normal, at needle-sharp corners). Only the positions change
// (operand.cpp).
TriangleMesh grown(const TriangleMesh& solid, double delta);

// a ∪ b (unite) or a \ b, exactly, both closed and usable (make_usable). The result is
// checked (a valid, closed halfedge mesh); false when it is not one.
bool exact_boolean(const ExactMesh& a, const ExactMesh& b, bool unite, ExactMesh* out);

// Signed volume of a closed mesh. Summed in doubles: PMP::volume in the exact kernel
// builds one lazy sum over every face and evaluates it exactly (11 s of the 5 x 5 net's
// 19 s contact, 492k faces). Only the sign decides something (additive or a bite); where
// the double sum is too close to zero to trust its sign, the exact one is taken.
double signed_volume(const ExactMesh& m);

// Orders exact points lexicographically (to merge and match vertices across meshes).
struct PointLess {
  bool operator()(const ExactPoint& a, const ExactPoint& b) const {
    return CGAL::compare_xyz(a, b) == CGAL::SMALLER;
  }
};

// One organic cell boundary Q_c: the organic sheet trimmed at its contact curves plus the
// caps it encloses on ∂S, closed and consistently oriented (see contact.cpp).
struct OrganicCell {
  int component = -1;
  ExactMesh closed;          // Q_c, oriented like the organic surface
  ExactMesh trimmed;         // T_c = O_c cut at C, the part the result keeps
  bool additive = true;      // Q_c encloses positive volume: material, else a bite
  double volume = 0;         // signed, design units³
  bool usable = false;       // `closed`, as a Boolean operand, passed make_usable
};

// Result of cutting one pulled sheet at ∂S: contact polylines (per sheet loop, -1 where
// unmatched) and, when they match the loops one to one, the cell.
struct ContactCut {
  std::vector<std::vector<Vec3>> curves;
  std::vector<int> curve_loop;
  bool homeomorphic = false;
  std::string problem;       // why not, in words
  bool has_cell = false;
  OrganicCell cell;
};

// Unites the given solids' meshes exactly (the loop's S of §7.1). Throws on failure.
ExactMesh solid_union(const std::vector<SolidInput>& solids, const std::vector<int>& members);

// §7.3's check and the trimming: corefines the pulled sheet with ∂S, extracts C = O ∩ ∂S,
// checks that every loop's end of O is an annulus bounded by that loop and exactly one
// contact curve, and builds Q_c.
ContactCut cut_at_contact(const OrganicSheet& pulled, const ExactMesh& solid_union_mesh);

}  // namespace genbrep::detail
