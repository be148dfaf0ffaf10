// quad/arcs.cpp — layout curves split into arcs at nodes, the angles of patch sectors, and
// stretches of separatrices taken off the layout (quad/quad.h step 1). build_patches
// (patches.cpp) reads patches from these.
// Corners are read where the patch boundary turns at a layout node: the angle between the
// curves' tangents (field directions for separatrices, chord tangents for loops) rounded
// to quarter turns q; a valid patch is a disk whose boundary turns Σ(2 − q) = 4 with no
// reflex (q = 3) node. Invalid patches are cut by more traces (a dangling separatrix is
// continued, a reflex node continues its incoming curve, a non-disk is cut from the middle
// of its longest arc); a wrong corner count is fixed by choosing the four nodes that best
// make a rectangle (best_corners; options.fit_corners) or, the older way, by re-reading
// the most ambiguous angle one at a time and, failing that, taking the four sharpest turns.
// A valid patch whose opposite sides differ several times over (a wedge) gets one more
// cut across (options.wedge_cut_ratio). Two curves meeting at under 45° are a cusp: the
// sector between them reads 0 quarter turns (options.cusp_corners), and a thin patch
// between them is a triangle with an empty side, which quantization collapses onto one
// curve. At a singular vertex the angles are the curves' own, scaled to the singularity's
// quarter turns.
#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <set>

#include "quad/detail/patches.h"

namespace genbrep::quad_detail {
double ccw_angle(const Vec3& a, const Vec3& b, const Vec3& n) {
  double angle = std::atan2(n.dot(a.cross(b)), a.dot(b));
  if (angle <= 1e-9) angle += 2 * kPi;
  return angle;
}

namespace {

// QuadOptions::kink_nodes: a vertex where an open curve's recorded direction turns a
// quarter turn against the field from the vertex before (its walk snapped to the other
// cross direction there, where the field turns fast under it) is read with the direction
// the curve came along as its tangent into it: a vertex of the curve alone becomes a node
// (sectors of 90° and 270° there), one where other curves meet it (`degree` ≠ 2, curve
// edges at each vertex) or the curve's last vertex, a node already, has its sectors read
// with that tangent. Otherwise the turn lies inside an arc, or in the tangent of a node,
// where no reading sees it: the patches either side turn three and five quarter turns at
// their nodes, and the corner reading makes up the difference at some other node, an
// irregular vertex no singularity explains. Left as they are: link curves, the curves'
// first vertices, and turns within kCaptureReach of a singular vertex the curve starts or
// ends at (a curve arriving at one keeps the separatrix direction it took there), where
// the walk follows its way to the singularity (read as a corner, such a turn leaves an
// irregular vertex unexplained and quads oversized beside it), except where an earlier cage of this layout left an
// irregular vertex no singularity explains (Layout::costly_nodes, the second reading of
// QuadOptions::off_node_price): there such a turn is read too, a singular end's included.
// O(curve vertices +
// curves × singularities + kinks × costly spots), every round of build_patches: again on
// the same curves (their tangents are set again where a curve's tail was registered anew
// after a stretch of it was taken off).
void mark_kinks(const Surface& s, Layout& layout, const std::vector<int>& degree) {
  for (const Curve& curve : layout.curves) {
    const int n = static_cast<int>(curve.vertices.size());  // 0: taken off the layout
    if (curve.closed || curve.link || n < 3) continue;
    std::vector<int> captured;  // the curve's ends at singular vertices
    for (int end : {curve.vertices.front(), curve.vertices.back()})
      if (layout.attractor(end)) captured.push_back(end);
    for (int i = 1; i < n; ++i) {
      const int u = curve.vertices[i - 1], v = curve.vertices[i];
      const int h = s.mesh.find_halfedge(s.mesh.vertex_handle(u), s.mesh.vertex_handle(v)).idx();
      const int f = s.in(s.face(h)) ? s.face(h) : s.face(h ^ 1);
      if (!s.in(f)) continue;
      // Both directions snapped on one face, so the field's own turning between the two
      // vertices does not count.
      const Vec3 a = s.snap(f, curve.direction[i - 1]), b = s.snap(f, curve.direction[i]);
      if (std::abs(a.dot(b)) > 0.5) continue;
      bool on_the_way = false;
      for (int end : captured)
        on_the_way |= (s.point[v] - s.point[end]).norm() < kCaptureReach * s.vertex_size[end];
      if (on_the_way && !layout.costly(s.point[v])) continue;
      if (degree[v] == 2) layout.node[v] = 1;
      layout.halfedge_dir[h ^ 1] = -curve.direction[i - 1];
    }
  }
}

}  // namespace

void build_arcs(const Surface& s, Layout& layout, bool kink_nodes, PatchLayout& out) {
  const int n_curves = static_cast<int>(layout.curves.size());
  std::vector<int> degree(s.mesh.n_vertices(), 0);
  for (int e = 0; e < static_cast<int>(layout.edge_curve.size()); ++e)
    if (layout.edge_curve[e] >= 0) {
      const auto h = s.mesh.halfedge_handle(s.mesh.edge_handle(e), 0);
      ++degree[s.mesh.from_vertex_handle(h).idx()];
      ++degree[s.mesh.to_vertex_handle(h).idx()];
    }
  for (int v : s.vertices)
    if (layout.claimed[v] && degree[v] != 2) layout.node[v] = 1;
  if (kink_nodes) mark_kinks(s, layout, degree);
  out.arcs.clear();
  out.halfedge_arc.assign(s.mesh.n_halfedges(), -1);
  out.loop_arcs.assign(n_curves, {});
  for (int c = 0; c < n_curves; ++c) {
    const Curve& curve = layout.curves[c];
    if (curve.vertices.empty()) continue;  // removed
    std::vector<int> vs = curve.vertices;
    if (curve.closed) {
      auto it = std::find_if(vs.begin(), vs.end(), [&](int v) { return layout.node[v] != 0; });
      if (it == vs.end()) layout.node[vs.front()] = 1, it = vs.begin();
      std::rotate(vs.begin(), it, vs.end());
      vs.push_back(vs.front());
    }
    Arc arc;
    arc.curve = c;
    arc.vertices.push_back(vs.front());
    for (size_t i = 1; i < vs.size(); ++i) {
      const int a = vs[i - 1], b = vs[i];
      const auto h = s.mesh.find_halfedge(s.mesh.vertex_handle(a), s.mesh.vertex_handle(b));
      const int id = static_cast<int>(out.arcs.size());
      out.halfedge_arc[h.idx()] = 2 * id;          // even: along the arc
      out.halfedge_arc[h.idx() ^ 1] = 2 * id + 1;  // odd: against it
      const Vec3 e = s.point[b] - s.point[a];
      int f = s.face(h.idx());
      if (!s.in(f)) f = s.face(h.idx() ^ 1);
      arc.length += e.norm();
      // The target counts the arc's progress along its curve's direction, not the length
      // of its mesh-edge path: a path that zigzags about the field line is some 10% longer
      // than the line, and cages came out a fifth denser than the size field asked.
      const Vec3& d = layout.halfedge_dir[h.idx()];
      const double along = d.squaredNorm() > 0 ? std::abs(e.dot(d.normalized())) : e.norm();
      arc.target += along / s.size_along(f, e);
      arc.vertices.push_back(b);
      if (layout.node[b] || i + 1 == vs.size()) {
        if (curve.closed) out.loop_arcs[c].push_back(id);
        out.arcs.push_back(arc);
        arc = Arc();
        arc.curve = c;
        arc.vertices.push_back(b);
      }
    }
  }
}

// Direction in which the curve through halfedge h leaves from(h): towards the point a few
// mesh edges along it (fewer if a node comes first), in the vertex's tangent plane.
static Vec3 curve_chord(const Surface& s, const Layout& layout, int h) {
  const int v = s.from(h);
  const Curve& curve = layout.curves[layout.edge_curve[h >> 1]];
  const std::vector<int>& vs = curve.vertices;
  const int n = static_cast<int>(vs.size());
  int at = -1, step = 0;
  for (int i = 0; i < n && at < 0; ++i) {
    if (vs[i] != v) continue;
    const int next = curve.closed ? (i + 1) % n : i + 1, prev = curve.closed ? (i + n - 1) % n : i - 1;
    if (next < n && vs[next] == s.to(h)) at = i, step = 1;
    else if (prev >= 0 && vs[prev] == s.to(h)) at = i, step = -1;
  }
  int w = s.to(h);
  for (int k = 1, i = at; at >= 0 && k <= 3; ++k) {
    i += step;
    if (curve.closed) i = (i + n) % n;
    if (i < 0 || i >= n) break;
    w = vs[i];
    if (layout.node[w]) break;
  }
  return s.tangent(v, s.point[w] - s.point[v]);
}

// (quad/detail/layout.h)
double sector_angle(const Surface& s, const Layout& layout, int h_out, int h_in, int valence) {
  const int v = s.from(h_out);
  const Vec3& n = s.vertex_normal[v];
  if (valence > 0)
    return ccw_angle(curve_chord(s, layout, h_out), curve_chord(s, layout, h_in ^ 1), n) *
           valence / 4;
  const double angle = ccw_angle(layout.halfedge_dir[h_out], layout.halfedge_dir[h_in ^ 1], n);
  constexpr double kAmbiguous = 0.2;  // radians either side of 0 ≡ 2π
  if (angle > kAmbiguous && angle < 2 * kPi - kAmbiguous) return angle;
  const double chord = ccw_angle(curve_chord(s, layout, h_out), curve_chord(s, layout, h_in ^ 1), n);
  if (chord < kPi) return std::max(angle > kPi ? angle - 2 * kPi : angle, 1e-6);
  return angle < kPi ? 2 * kPi : angle;
}

int next_on_boundary(const Surface& s, const Layout& layout, int h) {
  int c = s.mesh.next_halfedge_handle(s.mesh.halfedge_handle(h)).idx();
  for (int guard = 0; layout.edge_curve[c >> 1] < 0 && guard < 256; ++guard)
    c = s.mesh.next_halfedge_handle(s.mesh.halfedge_handle(c ^ 1)).idx();
  return c;
}

bool remove_stretch(const Surface& s, Layout& layout, std::vector<int> vertices) {
  if (vertices.size() < 2) return false;
  const auto h = s.mesh.find_halfedge(s.mesh.vertex_handle(vertices[0]),
                                      s.mesh.vertex_handle(vertices[1]));
  if (!h.is_valid()) return false;
  const int c = layout.edge_curve[s.mesh.edge_handle(h).idx()];
  if (c < 0 || layout.curves[c].closed) return false;
  const std::vector<int>& cv = layout.curves[c].vertices;
  for (int pass = 0; pass < 2; ++pass, std::reverse(vertices.begin(), vertices.end())) {
    auto it = std::search(cv.begin(), cv.end(), vertices.begin(), vertices.end());
    if (it == cv.end()) continue;
    const int first = static_cast<int>(it - cv.begin());
    remove_arc(s, layout, c, first, first + static_cast<int>(vertices.size()) - 1);
    return true;
  }
  return false;
}

// A stretch as its two ends, lower first: the same stretch traced again by a fix in
// build_patches reads as the one taken off.
std::pair<int, int> stretch_ends(const std::vector<int>& vertices) {
  return std::minmax(vertices.front(), vertices.back());
}

std::vector<int> shortest_open_arc(const Layout& layout, const PatchLayout& patches,
                                   const std::vector<int>& arcs,
                                   const std::set<std::pair<int, int>>& passed) {
  int best = -1;
  for (int a : arcs) {
    if (layout.curves[patches.arcs[a].curve].closed) continue;
    if (passed.count(stretch_ends(patches.arcs[a].vertices))) continue;
    if (best < 0 || patches.arcs[a].length < patches.arcs[best].length) best = a;
  }
  return best < 0 ? std::vector<int>() : patches.arcs[best].vertices;
}

double side_target(const std::vector<Arc>& arcs, const Patch& patch, int k) {
  double sum = 0;
  for (auto& [a, reversed] : patch.sides[k]) sum += arcs[a].target;
  return sum;
}

bool merge_patch(const Surface& s, Layout& layout, const PatchLayout& patches, int patch,
                 std::set<std::pair<int, int>>* removed) {
  std::vector<int> arcs;
  for (const auto& side : patches.patches[patch].sides)
    for (auto& [a, reversed] : side) arcs.push_back(a);
  const std::vector<int> stretch = shortest_open_arc(layout, patches, arcs, *removed);
  if (!remove_stretch(s, layout, stretch)) return false;
  removed->insert(stretch_ends(stretch));
  return true;
}

int straighten_cusps(Layout& layout, const PatchLayout& patches, int patch) {
  int taken = 0;
  for (int h : patches.patches[patch].cusps) taken += layout.no_cusp.insert(h).second;
  if (taken) return taken;
  std::set<int> arcs;
  for (const auto& side : patches.patches[patch].sides)
    for (auto& [a, reversed] : side) arcs.insert(a);
  for (const Patch& other : patches.patches) {
    if (other.cusps.empty()) continue;
    bool shares = &other == &patches.patches[patch];
    for (const auto& side : other.sides)
      for (auto& [a, reversed] : side) shares |= arcs.count(a) > 0;
    if (shares)
      for (int h : other.cusps) taken += layout.no_cusp.insert(h).second;
  }
  return taken;
}


}  // namespace genbrep::quad_detail
