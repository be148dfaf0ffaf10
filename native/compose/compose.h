// compose/compose.h — contact curves (§7.1–7.3) and the watertight composed solid (§8).
// Takes: one open organic sheet per component (the partition's organic triangles as a
// stand-in, or a fitted cage's tessellated limit surface), each boundary loop tagged with
// the solids it borders, and the prepared input solids with their roles.
// Gives: per component the pulled sheet, the safety tolerance η used and the contact
// curves C = O ∩ ∂S matched one to one with the boundary loops; the composed mesh with
// each face's source; a report of measured checks.
// Method: per component, pull (pull/) with η doubling until C is homeomorphic to ∂O
// (§7.3); cut O at C and close the kept part T with the caps of ∂S it encloses into a
// closed oriented surface Q (exact constructions, so the caps lie exactly on ∂S). Then the
// cellular classification of §8.2 is evaluated as exact Booleans on closed meshes:
//   G = (((P \ ⋃ bites) ∪ ⋃ additive Q) ∪ K) \ L
// with P the seeds, K the keep-ins, L the keep-outs, an additive Q one enclosing positive
// volume (its T faces outward: rule 2) and a bite one enclosing negative volume (T facing
// into the cell: rule 3, a seed's eroded part). Cells inside a keep-in are inside (∪ K
// last); cells bounded by solid faces only are inside iff inside S (seeds; keep-outs are
// subtracted); cells seen from both orientations are inside (additive after the bites,
// rule 4) and reported. Organic operands cross the solids transversally or share exactly
// coplanar faces with them; input solids may nearly coincide (a bolt in its bore), so edges
// of the exact result shorter than 1e-10 × the scene are collapsed before it is rounded to
// doubles (compose/round.cpp), and the rounded mesh is what the report measures.
// Guarantees: faces on input solids carry the input's vertex positions (new vertices lie
// only on intersection curves); the report is measured on the returned double mesh.
// Tiers. Each component is composed from the best surface that works: its pulled fitted
// cage ("cage"), else that cage extended into its solids by a row of quads and pulled
// ("extended cage", pull/extend.cpp), else its design region ("design region"); a component with no boundary on
// a solid (a closed organic shell) is its own closed cell. Where the design is given, a
// component with no tier that works takes its part of the design solid: the volumes of
// the exact D \ K (design less keep-ins) its design region lies on ("design solid"; a
// component with a cell that shares such a volume gives its cell up for it). When that
// cannot be done (such a component borders a seed, or would need a bite's volume), or the
// Booleans or the rounding cannot give a valid solid, the floor takes over: the exact
// Boolean (D ∪ K) \ L of the design with the keep-ins added and the keep-outs removed
// ("design Boolean", every component). The solids enter every Boolean slightly grown
// (docs/compose_method.md). Each component's contact says which tier it used and why it
// fell back.
// Preconditions: nothing reaches corefinement that breaks CGAL's documented ones (triangle
// meshes without self-intersections or degenerate faces; Boolean operands closed and
// bounding a volume): operands are checked first and a failed check takes the next tier.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/cage.h"
#include "core/context.h"
#include "core/error.h"
#include "core/types.h"
#include "incidence/incidence.h"
#include "pull/pull.h"

namespace genbrep {

struct ComposeOptions {
  // η₀ of §7.3, design units (< 0). 0 = −1e-4 × the bounding-box diagonal.
  double initial_eta = 0;
  int max_doublings = 10;  // η → 2η at most this often
  PullOptions pull;
};

// One contact curve C_i,j: a closed polyline on ∂S, with the sheet loop it corresponds to.
struct ContactCurve {
  int loop = -1;  // sheet loop index; -1 = matches no loop (reported)
  std::vector<Vec3> points;
};

struct ComponentContact {
  int component = -1;
  double eta = 0;              // η that made C homeomorphic to ∂O, design units
  int doublings = 0;
  bool established = false;    // pulled and homeomorphic
  bool additive = true;        // Q encloses material (else a bite out of a seed)
  double cell_volume = 0;      // signed volume of Q, design units³
  OrganicSheet pulled;         // the pulled sheet (a cage: its pulled limit tessellation)
  // What was composed: "cage", "extended cage", "design region", "closed shell" (a cage's
  // or the design's closed component), "design solid" (its part of D \ K) or "design
  // Boolean" (the floor).
  std::string surface = "design region";
  std::string fallback;        // why a lower tier than the component's best was used; empty if none
  QuadCage cage;               // surface "cage" or "extended cage": the pulled cage (matches `pulled`)
  std::vector<double> max_distance_before;  // per loop: max F on the boundary before the pull
  std::vector<double> max_distance_after;   // and after (≤ η when established)
  std::vector<ContactCurve> curves;
  Diagnostics diagnostics;
};

struct ComposeReport {
  bool ok = false;             // composed, closed, manifold, oriented, no self-intersection
  int vertices = 0, triangles = 0;
  int boundary_edges = 0, non_manifold_edges = 0, non_manifold_vertices = 0;
  int inconsistent_edges = 0;
  bool self_intersecting = false;
  double volume = 0;
  int shells = 0;
  int genus = 0;               // Σ genus over shells, from Euler's formula
  int organic_cells = 0;       // closed organic cells Q (additive + bites)
  int solid_cells = 0;         // solid operands (keep-ins, seeds, keep-outs)
  int solid_faces = 0, organic_faces = 0;
  double seconds_contact = 0, seconds_boolean = 0;
  bool floor = false;          // composed as the design Boolean (D ∪ K) \ L
  Diagnostics diagnostics;
  Diagnostics notes;           // how it went where nothing fell short (e.g. rounding repaired)
};

// Face sources: solid index ≥ 0, or organic component c encoded as −1 − c.
inline int organic_source(int component) { return -1 - component; }

struct Composed {
  TriangleMesh mesh;           // triangle_source = face source as above
  std::vector<ComponentContact> contacts;
  ComposeReport report;
};

// §7.2–7.3 for one sheet: pull, cut, check, doubling η as needed.
ComponentContact establish_contact(const OrganicSheet& sheet, const SolidSet& solids,
                                   const ComposeOptions& options);

// §7.2–7.3 for a fitted cage (pull/pull_cage on its limit boundary, η doubling until the
// contact is homeomorphic): contact.cage is the pulled cage, contact.pulled its limit
// tessellation with one loop per chain (an OrganicSheet compose() accepts as it is: its
// tessellated boundary is already at F ≤ η). chain_solids[i]: the solids chain i borders.
ComponentContact establish_cage_contact(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                                        const SolidSet& solids, const ComposeOptions& options);

// The organic surface of one component for compose(): a cage when there is one (pulled
// as above), else — or when the cage cannot be pulled, with a diagnostic — the sheet.
// A surface with neither a cage nor sheet triangles is skipped.
struct OrganicSurface {
  OrganicSheet sheet;                         // stand-in; no triangles = no fallback
  std::optional<QuadCage> cage;
  std::vector<std::vector<int>> chain_solids; // per cage chain: the solids it borders
};

// §7 then §8 for all sheets. Throws Error{Cancelled} on cancel; everything else is in the
// report (ok = false and a named diagnostic when the composition cannot be valid).
// `design` (closed, outward, as validated by mesh/) enables the floor; without it a failed
// component leaves report.ok false with the reason.
Composed compose(const std::vector<OrganicSheet>& sheets, const SolidSet& solids,
                 const ComposeOptions& options, const Context& context,
                 const TriangleMesh* design = nullptr);
Composed compose(const std::vector<OrganicSurface>& surfaces, const SolidSet& solids,
                 const ComposeOptions& options, const Context& context,
                 const TriangleMesh* design = nullptr);

// The components of a composed solid that fell back from their best tier, one line each
// ("organic component 2: composed from the design region: …"); empty when everything was
// made as asked, or when no solid was made (report.ok false: the diagnostics say why).
std::vector<std::string> fallbacks(const Composed& composed);

}  // namespace genbrep
