// quad/patches.cpp — from layout curves to four-sided patches (quad/quad.h step 1).
// Rounds after the first fill and read again only the patches around vertices where the
// layout changed (cuts traced, stretches removed, nodes added), with the same patches as a
// full fill. A PatchReading carries this across calls: the balance rounds (attempt.cpp: a
// patch merged, cusps taken back) read again only what changed.
#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <set>

#include "quad/detail/patches.h"

namespace genbrep::quad_detail {
namespace {

// What a round of build_patches reads and its fixes change: the curves (as a set: a curve
// taken off leaves an empty slot, and one traced again is appended), the nodes, the
// overridden corner readings and the wedges already cut.
std::size_t round_state(const Layout& layout, const std::map<int, int>& quarter_override,
                        const std::set<int>& wedge_tried) {
  std::vector<std::size_t> curves;
  for (const Curve& curve : layout.curves) {
    if (curve.vertices.empty()) continue;
    std::size_t key = curve.vertices.size() * 4 + curve.closed * 2 + curve.link;
    for (int v : curve.vertices) key = key * 1000003u + static_cast<std::size_t>(v) + 1;
    curves.push_back(key);
  }
  std::sort(curves.begin(), curves.end());
  std::size_t key = curves.size();
  auto mix = [&key](std::size_t value) { key = key * 1000003u + value + 1; };
  for (std::size_t curve : curves) mix(curve);
  for (std::size_t v = 0; v < layout.node.size(); ++v)
    if (layout.node[v]) mix(v);
  for (const auto& [h, quarters] : quarter_override) mix(static_cast<std::size_t>(h) * 8 + quarters);
  for (int f : wedge_tried) mix(static_cast<std::size_t>(f));
  return key;
}

}  // namespace

struct PatchReading::State {
  bool read = false;                 // false: nothing read yet
  std::map<int, Examined> examined;  // by the patch's lowest face
  std::vector<int> patch_of;         // per face: its patch's key, -1 none
  // The layout as the last round read it.
  std::vector<int> last_edge_curve;
  std::vector<Vec3> last_dir;
  std::vector<char> last_node;
  std::set<int> last_no_cusp;
  std::vector<int> last_attractors;
  // Examination stamps (per vertex, per halfedge) and a boundary halfedge's place in its
  // patch's sorted boundary.
  std::vector<int> vertex_stamp, halfedge_stamp, boundary_at;
  int visit = 0;
};
PatchReading::PatchReading() : state(std::make_unique<State>()) {}
PatchReading::~PatchReading() = default;

namespace {

// How build_patches mends a patch that is not a four-sided disk: a list of places to cut from,
// tried in order; if none can be traced, a reflex reading is overridden to straight instead
// (and reported).
struct Cut { int vertex, first, last; double fraction; };
struct Fix {
  std::vector<Cut> cuts;
  int override_halfedge = -1;
  std::vector<std::pair<int, int>> forced;  // last resort: (halfedge_out, quarters)
  std::vector<int> forced_nodes;
  // When no cut can be traced: a stretch of an open curve to take off the layout
  // (vertex list; a dangling separatrix, or the shortest arc of a sliver patch).
  std::vector<int> remove_stretch;
  bool optional = false;  // a wedge's cut: the patch stays as it is if none traces
  // A pinched disk (its boundary passes a vertex twice): first a cut between the two
  // stretches of its boundary either side of that vertex (cut_pinch), through `faces`.
  std::vector<int> pinch_from, pinch_to;
  const std::vector<int>* faces = nullptr;
};

// The rounds of build_patches on one layout: each round splits the curves into arcs, fills
// and examines the patches around what changed (PatchReading), and mends every patch that
// is not a four-sided disk (a Fix), until none needs mending.
class PatchBuilder {
 public:
  PatchBuilder(const Surface& s, Layout& layout, const QuadOptions& options,
               PatchReading::State& st);
  PatchLayout run(Messages& messages);

 private:
  // What look_at did with a patch: kept it (valid), planned a fix, or re-read its corners
  // (the patch is looked at again).
  enum Outcome { kValid, kFixed, kReread };
  std::vector<int> refill();
  void examine(int key);
  Outcome look_at(Examined& examined, int round, bool stalled);
  void fix_non_disk(const std::vector<int>& faces, long chi, bool repeated,
                    const std::vector<Cycle>& cycles);
  Outcome reread_corners(std::vector<Cycle>& cycles, int turning,
                         const std::vector<double>& after);
  Outcome split_into_sides(const std::vector<int>& faces, std::vector<Cycle>& cycles, int round);
  void check_progress(int round);
  void apply_fixes();
  std::vector<int> shortest_open_arc_of(const std::vector<Cycle>& cycles) const;
  void force_corners(const Cycle& c, Fix& fix) const;
  Fix middle_cuts(const std::vector<Cycle>& cycles) const;

  const Surface& s;
  Layout& layout;
  const QuadOptions& options;
  const std::string who;
  std::map<int, int> quarter_override;  // by the sector's outgoing halfedge
  std::set<int> wedge_tried;             // wedge patches cut once, by their first face
  std::map<int, int> singular_valence;   // traced singular vertex → its separatrix count
  PatchLayout out;
  PatchReading::State& st;
  const int nf;
  std::map<int, Examined>& examined;
  std::vector<int>& patch_of;  // face → its patch's key
  std::vector<int>& vertex_stamp;
  std::vector<int>& halfedge_stamp;
  std::vector<int>& boundary_at;
  int& visit;  // stamp of an examination
  int fewest_fixes = std::numeric_limits<int>::max(), fewest_round = 0;  // no-progress stop
  const int stall;
  std::vector<Fix> fixes;  // this round's
};

PatchBuilder::PatchBuilder(const Surface& s, Layout& layout, const QuadOptions& options,
                           PatchReading::State& st)
    : s(s),
      layout(layout),
      options(options),
      who("component " + std::to_string(s.component)),
      st(st),
      nf(static_cast<int>(s.mesh.n_faces())),
      examined(st.examined),
      patch_of(st.patch_of),
      vertex_stamp(st.vertex_stamp),
      halfedge_stamp(st.halfedge_stamp),
      boundary_at(st.boundary_at),
      visit(st.visit),
      stall(options.fix_rounds_without_progress) {
  for (size_t i = 0; i < layout.attractors.size() && i < layout.attractor_directions.size(); ++i)
    singular_valence[layout.attractors[i]] = static_cast<int>(layout.attractor_directions[i].size());
  // Singular valences change readings anywhere: read everything again if they differ.
  if (st.read && st.last_attractors != layout.attractors) st = PatchReading::State();
  if (!st.read) {
    st.patch_of.assign(nf, -1);
    st.vertex_stamp.assign(s.mesh.n_vertices(), -1);
    st.halfedge_stamp.assign(s.mesh.n_halfedges(), -1);
    st.boundary_at.assign(s.mesh.n_halfedges(), 0);
  }
}

PatchLayout PatchBuilder::run(Messages& messages) {
  // The state at the start of each round: the fixes can cycle (a cut traced one round is
  // taken off as the shortest arc of a patch it pinched the next), and a state seen
  // before only leads through the same rounds again.
  std::map<std::size_t, int> seen_states;
  for (int round = 0;; ++round) {
    ++layout.patch_rounds;
    const auto [first_seen, fresh] =
        seen_states.insert({round_state(layout, quarter_override, wedge_tried), round});
    GENBREP_CHECK(fresh, Code::StageFailure,
                  "quad: " + who + ": the extra cuts of round " + std::to_string(round) +
                      " give back the layout of round " + std::to_string(first_seen->second) +
                      "; some patches never become four-sided disks");
    build_arcs(s, layout, options.kink_nodes, out);
    const std::vector<int> fresh_keys = refill();
    out.patches.clear();
    fixes.clear();
    // The new patches' boundary cycles, Euler characteristic and corner readings.
    for (int key : fresh_keys) examine(key);
    // Once the rounds stall (half of fix_rounds_without_progress without fewer patches to
    // fix), an override read where the layout was different (the halfedge a corner then)
    // no longer hides a dangling end, which can leave a pinched strip that the cuts never
    // resolve. Before that the overrides stand (honouring dangling ends from the start
    // leaves more irregular vertices away from singularities).
    const bool stalled = round - fewest_round >= std::max(1, (stall > 0 ? stall : 24) / 2);
    // Every patch, in key order: validity and, if invalid, the fix this round (a patch is
    // looked at again after its corners are re-read: --p below).
    std::vector<Examined*> patches_in_order;
    for (auto& [key, patch] : examined) patches_in_order.push_back(&patch);
    if (options.fit_corners && options.global_corners)
      out.recornered += read_corners_together(s, layout, options, singular_valence, out,
                                              patches_in_order, stalled, quarter_override);
    for (int p = 0; p < static_cast<int>(patches_in_order.size()); ++p)
      if (look_at(*patches_in_order[p], round, stalled) == kReread) --p;
    if (fixes.empty()) break;
    check_progress(round);
    apply_fixes();
  }
  if (out.pinches_cut)
    messages.notes.push_back(who + ": " + std::to_string(out.pinches_cut) +
                          " pinched patches (boundary through one vertex twice) cut across");
  if (out.removed_stretches)
    messages.notes.push_back(who + ": " + std::to_string(out.removed_stretches) +
                          " stretches of separatrices removed (dangling, or enclosing a patch "
                          "too small to cut)");
  for (const Patch& patch : out.patches) out.cusps += !patch.cusps.empty();
  if (out.cusps)
    messages.notes.push_back(who + ": " + std::to_string(out.cusps) +
                          " cusp patches (curves converging at under 45°) collapsed onto one "
                          "curve");
  if (out.recornered)
    messages.notes.push_back(who + ": " + std::to_string(out.recornered) +
                          " patch corners re-read to make four-sided patches");
  return out;
}

// Flood fills the component's faces across edges no curve runs along, where the layout
// changed since the last round; returns the keys of the patches filled.
std::vector<int> PatchBuilder::refill() {
  // Flood fill the component's faces across edges no curve runs along. Only where the
  // layout changed since the last round (a curve edge, its direction or a node): the
  // patches around those vertices are filled and examined again, the others keep what
  // the last round found. A patch is known by its lowest face (its key), and patches
  // are taken in key order, as a full fill from face 0 up would number them.
  std::vector<int> pool;  // faces to fill again
  if (!st.read) {
    for (int f = 0; f < nf; ++f)
      if (s.in(f)) pool.push_back(f);
    st.read = true;
  } else {
    std::vector<int> changed;
    // Directions are compared, and updated for the next round, only on curve edges (of
    // either round), in place: a copy of all of them is large on a fine component.
    for (int e = 0; e < static_cast<int>(layout.edge_curve.size()); ++e) {
      const bool curve = layout.edge_curve[e] >= 0 || st.last_edge_curve[e] >= 0;
      bool differs = layout.edge_curve[e] != st.last_edge_curve[e];
      for (int h : {2 * e, 2 * e + 1})
        if (curve && layout.halfedge_dir[h] != st.last_dir[h]) {
          differs = true;
          st.last_dir[h] = layout.halfedge_dir[h];
        }
      if (differs) changed.push_back(s.from(2 * e)), changed.push_back(s.to(2 * e));
    }
    for (int v : s.vertices)
      if (layout.node[v] != st.last_node[v]) changed.push_back(v);
    // Cusp readings taken back (straighten_cusps) between calls.
    std::vector<int> cusps;
    std::set_symmetric_difference(layout.no_cusp.begin(), layout.no_cusp.end(),
                                  st.last_no_cusp.begin(), st.last_no_cusp.end(),
                                  std::back_inserter(cusps));
    for (int h : cusps) changed.push_back(s.from(h));
    std::set<int> stale;  // keys of the patches to fill again
    for (int v : changed)
      for (auto f : s.mesh.vf_range(s.mesh.vertex_handle(v)))
        if (s.in(f.idx())) stale.insert(patch_of[f.idx()]);
    for (int key : stale) {
      const auto it = examined.find(key);
      pool.insert(pool.end(), it->second.faces.begin(), it->second.faces.end());
      examined.erase(it);
    }
    std::sort(pool.begin(), pool.end());
    for (int f : pool) patch_of[f] = -1;
  }
  if (st.last_dir.empty()) st.last_dir = layout.halfedge_dir;
  st.last_edge_curve = layout.edge_curve;
  st.last_node = layout.node;
  st.last_no_cusp = layout.no_cusp;
  st.last_attractors = layout.attractors;
  std::vector<int> fresh_keys;
  for (int f0 : pool) {
    if (patch_of[f0] >= 0) continue;
    Examined& patch = examined[f0];
    fresh_keys.push_back(f0);
    patch.faces.push_back(f0);
    patch_of[f0] = f0;
    for (size_t k = 0; k < patch.faces.size(); ++k)
      for (auto h : s.mesh.fh_range(s.mesh.face_handle(patch.faces[k]))) {
        if (layout.edge_curve[h.idx() >> 1] >= 0) continue;
        const int g = s.face(h.idx() ^ 1);
        if (g >= 0 && s.in(g) && patch_of[g] < 0) patch_of[g] = f0, patch.faces.push_back(g);
      }
  }
  return fresh_keys;
}

// Reads a freshly filled patch: its boundary cycles, Euler characteristic and corner readings.
void PatchBuilder::examine(int key) {
  Examined& patch = examined[key];
  ++visit;
  // V − E + F with E = (3F + halfedges whose other side is not in the patch) / 2;
  // vertices and boundary halfedges are marked with this examination's stamp.
  std::vector<int> boundary;
  long vertex_count = 0, open_halfedges = 0;
  for (int f : patch.faces)
    for (auto h : s.mesh.fh_range(s.mesh.face_handle(f))) {
      const int v = s.from(h.idx());
      if (vertex_stamp[v] != visit) {
        vertex_stamp[v] = visit;
        ++vertex_count;
      }
      const int g = s.face(h.idx() ^ 1);
      if (g < 0 || patch_of[g] != key) ++open_halfedges;
      if (layout.edge_curve[h.idx() >> 1] >= 0) boundary.push_back(h.idx());
    }
  std::sort(boundary.begin(), boundary.end());  // cycles start at their lowest halfedge
  for (size_t b = 0; b < boundary.size(); ++b)
    halfedge_stamp[boundary[b]] = visit, boundary_at[boundary[b]] = static_cast<int>(b);
  const long face_count = static_cast<long>(patch.faces.size());
  patch.chi = vertex_count - (3 * face_count + open_halfedges) / 2 + face_count;
  std::vector<char> used(boundary.size(), 0);
  for (size_t b = 0; b < boundary.size(); ++b) {
    if (used[b]) continue;
    Cycle cycle;
    int h = boundary[b];
    for (size_t guard = 0; guard <= boundary.size(); ++guard) {
      if (halfedge_stamp[h] != visit || used[boundary_at[h]]) break;
      const size_t at = static_cast<size_t>(boundary_at[h]);
      used[at] = 1;
      cycle.halfedges.push_back(h);
      h = next_on_boundary(s, layout, h);
    }
    const int n = static_cast<int>(cycle.halfedges.size());
    for (int i = 0; i < n; ++i) {
      const int h_out = cycle.halfedges[i], h_in = cycle.halfedges[(i + n - 1) % n];
      const int v = s.from(h_out);
      if (!layout.node[v]) continue;
      const auto singular = singular_valence.find(v);
      Corner corner{h_out, h_in,
                    sector_angle(s, layout, h_out, h_in,
                                 singular == singular_valence.end() ? 0 : singular->second),
                    2};
      const int together = node_quarters(s, layout, h_out,
                                         singular == singular_valence.end() ? 0 : singular->second);
      const int alone = static_cast<int>(std::lround(corner.angle / (kPi / 2)));
      corner.quarters =
          std::clamp(together >= 0 ? together : alone, options.cusp_corners ? 0 : 1, 3);
      if (corner.quarters == 0 && layout.no_cusp.count(h_out)) corner.quarters = 1;
      if (h_out == (h_in ^ 1)) corner.quarters = 4;  // a dangling end: full turn
      cycle.nodes.push_back(corner);
    }
    // A jog: a link arc (trace.cpp) whose end turns cancel (a reflex and a quarter turn)
    // is a step in a straight side; both ends read straight.
    const int m = static_cast<int>(cycle.nodes.size());
    for (int i = 0; i < m && m > 1; ++i) {
      Corner& a = cycle.nodes[i];
      Corner& b = cycle.nodes[(i + 1) % m];
      const int arc = out.halfedge_arc[a.halfedge_out] / 2;
      if (layout.curves[out.arcs[arc].curve].link && a.quarters + b.quarters == 4 &&
          (a.quarters == 1 || a.quarters == 3))
        a.quarters = b.quarters = 2;
    }
    for (Corner& k : cycle.nodes) k.read = k.quarters;
    patch.cycles.push_back(cycle);
  }
}

// Whether `examined` is a four-sided disk (kept in out.patches), or the fix it needs this
// round (in fixes), or kReread once its corners are read anew.
PatchBuilder::Outcome PatchBuilder::look_at(Examined& examined, int round, bool stalled) {
  const std::vector<int>& faces = examined.faces;
  const long chi = examined.chi;
  std::vector<Cycle>& cycles = examined.cycles;
  for (Cycle& c : cycles)
    for (Corner& k : c.nodes) k.quarters = read_with_override(quarter_override, k, stalled);
  const bool repeated = passes_a_vertex_twice(s, cycles);
  const Corner* dangling = nullptr;
  const Corner* reflex = nullptr;
  for (const Cycle& c : cycles)
    for (const Corner& k : c.nodes) {
      if (k.quarters == 4 && !dangling) dangling = &k;
      if (k.quarters == 3 && !reflex) reflex = &k;
    }
  if (dangling) {
    Fix fix;
    fix.cuts.push_back({s.from(dangling->halfedge_out), dangling->halfedge_out,
                        dangling->halfedge_out, 0.5});
    const int curve = layout.edge_curve[dangling->halfedge_out >> 1];
    if (!layout.curves[curve].closed) fix.remove_stretch = layout.curves[curve].vertices;
    fixes.push_back(fix);
    return kFixed;
  }
  if (cycles.size() != 1 || chi != 1 || repeated) {
    fix_non_disk(faces, chi, repeated, cycles);
    return kFixed;
  }
  if (reflex) {
    Fix fix;
    fix.cuts.push_back({s.from(reflex->halfedge_out), reflex->halfedge_out,
                        reflex->halfedge_in ^ 1, 1.0 / 3});
    fix.cuts.push_back({s.from(reflex->halfedge_out), reflex->halfedge_out,
                        reflex->halfedge_in ^ 1, 2.0 / 3});
    fix.override_halfedge = reflex->halfedge_out;
    fixes.push_back(fix);
    return kFixed;
  }
  Cycle& cycle = cycles[0];
  int turning = 0;
  for (const Corner& k : cycle.nodes) turning += 2 - k.quarters;
  // Target length of the arc after each node (nodes split the cycle into whole arcs).
  std::vector<double> after;
  for (const Corner& k : cycle.nodes)
    after.push_back(out.arcs[out.halfedge_arc[k.halfedge_out] / 2].target);
  if (turning != 4) return reread_corners(cycles, turning, after);
  return split_into_sides(faces, cycles, round);
}

// The fix for a patch that is not a disk, or a disk whose boundary passes a vertex twice.
void PatchBuilder::fix_non_disk(const std::vector<int>& faces, long chi, bool repeated,
                                const std::vector<Cycle>& cycles) {
  if (cycles.empty()) {  // no boundary at all (a closed component without curves)
    const int h = s.mesh.halfedge_handle(s.mesh.face_handle(faces[0])).idx();
    Fix fix;
    fix.cuts.push_back({s.from(h), h, h, 0.5});
    fixes.push_back(fix);
  } else {
    fixes.push_back(middle_cuts(cycles));
    // If no cut traces (an annulus too thin to cross, e.g. around a strut): its
    // shortest open arc goes, merging it with a neighbour.
    fixes.back().remove_stretch = shortest_open_arc_of(cycles);
    if (repeated && chi == 1) {
      // The stretches before and after the first vertex the cycle passes twice (a
      // vertex in both belongs to neither).
      std::vector<int> cv;
      for (int h : cycles[0].halfedges) cv.push_back(s.from(h));
      const int n = static_cast<int>(cv.size());
      std::map<int, int> first_at;
      int i = -1, j = -1;
      for (int k = 0; k < n && j < 0; ++k) {
        const auto [it, fresh] = first_at.insert({cv[k], k});
        if (!fresh) i = it->second, j = k;
      }
      std::vector<int> inside(cv.begin() + i + 1, cv.begin() + j), outside;
      for (int k = j + 1; k < n + i; ++k) outside.push_back(cv[k % n]);
      std::sort(inside.begin(), inside.end());
      std::sort(outside.begin(), outside.end());
      Fix& fix = fixes.back();
      std::set_difference(inside.begin(), inside.end(), outside.begin(), outside.end(),
                          std::back_inserter(fix.pinch_from));
      std::set_difference(outside.begin(), outside.end(), inside.begin(), inside.end(),
                          std::back_inserter(fix.pinch_to));
      fix.pinch_from.erase(std::remove(fix.pinch_from.begin(), fix.pinch_from.end(), cv[i]),
                           fix.pinch_from.end());
      fix.pinch_to.erase(std::remove(fix.pinch_to.begin(), fix.pinch_to.end(), cv[i]),
                         fix.pinch_to.end());
      fix.faces = &faces;
    }
  }
}

// A disk whose corners do not turn four quarter turns: its corners re-read (kReread), or
// a fix.
PatchBuilder::Outcome PatchBuilder::reread_corners(std::vector<Cycle>& cycles, int turning,
                                                   const std::vector<double>& after) {
  Cycle& cycle = cycles[0];
  if (turning != 4 && !options.fit_corners) {
    // Re-read the most ambiguous angle: a corner nearest to straight, or the reverse.
    Corner* pick = nullptr;
    for (Corner& k : cycle.nodes) {
      if (turning > 4 && k.quarters == 1 && (!pick || k.angle > pick->angle)) pick = &k;
      if (turning < 4 && k.quarters == 2 && (!pick || k.angle < pick->angle)) pick = &k;
    }
    if (!pick || std::abs(turning - 4) > 2) {
      fixes.push_back(middle_cuts(cycles));
      force_corners(cycle, fixes.back());
      // A one-triangle sliver between curves can be neither cut nor forced: merge it.
      if (fixes.back().forced.empty()) fixes.back().remove_stretch = shortest_open_arc_of(cycles);
      return kFixed;
    }
    quarter_override[pick->halfedge_out] = turning > 4 ? 2 : 1;
    ++out.recornered;
    return kReread;  // re-examine the same patch with the new reading
  }
  if (turning != 4) {
    // The best rectangle among the patch's nodes (best_corners).
    double cost = 0;
    const std::vector<int> best = best_corners(cycle.nodes, after, &cost);
    if (best.empty()) {
      fixes.push_back(middle_cuts(cycles));
      force_corners(cycle, fixes.back());
      // A one-triangle sliver between curves can be neither cut nor forced: merge it.
      if (fixes.back().forced.empty()) fixes.back().remove_stretch = shortest_open_arc_of(cycles);
      return kFixed;
    }
    for (size_t i = 0; i < best.size(); ++i)
      quarter_override[cycle.nodes[i].halfedge_out] = best[i];
    ++out.recornered;
    return kReread;  // re-examine the same patch with the new reading
  }
  return kFixed;
}

// A disk of four corners: split into four sides (out.patches), unless its cusps must be
// read as quarter turns (kReread) or it is a wedge to cut across (kFixed).
PatchBuilder::Outcome PatchBuilder::split_into_sides(const std::vector<int>& faces,
                                                     std::vector<Cycle>& cycles, int round) {
  Cycle& cycle = cycles[0];
  // Valid: split the cycle into four sides at its corners.
  Patch patch;
  patch.faces = faces;
  for (int f : patch.faces) patch.quads += s.face_quads(f);
  std::vector<int> corner_at;
  const int n = static_cast<int>(cycle.halfedges.size());
  std::vector<int> quarters(n, 2);
  std::vector<char> is_node(n, 0);
  for (int i = 0; i < n; ++i) is_node[i] = layout.node[s.from(cycle.halfedges[i])];
  {
    size_t k = 0;
    for (int i = 0; i < n; ++i)
      if (is_node[i]) quarters[i] = cycle.nodes[k++].quarters;
  }
  // A cusp (quarters 0) is two corners at one node, with an empty side between them.
  int start = 0;
  while (quarters[start] > 1) ++start;
  patch.sides.assign(4, {});
  int side = -1;
  for (int t = 0; t < n; ++t) {
    const int i = (start + t) % n;
    if (quarters[i] <= 1) side += 2 - quarters[i];
    if (is_node[i]) {
      const int code = out.halfedge_arc[cycle.halfedges[i]];
      patch.sides[side].push_back({code / 2, (code & 1) != 0});
    }
  }
  // A cusp patch collapses (fill.cpp) onto one curve, so it must be thin: the side
  // across from its empty side short (kCuspCollapseAcross target edges;
  // interior arcs may quantize to 0) and the patch narrow on average (area over length,
  // kCuspCollapseWidth; a thin triangle on a base of one edge is half an edge wide),
  // or the collapse squeezes the quads beside it. Nor may it touch the component's
  // border (a loop: the collapse glues its two long sides onto each other, and a chain
  // must stay on its loop). Otherwise its cusps read as quarter turns and it is
  // examined again.
  bool cusp = false, collapsible = true;
  for (int k = 0; k < 4; ++k)
    if (patch.sides[k].empty()) {
      cusp = true;
      const double d = options.density;
      const double along = 0.5 * d * (side_target(out.arcs, patch, (k + 1) % 4) +
                                       side_target(out.arcs, patch, (k + 3) % 4));
      collapsible &=
          side_target(out.arcs, patch, (k + 2) % 4) * d < kCuspCollapseAcross &&
          patch.quads * d * d / std::max(along, 1.0) < kCuspCollapseWidth;
    }
  if (cusp) {
    for (const auto& arcs : patch.sides)
      for (auto& [a, reversed] : arcs) {
        const std::vector<int>& vs = out.arcs[a].vertices;
        const int h = s.mesh.find_halfedge(s.mesh.vertex_handle(vs[0]),
                                           s.mesh.vertex_handle(vs[1])).idx();
        collapsible &= s.in(s.face(h)) && s.in(s.face(h ^ 1));
      }
    if (!collapsible) {
      for (const Corner& k : cycle.nodes)
        if (k.quarters == 0) quarter_override[k.halfedge_out] = 1;
      ++out.recornered;
      return kReread;
    }
    for (const Corner& k : cycle.nodes)
      if (k.quarters == 0) patch.cusps.push_back(k.halfedge_out);
  }
  // A wedge: opposite sides whose targets differ several times over (a triangle read
  // as a rectangle) can only be balanced by squeezing the long one
  // (QuadOptions::wedge_cut_ratio). It is cut from the middle of its boundary, once,
  // and only in the first half of the rounds (the others are for invalid patches); if
  // no cut traces, it stays as it is.
  const double wedge_ratio = options.wedge_cut_ratio;
  if (!cusp && wedge_ratio > 0 && 2 * round < options.max_fix_rounds &&
      !wedge_tried.count(patch.faces.front())) {
    bool wedge = false;
    for (int pair = 0; pair < 2; ++pair) {
      const double side[2] = {side_target(out.arcs, patch, pair) * options.density,
                              side_target(out.arcs, patch, pair + 2) * options.density};
      const double lo = std::min(side[0], side[1]), hi = std::max(side[0], side[1]);
      wedge |= hi >= 3 && hi > wedge_ratio * std::max(lo, 0.5);
    }
    if (wedge) {
      wedge_tried.insert(patch.faces.front());
      fixes.push_back(middle_cuts(cycles));
      fixes.back().optional = true;
      return kFixed;
    }
  }
  out.patches.push_back(patch);
  return kValid;
}

// Stops the rounds (throws) when they make no progress or run out.
void PatchBuilder::check_progress(int round) {
  // Rounds that leave no fewer patches to fix than the fewest so far trade one invalid
  // patch for another (QuadOptions::fix_rounds_without_progress).
  int required = 0;  // patches to fix, optional wedge cuts not counted
  for (const Fix& fix : fixes) required += !fix.optional;
  if (required < fewest_fixes) fewest_fixes = required, fewest_round = round;
  GENBREP_CHECK(stall <= 0 || round - fewest_round < stall, Code::StageFailure,
                "quad: " + who + ": extra cuts make no progress: " + std::to_string(required) +
                    " patches are still not four-sided disks after " + std::to_string(round) +
                    " rounds, none fewer than after round " + std::to_string(fewest_round));
  GENBREP_CHECK(round < options.max_fix_rounds, Code::StageFailure,
                "quad: " + who + ": " + std::to_string(fixes.size()) +
                    " patches are still not four-sided disks after " +
                    std::to_string(round) + " rounds of extra cuts");
}

// Traces or applies this round's fixes; throws if none could be.
void PatchBuilder::apply_fixes() {
  int traced = 0;
  for (const Fix& fix : fixes) {
    bool done = false;
    if (fix.faces &&
        cut_pinch(s, layout, *fix.faces, fix.pinch_from, fix.pinch_to)) {
      done = true;
      ++out.pinches_cut;
    }
    for (int pass = 0; pass < 2 && !done; ++pass)  // field-aligned first, then straight
      for (const Cut& cut : fix.cuts)
        if (trace_from(s, layout, cut.vertex, cut.first, cut.last, cut.fraction, pass == 0)) {
          done = true;
          break;
        }
    if (!done && !fix.forced.empty()) {
      for (int v : fix.forced_nodes) layout.node[v] = 1;
      for (auto& [h, q] : fix.forced) quarter_override[h] = q;
      ++out.recornered;
      done = true;
    }
    if (!done && remove_stretch(s, layout, fix.remove_stretch)) {
      ++out.removed_stretches;
      done = true;
    }
    if (!done && fix.override_halfedge >= 0) {
      quarter_override[fix.override_halfedge] = 2;
      ++out.recornered;
      done = true;
    }
    traced += done || fix.optional;
  }
  GENBREP_CHECK(traced > 0, Code::StageFailure,
                "quad: " + who + ": no extra cut could be traced into an invalid patch");
}

std::vector<int> PatchBuilder::shortest_open_arc_of(const std::vector<Cycle>& cycles) const {
  std::vector<int> arcs;
  for (const Cycle& c : cycles)
    for (int h : c.halfedges) arcs.push_back(out.halfedge_arc[h] / 2);
  return shortest_open_arc(layout, out, arcs);
}

// Last resort for a disk: its four sharpest boundary turns become the corners.
void PatchBuilder::force_corners(const Cycle& c, Fix& fix) const {
  const int n = static_cast<int>(c.halfedges.size());
  if (n < 4) return;
  std::vector<std::pair<double, int>> turns;
  for (int i = 0; i < n; ++i) {
    const int h_out = c.halfedges[i], h_in = c.halfedges[(i + n - 1) % n];
    turns.push_back({ccw_angle(layout.halfedge_dir[h_out], layout.halfedge_dir[h_in ^ 1],
                               s.vertex_normal[s.from(h_out)]), i});
  }
  std::stable_sort(turns.begin(), turns.end());
  std::vector<char> corner(n, 0);
  for (int k = 0; k < 4; ++k) corner[turns[k].second] = 1;
  for (int i = 0; i < n; ++i) {
    const int v = s.from(c.halfedges[i]);
    if (corner[i] && !layout.node[v]) fix.forced_nodes.push_back(v);
    if (corner[i] || layout.node[v]) fix.forced.push_back({c.halfedges[i], corner[i] ? 1 : 2});
  }
}

// Cuts from the non-node vertices of the cycles, the farthest from any node first, at
// most kMiddleCutsPerStretch from one stretch between nodes: the middle of
// one long arc may lie where the patch is a strip one triangle wide, and no cut traces
// there, and the rounds would cycle with every cut from that arc.
Fix PatchBuilder::middle_cuts(const std::vector<Cycle>& cycles) const {
  std::vector<std::pair<int, Cut>> ranked;
  std::vector<int> stretch_of;  // per ranked entry: its stretch (cycle and run of it)
  int stretches = 0;
  for (const Cycle& c : cycles) {
    const int n = static_cast<int>(c.halfedges.size());
    std::vector<int> gap(n, n);
    for (int pass = 0; pass < 2; ++pass)
      for (int t = 0; t < 2 * n; ++t) {
        const int i = pass == 0 ? t % n : (2 * n - 1 - t) % n;
        const int j = pass == 0 ? (i + n - 1) % n : (i + 1) % n;
        if (layout.node[s.from(c.halfedges[i])]) gap[i] = 0;
        else gap[i] = std::min(gap[i], gap[j] + 1);
      }
    // Stretches are numbered from the cycle's first node on (before it: the last one).
    int first_node = 0;
    while (first_node < n && !layout.node[s.from(c.halfedges[first_node])]) ++first_node;
    std::vector<int> run(n, stretches);
    for (int t = 0, r = stretches; t < n; ++t) {
      const int i = (first_node + t) % n;
      if (t > 0 && layout.node[s.from(c.halfedges[i])]) ++r;
      run[i] = r, stretches = std::max(stretches, r + 1);
    }
    for (int i = 0; i < n; ++i) {
      ranked.push_back({-gap[i], Cut{s.from(c.halfedges[i]), c.halfedges[i],
                                     c.halfedges[(i + n - 1) % n] ^ 1, 0.5}});
      stretch_of.push_back(run[i]);
    }
  }
  std::vector<int> order(ranked.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return ranked[a].first < ranked[b].first; });
  std::vector<int> taken(stretches, 0);
  Fix fix;
  for (int k : order)
    if (fix.cuts.size() < 24 && taken[stretch_of[k]]++ < kMiddleCutsPerStretch)
      fix.cuts.push_back(ranked[k].second);
  return fix;
}

}  // namespace

PatchLayout build_patches(const Surface& s, Layout& layout, const QuadOptions& options,
                          Messages& messages, PatchReading* reading) {
  PatchReading local;
  return PatchBuilder(s, layout, options, *(reading ? reading : &local)->state).run(messages);
}

}  // namespace genbrep::quad_detail
