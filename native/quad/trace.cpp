// quad/trace.cpp — field-guided tracing along mesh edges
// (the motorcycle graph of the patch layout, quad/quad.h step 1).
// Separatrices run along mesh edges, not across triangles: two edge paths of an embedded
// mesh can only meet at a vertex, so "stop at the first claimed vertex" yields an embedded
// layout graph without any intersection arithmetic. To keep an edge path on the field line
// the walk tracks the ideal streamline point and picks the forward neighbour closest to it.
// As a layout choice, a walk that comes close beside a nearly parallel curve joins it
// across a short link curve instead of converging onto it (parallel_join). A walk that
// ends on a singular vertex takes the separatrix direction it arrives along, or records
// its chord there (arrival_direction), so that direction is not traced again from the
// singularity.
#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include "quad/detail/layout.h"

namespace genbrep::quad_detail {
namespace {
// A walk takes the shortest free path to a singular vertex ahead (route_to) when it lies
// within acos(kRouteCos) = 18° of the walk's direction: there stepping to the neighbour
// nearest to it goes straight on past it one row over. A wider cone routes walks that
// should have followed the field.
constexpr double kRouteCos = 0.95;
}  // namespace

void register_curve(const Surface& s, Layout& layout, int c) {
  const Curve& curve = layout.curves[c];
  const int n = static_cast<int>(curve.vertices.size());
  const int edges = curve.closed ? n : n - 1;
  for (int i = 0; i < n; ++i) layout.claimed[curve.vertices[i]] = 1;
  for (int i = 0; i < edges; ++i) {
    const int j = (i + 1) % n;
    const auto h = s.mesh.find_halfedge(s.mesh.vertex_handle(curve.vertices[i]),
                                        s.mesh.vertex_handle(curve.vertices[j]));
    GENBREP_CHECK(h.is_valid(), Code::Internal, "quad: layout curve leaves the mesh edges");
    layout.edge_curve[s.mesh.edge_handle(h).idx()] = c;
    layout.halfedge_dir[h.idx()] = curve.direction[i];
    layout.halfedge_dir[h.idx() ^ 1] = -curve.direction[j];
  }
}

void remove_arc(const Surface& s, Layout& layout, int c, int first, int last) {
  Curve& curve = layout.curves[c];
  for (int i = first; i < last; ++i) {
    const auto h = s.mesh.find_halfedge(s.mesh.vertex_handle(curve.vertices[i]),
                                        s.mesh.vertex_handle(curve.vertices[i + 1]));
    layout.edge_curve[s.mesh.edge_handle(h).idx()] = -1;
    layout.halfedge_dir[h.idx()] = layout.halfedge_dir[h.idx() ^ 1] = Vec3::Zero();
  }
  for (int i = first; i <= last; ++i) {
    const int v = curve.vertices[i];
    bool held = layout.attractor(v);
    for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(v)))
      held |= layout.edge_curve[oh.idx() >> 1] >= 0;
    if (!held) layout.claimed[v] = layout.node[v] = 0;
  }
  // The part after the arc becomes a curve of its own (if it has an edge).
  if (last + 1 < static_cast<int>(curve.vertices.size())) {
    Curve tail;
    tail.vertices.assign(curve.vertices.begin() + last, curve.vertices.end());
    tail.direction.assign(curve.direction.begin() + last, curve.direction.end());
    tail.link = curve.link;
    layout.curves.push_back(tail);
    register_curve(s, layout, static_cast<int>(layout.curves.size()) - 1);
  }
  Curve& head = layout.curves[c];  // push_back may have moved it
  const int keep = first >= 1 ? first + 1 : 0;
  head.vertices.resize(keep);
  head.direction.resize(keep);
}

Layout start_layout(const Surface& s) {
  Layout layout;
  const int nv = static_cast<int>(s.mesh.n_vertices());
  layout.edge_curve.assign(s.mesh.n_edges(), -1);
  layout.claimed.assign(nv, 0);
  layout.node.assign(nv, 0);
  layout.halfedge_dir.assign(s.mesh.n_halfedges(), Vec3::Zero());
  layout.on_loop.assign(nv, 0);
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (int v : s.vertices) lo = lo.cwiseMin(s.point[v]), hi = hi.cwiseMax(s.point[v]);
  layout.length_cap = (hi - lo).norm();
  for (int l = 0; l < static_cast<int>(s.partition.loops.size()); ++l) {
    const BoundaryLoop& loop = s.partition.loops[l];
    if (loop.component != s.component) continue;
    Curve curve;
    curve.vertices = loop.vertices;
    curve.closed = true;
    curve.loop = l;
    const int n = static_cast<int>(loop.vertices.size());
    // Tangent from a chord of about half a target edge length: the raw loops zigzag along
    // voxel stairs, and a one-edge tangent would be off by up to 45°.
    for (int i = 0; i < n; ++i) {
      const int v = loop.vertices[i];
      const double reach = 0.5 * s.vertex_size[v];
      int a = i, b = i;
      double la = 0, lb = 0;
      for (int k = 0; k < n / 4 && (la < reach || lb < reach); ++k) {
        const int na = (a + n - 1) % n, nb = (b + 1) % n;
        if (la < reach) la += (s.point[loop.vertices[na]] - s.point[loop.vertices[a]]).norm(), a = na;
        if (lb < reach) lb += (s.point[loop.vertices[nb]] - s.point[loop.vertices[b]]).norm(), b = nb;
      }
      if (a == b) a = (i + n - 1) % n, b = (i + 1) % n;
      curve.direction.push_back(s.tangent(v, s.point[loop.vertices[b]] - s.point[loop.vertices[a]]));
    }
    for (int v : loop.vertices) layout.on_loop[v] = 1;
    layout.curves.push_back(curve);
    register_curve(s, layout, static_cast<int>(layout.curves.size()) - 1);
  }
  for (const Singularity& sing : s.field.singularities)
    if (sing.component == s.component && sing.on_boundary) layout.node[sing.vertex] = 1;
  return layout;
}

namespace {

// One step of the walk from v along d: the neighbour not joined to v by a curve edge that
// is closest to the ideal line (origin, d) with forward progress; -1 if there is none.
int next_vertex(const Surface& s, const Layout& layout, int v, const Vec3& origin, const Vec3& d,
                const std::vector<int>& allowed) {
  int best = -1;
  double best_score = 1e300;
  for (int h : allowed) {
    if (layout.edge_curve[h >> 1] >= 0) continue;
    const int w = s.to(h);
    const Vec3 e = s.point[w] - s.point[v];
    const double forward = e.dot(d);
    if (forward <= 0.2 * e.norm()) continue;
    Vec3 offset = s.point[w] - origin;
    offset -= d * offset.dot(d);
    offset -= s.vertex_normal[w] * s.vertex_normal[w].dot(offset);
    const double score = offset.norm() - 1e-3 * forward;
    if (score < best_score) best_score = score, best = h;
  }
  return best;
}

// The field direction at vertex v closest to d: snapped on the fan face d points into.
Vec3 field_at(const Surface& s, int v, const Vec3& d) {
  int best = -1;
  double best_dot = -2;
  for (auto fh : s.mesh.vf_range(s.mesh.vertex_handle(v))) {
    if (!s.in(fh.idx())) continue;
    Vec3 c = Vec3::Zero();
    for (auto u : s.mesh.fv_range(fh)) c += s.point[u.idx()] / 3.0;
    const double dot = (c - s.point[v]).normalized().dot(d);
    if (dot > best_dot) best_dot = dot, best = fh.idx();
  }
  if (best < 0) return d;
  return s.tangent(v, s.snap(best, d));
}

}  // namespace

namespace {

// A sector of the component's fan at a vertex: outgoing spokes counter-clockwise with the
// polar angle (sum of corner angles) at which each begins, and the polar angles where a
// field direction of a sector face leaves the vertex inside that face.
struct Sector {
  std::vector<int> spokes;
  std::vector<double> polar;
  double total = 0;
  std::vector<double> field_polar;
};

Sector make_sector(const Surface& s, int vertex, int first, int last) {
  Sector sector;
  sector.polar.push_back(0);
  for (int h = first, guard = 0; guard < 64; ++guard) {
    if (!s.in(s.face(h))) return Sector();
    sector.spokes.push_back(h);
    sector.polar.push_back(sector.polar.back() + s.corner_angle(h));
    h = s.ccw(h);
    if (h == last) break;
  }
  sector.total = sector.polar.back();
  for (size_t j = 0; j < sector.spokes.size(); ++j) {
    const int f = s.face(sector.spokes[j]);
    const Vec3 e = (s.point[s.to(sector.spokes[j])] - s.point[vertex]).normalized();
    const Vec3 u = s.field.direction.row(f).transpose();
    const Vec3 n = s.face_normal[f];
    for (int r = 0; r < 4; ++r) {
      const double angle = r * kPi / 2;
      const Vec3 c = std::cos(angle) * u + std::sin(angle) * n.cross(u);
      const double a = std::atan2(n.cross(e).dot(c), e.dot(c));
      if (a >= 0 && a <= s.corner_angle(sector.spokes[j]))
        sector.field_polar.push_back(sector.polar[j] + a);
    }
  }
  std::sort(sector.field_polar.begin(), sector.field_polar.end());
  return sector;
}

// The unit tangent leaving `vertex` at polar angle `angle` of the sector.
Vec3 sector_direction(const Surface& s, const Sector& sector, int vertex, double angle) {
  angle = std::fmod(std::fmod(angle, sector.total) + sector.total, sector.total);
  size_t k = 0;
  while (k + 1 < sector.spokes.size() && sector.polar[k + 1] < angle) ++k;
  const int f = s.face(sector.spokes[k]);
  const Vec3 e = (s.point[s.to(sector.spokes[k])] - s.point[vertex]).normalized();
  const double a = angle - sector.polar[k];
  return s.tangent(vertex, std::cos(a) * e + std::sin(a) * s.face_normal[f].cross(e));
}

// Where a trace running beside an earlier curve should join it: the claimed vertex u
// within `radius` of w (two rings) that lies across d from w (|cos| ≤ 0.6), on a curve
// nearly parallel to d (|cos| > 0.7), not on the trace itself and not within 3 radii of
// its start (where the field turns round the trace's own singularity, its other
// separatrices look parallel), reached from w by the shortest path of at most two free
// edges: [w, (x,) u]. Empty when there is none.
std::vector<int> parallel_join(const Surface& s, const Layout& layout, int w, const Vec3& d,
                               double radius, const std::vector<int>& visited) {
  auto on_trace = [&](int u) { return std::find(visited.begin(), visited.end(), u) != visited.end(); };
  auto free_edge = [&](int a, int b) {
    const auto h = s.mesh.find_halfedge(s.mesh.vertex_handle(a), s.mesh.vertex_handle(b));
    return h.is_valid() && layout.edge_curve[s.mesh.edge_handle(h).idx()] < 0 &&
           (s.in(s.face(h.idx())) || s.in(s.face(h.idx() ^ 1)));
  };
  auto parallel_at = [&](int u) {
    for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(u)))
      if (layout.edge_curve[oh.idx() >> 1] >= 0 && std::abs(layout.halfedge_dir[oh.idx()].dot(d)) > 0.7)
        return true;
    return false;
  };
  std::vector<int> ring{w};
  for (auto vv : s.mesh.vv_range(s.mesh.vertex_handle(w))) ring.push_back(vv.idx());
  const size_t first_ring = ring.size();
  for (size_t k = 1; k < first_ring; ++k)
    for (auto vv : s.mesh.vv_range(s.mesh.vertex_handle(ring[k])))
      if (std::find(ring.begin(), ring.end(), vv.idx()) == ring.end()) ring.push_back(vv.idx());
  std::vector<int> best;
  double best_length = 1e300;
  for (size_t k = 1; k < ring.size(); ++k) {
    const int u = ring[k];
    if (!layout.claimed[u] || on_trace(u)) continue;
    const Vec3 e = s.point[u] - s.point[w];
    if (e.norm() > radius || std::abs(e.dot(d)) > 0.6 * e.norm() || !parallel_at(u)) continue;
    if ((s.point[u] - s.point[visited.front()]).norm() < 3 * radius) continue;
    if (free_edge(w, u) && e.norm() < best_length) best_length = e.norm(), best = {w, u};
    for (auto xv : s.mesh.vv_range(s.mesh.vertex_handle(w))) {
      const int x = xv.idx();
      if (layout.claimed[x] || !free_edge(w, x) || !free_edge(x, u)) continue;
      const double length = (s.point[x] - s.point[w]).norm() + (s.point[u] - s.point[x]).norm();
      if (length < best_length) best_length = length, best = {w, x, u};
    }
  }
  return best;
}

// Whether a curve leaves vertex a along direction d (unit, tangent at a) already: one of
// a's curve edges records a direction there within half a separatrix spacing `half_cos`
// (its cosine) of d.
bool direction_taken(const Surface& s, const Layout& layout, int a, const Vec3& d,
                     double half_cos) {
  for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(a)))
    if (layout.edge_curve[oh.idx() >> 1] >= 0 && layout.halfedge_dir[oh.idx()].dot(d) > half_cos)
      return true;
  return false;
}

// Whether a trace arriving at attractor i from point p comes in along one of its separatrix
// directions (within half their spacing) along which no curve leaves it yet. Arriving
// otherwise would add a sector to the singularity (a valence-6 cage vertex at a valence-5
// singularity, one of its corners squeezed under 45°).
bool free_arrival(const Surface& s, const Layout& layout, size_t i, const Vec3& p) {
  if (i >= layout.attractor_directions.size() || layout.attractor_directions[i].empty()) return true;
  const int a = layout.attractors[i];
  const std::vector<Vec3>& directions = layout.attractor_directions[i];
  const double half = std::cos(kPi / static_cast<double>(directions.size()));
  const Vec3 in = s.tangent(a, p - s.point[a]);
  const Vec3* along = nullptr;
  for (const Vec3& d : directions)
    if (in.dot(d) > half) along = &d;
  return along && !direction_taken(s, layout, a, *along, half);
}

// The direction a curve arriving at attractor w records there (pointing out of w), or
// false to keep the field's on the last fan face. Of w's directions no curve leaves it
// along yet, the one nearest to the chord from w back to the curve's first vertex at least
// a target edge length away, if within QuadOptions::arrival_snap of their spacing; else,
// with QuadOptions::arrival_chord, the chord itself. The walk's last step is one mesh
// edge, and on the mesh split round w it can run up to half the spacing off that chord.
bool arrival_direction(const Surface& s, const Layout& layout, const Curve& curve, Vec3* out) {
  const int w = curve.vertices.back();
  const int at = layout.attractor_index(w);
  const size_t i = static_cast<size_t>(at);
  if ((layout.arrival_snap <= 0 && !layout.arrival_chord) || at < 0 ||
      i >= layout.attractor_directions.size() || layout.attractor_directions[i].empty() ||
      curve.vertices.size() < 2)
    return false;
  int back = static_cast<int>(curve.vertices.size()) - 2;
  while (back > 0 && (s.point[curve.vertices[back]] - s.point[w]).norm() < s.vertex_size[w]) --back;
  const Vec3 in = s.tangent(w, s.point[curve.vertices[back]] - s.point[w]);
  const std::vector<Vec3>& directions = layout.attractor_directions[i];
  const double spacing = 2 * kPi / static_cast<double>(directions.size());
  const double half = std::cos(0.5 * spacing);
  const Vec3* nearest = nullptr;
  double best = std::cos(layout.arrival_snap * spacing);
  for (const Vec3& d : directions)
    if (layout.arrival_snap > 0 && in.dot(d) > best && !direction_taken(s, layout, w, d, half))
      best = in.dot(d), nearest = &d;
  if (!nearest && !layout.arrival_chord) return false;
  *out = nearest ? *nearest : in;
  return true;
}

// The shortest path from v to attractor i (vertex a) along free edges (on no curve, beside
// a face of the component) through vertices neither claimed nor on the trace (`visited`),
// no longer than 1.5 |v a| (a detour round a curve is not a way to it), the first step
// one of `allowed`, arriving at a along a free separatrix direction (free_arrival): the
// vertices after v, ending with a; empty if there is none.
std::vector<int> route_to(const Surface& s, const Layout& layout, int v, size_t i,
                          const std::vector<int>& allowed, const std::vector<int>& visited) {
  const int a = layout.attractors[i];
  const double limit = 1.5 * (s.point[a] - s.point[v]).norm();
  auto on_trace = [&](int u) { return std::find(visited.begin(), visited.end(), u) != visited.end(); };
  std::unordered_map<int, double> distance{{v, 0.0}};
  std::unordered_map<int, int> previous{{v, -1}};
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  queue.push({0.0, v});
  bool reached = false;
  while (!queue.empty() && !reached) {
    const auto [dv, u] = queue.top();
    queue.pop();
    if (dv > distance[u]) continue;
    if (u == a) {
      reached = true;
      break;
    }
    for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(u))) {
      const int h = oh.idx(), w = s.to(h);
      if (layout.edge_curve[h >> 1] >= 0 || (!s.in(s.face(h)) && !s.in(s.face(h ^ 1)))) continue;
      if (u == v && std::find(allowed.begin(), allowed.end(), h) == allowed.end()) continue;
      if (w != a && (layout.claimed[w] || on_trace(w))) continue;
      if (w == a && !free_arrival(s, layout, i, s.point[u])) continue;
      const double dw = dv + (s.point[w] - s.point[u]).norm();
      if (dw > limit) continue;
      const auto it = distance.find(w);
      if (it != distance.end() && it->second <= dw) continue;
      distance[w] = dw, previous[w] = u;
      queue.push({dw, w});
    }
  }
  if (!reached) return {};
  std::vector<int> path;
  for (int u = a; u != v; u = previous[u]) path.push_back(u);
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace

bool trace_direction(const Surface& s, Layout& layout, int vertex, std::vector<int> allowed,
                     Vec3 d, bool snap_to_field) {
  // A first step onto a claimed vertex would enclose a one-triangle patch.
  allowed.erase(std::remove_if(allowed.begin(), allowed.end(),
                               [&](int h) { return layout.claimed[s.to(h)] != 0; }),
                allowed.end());
  if (allowed.empty()) return false;
  Curve curve;
  curve.vertices.push_back(vertex);
  curve.direction.push_back(d);
  Vec3 origin = s.point[vertex];
  int v = vertex;
  std::vector<int> visited{vertex};
  std::vector<int> route;  // the rest of the way to a singular vertex ahead (route_to)
  double travelled = 0;
  const double length_cap = layout.length_cap;
  for (int step = 0; step < static_cast<int>(s.vertices.size()) + 1; ++step) {
    int h = -1;
    // Near a singular vertex ahead, head straight for it: separatrices that pass a
    // singularity at less than a third of an edge length would leave a sliver patch. Only
    // along one of its own separatrix directions that is still free (free_arrival), by the
    // shortest free path (route_to): stepping to the neighbour nearest to it can run past
    // it one row of triangles over, where the rows are long and thin along the trace (two
    // separatrices then run side by side a sliver apart, and one patch has to take all its
    // rows through that strip).
    if (route.empty())
      for (size_t i = 0; i < layout.attractors.size(); ++i) {
        const int a = layout.attractors[i];
        if (a == vertex || a == v) continue;
        const Vec3 to_a = s.point[a] - s.point[v];
        if (to_a.norm() > kCaptureReach * s.vertex_size[v] || to_a.normalized().dot(d) < 0.6)
          continue;
        if (!free_arrival(s, layout, i, s.point[v])) continue;
        if (to_a.normalized().dot(d) > kRouteCos) {
          route = route_to(s, layout, v, i, allowed, visited);
          if (!route.empty()) break;
        }
        double best = to_a.norm();
        for (int c : allowed) {
          if (layout.edge_curve[c >> 1] >= 0) continue;
          const double dist = (s.point[a] - s.point[s.to(c)]).norm();
          if (dist < best) best = dist, h = c;
        }
        if (h >= 0) break;
      }
    if (!route.empty()) {
      for (int c : allowed)
        if (s.to(c) == route.front()) h = c;
      route.erase(route.begin());
    }
    if (h < 0) h = next_vertex(s, layout, v, origin, d, allowed);
    if (h < 0) {  // no forward edge: take any free edge rather than leave a dangling end
      double best_forward = -1e300;
      for (int c : allowed) {
        if (layout.edge_curve[c >> 1] >= 0) continue;
        if (!s.in(s.face(c)) && !s.in(s.face(c ^ 1))) continue;
        const double forward = (s.point[s.to(c)] - s.point[v]).dot(d);
        if (forward > best_forward) best_forward = forward, h = c;
      }
      if (h < 0) break;
    }
    const int w = s.to(h);
    const Vec3 step_vector = s.point[w] - s.point[v];
    origin += d * (s.point[w] - origin).dot(d);
    const Vec3 heading = step_vector.dot(d) > 0 ? d : Vec3(step_vector.normalized());
    d = snap_to_field ? field_at(s, w, heading) : s.tangent(w, heading);
    curve.vertices.push_back(w);
    curve.direction.push_back(d);
    const bool own = std::find(visited.begin(), visited.end(), w) != visited.end();
    travelled += step_vector.norm();
    // A transversal crossing of another separatrix is passed through (no T-junction, so
    // opposite patch sides stay single arcs); loops, singular vertices, the trace itself
    // and near-parallel meetings end the trace.
    bool cross = false;
    if (layout.allow_crossing && layout.claimed[w] && !own && !layout.on_loop[w] &&
        travelled < length_cap && !layout.attractor(w)) {
      for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(w)))
        if (layout.edge_curve[oh.idx() >> 1] >= 0 &&
            std::abs(layout.halfedge_dir[oh.idx()].dot(d)) < 0.5)
          cross = true;
    }
    // Running beside an earlier curve (closer than merge_parallel target edges, nearly
    // parallel): join it now, across a short connecting curve with a corner at w, rather
    // than converge onto it at a shallow angle further on (a wedge patch that no reading
    // of corners makes a rectangle). The strip left between is a sliver patch.
    if (layout.merge_parallel > 0 && !layout.claimed[w] && !own) {
      const std::vector<int> join =
          parallel_join(s, layout, w, d, layout.merge_parallel * s.vertex_size[w], visited);
      if (!join.empty()) {
        const int c = static_cast<int>(layout.curves.size());
        layout.curves.push_back(curve);
        register_curve(s, layout, c);
        Curve link;
        link.link = true;
        Vec3 across = s.point[join.back()] - s.point[w];
        across -= d * d.dot(across);
        for (int u : join) {
          link.vertices.push_back(u);
          link.direction.push_back(field_at(s, u, s.tangent(u, across)));
        }
        layout.curves.push_back(link);
        register_curve(s, layout, c + 1);
        ++layout.separatrices;
        ++layout.parallel_joins;
        layout.node[vertex] = layout.node[w] = layout.node[join.back()] = 1;
        return true;
      }
    }
    if ((layout.claimed[w] && !cross) || own) {
      const int c = static_cast<int>(layout.curves.size());
      // Arriving at a singular vertex along one of its free separatrix directions: that
      // direction is taken (the singularity's own separatrix is not traced beside it);
      // further off one, the chord it comes in along is.
      Vec3 along;
      if (!own && arrival_direction(s, layout, curve, &along)) curve.direction.back() = -along;
      layout.curves.push_back(curve);
      register_curve(s, layout, c);
      layout.node[vertex] = 1;
      layout.node[w] = 1;
      ++layout.separatrices;
      return true;
    }
    // Claim as we go so that traces of one round see each other.
    visited.push_back(w);
    v = w;
    allowed.clear();
    for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(v))) allowed.push_back(oh.idx());
  }
  ++layout.dropped_traces;
  return false;
}

bool trace_from(const Surface& s, Layout& layout, int vertex, int first, int last,
                double fraction, bool snap_to_field) {
  const Sector sector = make_sector(s, vertex, first, last);
  if (sector.total <= 0 || sector.spokes.size() < 2) return false;
  double angle = fraction * sector.total, best = 1e300;
  if (snap_to_field)
    for (double p : sector.field_polar)
      if (p > 0.2 * sector.total && p < 0.8 * sector.total &&
          std::abs(p - fraction * sector.total) < best)
        best = std::abs(p - fraction * sector.total), angle = p;
  const Vec3 d = sector_direction(s, sector, vertex, angle);
  // Interior spokes only: the first step must not run along the sector's own curves.
  std::vector<int> allowed(sector.spokes.begin() + 1, sector.spokes.end());
  return trace_direction(s, layout, vertex, allowed, d, snap_to_field);
}

// (quad/detail/layout.h)
bool cut_pinch(const Surface& s, Layout& layout, const std::vector<int>& faces,
               const std::vector<int>& from, const std::vector<int>& to) {
  if (from.empty() || to.empty()) return false;
  std::vector<int> patch(faces);
  std::sort(patch.begin(), patch.end());
  auto in_patch = [&](int f) { return f >= 0 && std::binary_search(patch.begin(), patch.end(), f); };
  std::unordered_map<int, double> distance;
  std::unordered_map<int, int> previous;
  std::unordered_set<int> target(to.begin(), to.end());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (int v : from) {
    if (target.count(v)) continue;
    distance[v] = 0, previous[v] = -1;
    queue.push({0.0, v});
  }
  int end = -1;
  while (!queue.empty() && end < 0) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v]) continue;
    const bool start = previous[v] < 0;
    for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(v))) {
      const int h = oh.idx(), w = s.to(h);
      if (layout.edge_curve[h >> 1] >= 0) continue;
      if (!in_patch(s.face(h)) && !in_patch(s.face(h ^ 1))) continue;
      // Through unclaimed vertices only; a claimed one ends the path if it is a target
      // (and not the first step: a one-edge cut would enclose a one-triangle patch).
      if (layout.claimed[w] && !(target.count(w) && !start)) continue;
      const double dw = d + (s.point[w] - s.point[v]).norm();
      const auto it = distance.find(w);
      if (it != distance.end() && it->second <= dw) continue;
      distance[w] = dw, previous[w] = v;
      if (layout.claimed[w]) {
        end = w;
        break;
      }
      queue.push({dw, w});
    }
  }
  if (end < 0) return false;
  Curve curve;
  for (int v = end; v >= 0; v = previous[v]) curve.vertices.push_back(v);
  std::reverse(curve.vertices.begin(), curve.vertices.end());
  const int n = static_cast<int>(curve.vertices.size());
  for (int i = 0; i < n; ++i) {
    const int a = curve.vertices[std::max(i - 1, 0)], b = curve.vertices[std::min(i + 1, n - 1)];
    const int v = curve.vertices[i];
    curve.direction.push_back(field_at(s, v, s.tangent(v, s.point[b] - s.point[a])));
  }
  const int c = static_cast<int>(layout.curves.size());
  layout.curves.push_back(curve);
  register_curve(s, layout, c);
  layout.node[curve.vertices.front()] = layout.node[curve.vertices.back()] = 1;
  ++layout.separatrices;
  return true;
}

// Separatrix directions of a singular vertex: `valence` evenly spaced polar angles,
// rotated so that they best match the field directions leaving the vertex.
std::vector<Vec3> singular_directions(const Surface& s, int vertex, int valence,
                                      std::vector<int>* spokes) {
  int spoke = -1;
  for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(vertex))) { spoke = oh.idx(); break; }
  const Sector sector = make_sector(s, vertex, spoke, spoke);
  if (sector.total <= 0) return {};
  *spokes = sector.spokes;
  const double step = sector.total / valence;
  double offset = 0.5 * step, best = 1e300;
  for (double c : sector.field_polar) {
    double cost = 0;
    for (double p : sector.field_polar) {
      const double r = std::fmod(std::abs(p - c), step);
      cost += std::min(r, step - r);
    }
    if (cost < best) best = cost, offset = c;
  }
  std::vector<Vec3> directions;
  for (int k = 0; k < valence; ++k)
    directions.push_back(sector_direction(s, sector, vertex, offset + k * step));
  return directions;
}

void trace_separatrices(const Surface& s, Layout& layout, const QuadOptions& options,
                        Messages& messages) {
  std::vector<Singularity> interior, concave;
  for (const Singularity& sing : s.field.singularities) {
    if (sing.component != s.component) continue;
    if (sing.on_boundary) {
      if (sing.index < 0) concave.push_back(sing);
    } else {
      interior.push_back(sing);
    }
  }
  // Cancelling ± pairs (the zigzag of unrelaxed loops leaves them one ring apart).
  std::vector<char> cancelled(interior.size(), 0);
  struct Pair { double distance; int a, b; };
  std::vector<Pair> pairs;
  for (size_t i = 0; i < interior.size(); ++i)
    for (size_t j = i + 1; j < interior.size(); ++j) {
      if ((interior[i].index > 0) == (interior[j].index > 0)) continue;
      const double dist = (s.point[interior[i].vertex] - s.point[interior[j].vertex]).norm();
      const double limit = options.pair_cancel_distance *
          0.5 * (s.vertex_size[interior[i].vertex] + s.vertex_size[interior[j].vertex]);
      if (dist < limit) pairs.push_back({dist, int(i), int(j)});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
    return x.distance != y.distance ? x.distance < y.distance : x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  for (const Pair& p : pairs) {
    if (cancelled[p.a] || cancelled[p.b]) continue;
    if (std::abs(interior[p.a].index) != 1 || std::abs(interior[p.b].index) != 1) continue;
    cancelled[p.a] = cancelled[p.b] = 1;
    ++layout.cancelled_pairs;
  }
  // Separatrices leave in `valence` evenly spaced polar directions snapped to the field,
  // traced in turns (one separatrix of every singularity per round) so no singularity
  // claims the surface first.
  const std::string who = "component " + std::to_string(s.component);
  // Singularities within `boundary_absorb_distance` of a loop are left to the boundary:
  // unrelaxed loops zigzag and the field compensates one ring inside with ± pairs (their
  // indices cancel along the loop); tracing them would cut slivers along every loop.
  int absorbed = 0;
  std::vector<int> loop_vertices;
  for (const Curve& c : layout.curves)
    if (c.closed) loop_vertices.insert(loop_vertices.end(), c.vertices.begin(), c.vertices.end());
  for (size_t i = 0; i < interior.size(); ++i) {
    if (cancelled[i]) continue;
    const int v = interior[i].vertex;
    for (int w : loop_vertices)
      if ((s.point[v] - s.point[w]).norm() < options.boundary_absorb_distance * s.vertex_size[v]) {
        cancelled[i] = 1;
        ++absorbed;
        break;
      }
  }
  if (absorbed)
    messages.notes.push_back(who + ": " + std::to_string(absorbed) +
                          " singularities next to a loop left to the boundary (not traced)");
  // All separatrix directions first; then traced in turns (the k-th of every singularity
  // per round) so no singularity claims the surface first. A direction already taken by
  // a separatrix that arrived from elsewhere is skipped.
  struct Start { int vertex; Vec3 direction; double spacing; std::vector<int> spokes; };
  std::vector<std::vector<Start>> rounds;
  for (size_t i = 0; i < interior.size(); ++i) {
    if (cancelled[i]) continue;
    const int valence = 4 - interior[i].index;
    if (valence < 1) continue;
    layout.attractors.push_back(interior[i].vertex);
    std::vector<int> spokes;
    const std::vector<Vec3> directions = singular_directions(s, interior[i].vertex, valence, &spokes);
    layout.attractor_directions.push_back(directions);
    for (size_t k = 0; k < directions.size(); ++k) {
      if (rounds.size() <= k) rounds.resize(k + 1);
      rounds[k].push_back({interior[i].vertex, directions[k], 2 * kPi / valence, spokes});
    }
  }
  for (int a : layout.attractors) layout.claimed[a] = 1;
  layout.arrival_snap = options.arrival_snap;
  layout.arrival_chord = options.arrival_chord;
  layout.allow_crossing = options.cross_separatrices;
  layout.merge_parallel = options.join_parallel ? options.join_parallel_distance / options.density : 0;
  int missing = 0;
  for (const auto& round : rounds)
    for (const Start& start : round) {
      if (direction_taken(s, layout, start.vertex, start.direction, std::cos(0.5 * start.spacing)))
        continue;
      missing += !trace_direction(s, layout, start.vertex, start.spokes, start.direction, true);
    }
  layout.allow_crossing = false;
  layout.merge_parallel = 0;
  if (layout.parallel_joins)
    messages.notes.push_back(who + ": " + std::to_string(layout.parallel_joins) +
                          " separatrices joined an earlier curve they ran beside");
  if (missing)
    messages.notes.push_back(who + ": " + std::to_string(missing) +
                          " separatrices could not leave their singularity");
  for (const Singularity& sing : concave) {
    // The component's fan at a boundary vertex runs from its outgoing loop edge
    // counter-clockwise to the reverse of its incoming loop edge.
    int first = -1, last = -1;
    for (auto oh : s.mesh.voh_range(s.mesh.vertex_handle(sing.vertex))) {
      const int h = oh.idx();
      if (layout.edge_curve[h >> 1] < 0) continue;
      if (s.in(s.face(h))) first = h;
      else last = h;
    }
    if (first < 0 || last < 0) continue;
    for (int k = 0; k < -sing.index; ++k)
      if (!trace_from(s, layout, sing.vertex, first, last, (k + 1.0) / (1 - sing.index), true))
        messages.warnings.push_back(who + ": no separatrix could leave concave corner " +
                              std::to_string(sing.vertex));
  }
  if (layout.cancelled_pairs)
    messages.notes.push_back("component " + std::to_string(s.component) + ": " +
                          std::to_string(layout.cancelled_pairs) +
                          " cancelling singularity pairs not traced");
}

}  // namespace genbrep::quad_detail
