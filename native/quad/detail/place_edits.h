// quad/detail/place_edits.h — internals of quad/place.cpp: a window of the cage as a small
// connectivity state, and every single edit of it (edge rotation, diagonal collapse, vertex
// split), made, handed to a caller and taken back.
#pragma once
#include <algorithm>
#include <array>
#include <tuple>
#include <utility>
#include <vector>

#include "core/types.h"

namespace genbrep::quad_detail::place {

constexpr int kScoreRings = 5;   // vertices counted; every edit's changed vertices lie here
constexpr int kMaxSplitValence = 8;  // the most quads at a vertex a split takes apart

// A window's connectivity after some edits, in local vertex ids.
struct State {
  std::vector<std::array<int, 4>> quads;  // quads[i][0] == -1: removed
  std::vector<int> origin;                // per quad: the cage's quad, or -1 (added)
  std::vector<int> valence, ring;         // per local vertex (ring: from the vertex)
  std::vector<char> fixed;                // on a chain or a crease edge
  std::vector<char> shed;                 // a chain vertex that may lose a quad (sheds)
  std::vector<Vec3> point;
  std::vector<double> reach;
  std::vector<int> changed;               // vertices whose valence an edit changed
};

// Directed edge (a, b) → quad * 4 + k, sorted for lookups.
struct Halfedges {
  explicit Halfedges(const State& s) : n(static_cast<long long>(s.valence.size())) {
    for (size_t q = 0; q < s.quads.size(); ++q)
      if (s.quads[q][0] >= 0)
        for (int k = 0; k < 4; ++k)
          list.push_back({s.quads[q][k] * n + s.quads[q][(k + 1) % 4], static_cast<int>(q * 4 + k)});
    std::sort(list.begin(), list.end());
  }
  int find(int a, int b) const {  // quad * 4 + k, or -1
    const auto it = std::lower_bound(list.begin(), list.end(), std::pair<long long, int>{a * n + b, -1});
    return it != list.end() && it->first == a * n + b ? it->second : -1;
  }
  bool joined(int a, int b) const { return find(a, b) >= 0 || find(b, a) >= 0; }
  long long n;
  std::vector<std::pair<long long, int>> list;
};

// Edits a state in place and takes them back (each edit is tried, scored and undone).
class Editor {
 public:
  explicit Editor(State& s)
      : s_(s), quads_(s.quads.size()), vertices_(s.valence.size()), changed_(s.changed.size()) {}
  void set_quad(int q, const std::array<int, 4>& c) {
    quad_log_.push_back({q, s_.quads[q]});
    s_.quads[q] = c;
  }
  void add_quad(const std::array<int, 4>& c) { s_.quads.push_back(c), s_.origin.push_back(-1); }
  // Call before changing v's valence, point or reach.
  void touch(int v) {
    vertex_log_.push_back({v, s_.valence[v], s_.point[v], s_.reach[v]});
    if (std::find(s_.changed.begin(), s_.changed.end(), v) == s_.changed.end())
      s_.changed.push_back(v);
  }
  int add_vertex(int valence, int ring, const Vec3& point, double reach) {
    const int v = static_cast<int>(s_.valence.size());
    s_.valence.push_back(valence), s_.ring.push_back(ring), s_.fixed.push_back(0);
    s_.shed.push_back(0);
    s_.point.push_back(point), s_.reach.push_back(reach), s_.changed.push_back(v);
    return v;
  }
  void undo() {
    for (auto it = quad_log_.rbegin(); it != quad_log_.rend(); ++it) s_.quads[it->first] = it->second;
    for (auto it = vertex_log_.rbegin(); it != vertex_log_.rend(); ++it) {
      const auto& [v, valence, point, reach] = *it;
      s_.valence[v] = valence, s_.point[v] = point, s_.reach[v] = reach;
    }
    s_.quads.resize(quads_), s_.origin.resize(quads_);
    s_.valence.resize(vertices_), s_.ring.resize(vertices_), s_.fixed.resize(vertices_);
    s_.shed.resize(vertices_);
    s_.point.resize(vertices_), s_.reach.resize(vertices_);
    s_.changed.resize(changed_);
  }

 private:
  State& s_;
  size_t quads_, vertices_, changed_;
  std::vector<std::pair<int, std::array<int, 4>>> quad_log_;
  std::vector<std::tuple<int, int, Vec3, double>> vertex_log_;
};

// Where single edits of a window's state can go (for_each_edit): the state's halfedges and
// the quads at each vertex as they were before any edit, the focus, and which vertices an
// edit may move or take a quad from.
struct EditSites {
  EditSites(State& s, const std::vector<char>& focus)
      : s(s), focus(focus), he(s), nq(static_cast<int>(s.quads.size())) {
    first.assign(s.valence.size() + 1, 0);
    for (int q = 0; q < nq; ++q)
      if (s.quads[q][0] >= 0)
        for (int v : s.quads[q]) ++first[v + 1];
    for (size_t v = 0; v + 1 < first.size(); ++v) first[v + 1] += first[v];
    at_list.resize(first.back());
    {
      std::vector<int> fill(first.begin(), first.end() - 1);
      for (int q = 0; q < nq; ++q)
        if (s.quads[q][0] >= 0)
          for (int v : s.quads[q]) at_list[fill[v]++] = q;
    }
  }
  struct Span {
    const int *b, *e;
    const int* begin() const { return b; }
    const int* end() const { return e; }
    size_t size() const { return static_cast<size_t>(e - b); }
  };
  Span quads_at(int v) const { return Span{at_list.data() + first[v], at_list.data() + first[v + 1]}; }
  bool in_focus(int q) const {
    if (s.quads[q][0] < 0) return false;
    for (int v : s.quads[q]) if (focus[v]) return true;
    return false;
  }
  bool movable(int v) const { return !s.fixed[v] && s.ring[v] <= kScoreRings; }
  // Vertices an edit takes a quad from: free ones of four or more, and chain vertices of
  // three or more that may shed one (their place and chain edges stay).
  bool loses(int v) const {
    return movable(v) ? s.valence[v] >= 4
                      : s.shed[v] && s.valence[v] >= 3 && s.ring[v] <= kScoreRings;
  }
  State& s;
  const std::vector<char>& focus;
  const Halfedges he;
  const int nq;
  // The quads at each vertex: quads_at(v) (compressed rows).
  std::vector<int> first, at_list;
};

// The edge rotations of quad q (edits of for_each_edit).
template <class Take>
void rotations_at(State& s, const EditSites& at, int q, Take& take) {
  const std::array<int, 4> c = s.quads[q];
  for (int k = 0; k < 4; ++k) {
    const int u = c[k], w = c[(k + 1) % 4];
    if (!at.loses(u) || !at.loses(w) || (!at.movable(u) && !at.movable(w))) continue;
    const int h = at.he.find(w, u);
    if (h < 0 || (u > w && at.in_focus(h / 4))) continue;  // each edge once
    const int q2 = h / 4, k2 = h % 4;
    const int a = c[(k + 2) % 4], b = c[(k + 3) % 4];
    const int cc = s.quads[q2][(k2 + 2) % 4], d = s.quads[q2][(k2 + 3) % 4];
    const std::array<int, 6> hexagon = {u, cc, d, w, a, b};
    bool distinct = true;
    for (int i = 0; i < 6; ++i)
      for (int j = i + 1; j < 6; ++j) distinct &= hexagon[i] != hexagon[j];
    if (!distinct) continue;
    for (int r = 0; r < 2; ++r) {
      const int x = r == 0 ? cc : d, y = r == 0 ? a : b;
      if (!at.movable(x) || !at.movable(y) || at.he.joined(x, y)) continue;
      Editor edit(s);
      if (r == 0) edit.set_quad(q, {cc, d, w, a}), edit.set_quad(q2, {a, b, u, cc});
      else edit.set_quad(q, {d, w, a, b}), edit.set_quad(q2, {b, u, cc, d});
      for (int v : {u, w, x, y}) edit.touch(v);
      --s.valence[u], --s.valence[w], ++s.valence[x], ++s.valence[y];
      take();
      edit.undo();
    }
  }
}

// The diagonal collapses of quad q (edits of for_each_edit).
template <class Take>
void collapses_at(State& s, const EditSites& at, int q, Take& take) {
  const std::array<int, 4> c = s.quads[q];
  // Diagonal collapses: p0 and p2 merge (valence a + c − 2 ≤ 6), p1 and p3 keep ≥ 3 quads
  // (a shedding chain vertex ≥ 2).
  for (int k = 0; k < 2; ++k) {
    const int p0 = c[k], p1 = c[k + 1], p2 = c[k + 2], p3 = c[(k + 3) % 4];
    if (!at.movable(p0) || !at.movable(p2) || !at.loses(p1) || !at.loses(p3)) continue;
    if (s.valence[p0] + s.valence[p2] - 2 > 6) continue;
    if (at.he.joined(p0, p2)) continue;
    // The link condition: p0 and p2 share no neighbour but p1 and p3, and no other quad.
    std::vector<int> around0;  // p0's edge neighbours
    bool linked = false;
    for (int r : at.quads_at(p0)) {
      if (r == q) continue;
      const auto& e = s.quads[r];
      linked |= std::count(e.begin(), e.end(), p2) > 0;
      for (int j = 0; j < 4; ++j)
        if (e[j] == p0) around0.push_back(e[(j + 1) % 4]), around0.push_back(e[(j + 3) % 4]);
    }
    for (int r : at.quads_at(p2)) {
      if (r == q || linked) continue;
      const auto& e = s.quads[r];
      for (int j = 0; j < 4; ++j)
        if (e[j] == p2)
          for (int n : {e[(j + 1) % 4], e[(j + 3) % 4]})
            linked |= n != p1 && n != p3 &&
                      std::find(around0.begin(), around0.end(), n) != around0.end();
    }
    if (linked) continue;
    Editor edit(s);
    for (int v : {p0, p1, p2, p3}) edit.touch(v);
    edit.set_quad(q, {-1, -1, -1, -1});
    for (int r : at.quads_at(p2)) {
      if (r == q) continue;
      std::array<int, 4> e = s.quads[r];
      for (int& v : e) if (v == p2) v = p0;
      edit.set_quad(r, e);
    }
    s.valence[p0] += s.valence[p2] - 2, s.valence[p2] = 0;
    --s.valence[p1], --s.valence[p3];
    s.point[p0] = 0.5 * (s.point[p0] + s.point[p2]);
    s.reach[p0] = 0.5 * (s.reach[p0] + s.reach[p2]);
    take();
    edit.undo();
  }
}

// The vertex splits of the vertices in `splittable` (edits of for_each_edit).
template <class Take>
void splits_at(State& s, const EditSites& at, std::vector<int> splittable, Take& take) {
  // Vertex splits: u of n ≥ 5 quads keeps m of them (2 ≤ m ≤ n − 2), a new vertex w takes
  // the others, and the quad (p, u, q, w) goes between.
  std::sort(splittable.begin(), splittable.end());
  splittable.erase(std::unique(splittable.begin(), splittable.end()), splittable.end());
  for (int u : splittable) {
    const int n = s.valence[u];
    if (!at.movable(u) || s.ring[u] >= kScoreRings || n < 5 || n > kMaxSplitValence) continue;
    if (static_cast<int>(at.quads_at(u).size()) != n) continue;
    // The fan of u in order: quad j runs from after[j] (after u) to before[j].
    std::vector<int> fan, after, before;
    for (int r : at.quads_at(u))
      for (int k = 0; k < 4; ++k)
        if (s.quads[r][k] == u) {
          fan.push_back(r);
          after.push_back(s.quads[r][(k + 1) % 4]);
          before.push_back(s.quads[r][(k + 3) % 4]);
        }
    std::vector<int> order = {0};
    while (static_cast<int>(order.size()) < n) {
      int next = -1;
      for (int j = 0; j < n; ++j)
        if (after[j] == before[order.back()]) next = j;
      if (next <= 0) break;
      order.push_back(next);
    }
    if (static_cast<int>(order.size()) != n || before[order.back()] != after[order[0]]) continue;
    for (int i = 0; i < n; ++i)
      for (int m = 2; m <= n - 2; ++m) {
        const int p = after[order[i]], pq = after[order[(i + m) % n]];
        if (p == pq || !at.movable(p) || !at.movable(pq) || at.he.joined(p, pq)) continue;
        Editor edit(s);
        const Vec3 at = s.point[u];
        Vec3 side[2] = {Vec3::Zero(), Vec3::Zero()};
        for (int j = 0; j < n; ++j) {
          const int r = fan[order[j]];
          for (int k = 0; k < 4; ++k) side[((j - i + n) % n) < m ? 0 : 1] += s.point[s.quads[r][k]];
        }
        for (int v : {u, p, pq}) edit.touch(v);
        const int w = edit.add_vertex(n - m + 1, s.ring[u],
                                      at + (side[1] / (4.0 * (n - m)) - at) / 3, s.reach[u]);
        for (int j = 0; j < n; ++j)
          if (((j - i + n) % n) >= m) {
            const int r = fan[order[j]];
            std::array<int, 4> e = s.quads[r];
            for (int& v : e) if (v == u) v = w;
            edit.set_quad(r, e);
          }
        edit.add_quad({p, u, pq, w});
        s.valence[u] = m + 1;
        ++s.valence[p], ++s.valence[pq];
        s.point[u] = at + (side[0] / (4.0 * m) - at) / 3;
        take();
        edit.undo();
      }
  }
}

// Makes every single edit of `s` on quads with a corner in `focus` in turn, calls `take`
// on the edited state, and takes the edit back.
template <class Take>
void for_each_edit(State& s, const std::vector<char>& focus, Take take) {
  const EditSites at(s, focus);
  const int nq = at.nq;
  std::vector<int> splittable;
  for (int q = 0; q < nq; ++q) {
    if (!at.in_focus(q)) continue;
    const std::array<int, 4> c = s.quads[q];
    for (int v : c) splittable.push_back(v);
    rotations_at(s, at, q, take);
    collapses_at(s, at, q, take);
  }
  splits_at(s, at, std::move(splittable), take);
}

}  // namespace genbrep::quad_detail::place
