// quad/corners.cpp — how patch corners are read (quad/quad.h step 1): a sector's quarter
// turns at its node (node_quarters: all of the node's sectors on one grid, so they add up
// to the node's quarter turns; QuadOptions::node_readings), the readings of all patches
// chosen at once (QuadOptions::global_corners; below), and a lone patch's best rectangle
// (best_corners, build_patches' patch-by-patch fit).
// A patch whose angles do not read four corners needs some sector re-read: a straight one
// (2 quarter turns) as a corner (1) or the reverse. Chosen patch by patch (best_corners),
// the node there gets a quad too many or too few in the cage — an irregular vertex no
// field singularity explains — although the patch across the node is often short of the
// opposite corner. Chosen together they pair up: a node's sectors should add up to the
// quarter turns the node has (4, a traced singularity's valence, a loop node's reading),
// and a change in one patch is balanced at the same node by its neighbour, or passed on
// through it, where the angles make that cheaper than an irregular vertex.
// The choice is a min-cost flow (transportation problem: every sector is one arc between
// its patch and its node), solved exactly by GLPK's out-of-kilter algorithm on integral
// data; it is the linear program "q_s ∈ [1, 2] per free sector, Σ(2 − q_s) = 4 per patch,
// Σ q_s + slack = target per node, minimise Σ |angle_s − q_s · 90°| + price · |slack|",
// whose matrix is totally unimodular. The price is kCornerNodePrice, or off_node_price at
// the nodes near irregular vertices an earlier cage of the layout left away from
// singularities (Layout::costly_nodes). A sector may carry a side cost too (patches.cpp: how
// far from a rectangle its patch would be, which a flow cannot weigh itself). The flow is
// an order of magnitude faster than the same LP through GLPK's simplex.
// Complexity: one min-cost flow on (patches + nodes) vertices and (sectors + 2 nodes) arcs.
#include <glpk.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "quad/detail/patches.h"

namespace genbrep::quad_detail {
namespace {
constexpr double kQuarter = 1.57079632679489661923;  // π/2

struct GraphDeleter {
  void operator()(glp_graph* g) const { glp_delete_graph(g); }
};

// Deviation of `angle` from `quarters` quarter turns, in quarter turns.
double deviation(double angle, int quarters) {
  return std::abs(angle - quarters * kQuarter) / kQuarter;
}
}  // namespace

std::vector<int> choose_corners(const std::vector<SectorChoice>& sectors, int patches,
                                const std::map<int, int>& node_target, double node_price,
                                const std::map<int, double>& node_prices) {
  std::vector<int> chosen(sectors.size());
  for (size_t i = 0; i < sectors.size(); ++i) chosen[i] = sectors[i].quarters;
  // Patches whose free sectors can make them turn 4 take part (one graph vertex each); the
  // others keep their readings. A free sector turns 1 read as a corner, 0 as straight.
  std::vector<int> turning(patches, 0), free_sectors(patches, 0), free_corners(patches, 0);
  for (const SectorChoice& s : sectors) {
    if (s.patch < 0) continue;
    turning[s.patch] += 2 - s.quarters;
    free_sectors[s.patch] += s.free;
    free_corners[s.patch] += s.free && s.quarters == 1;
  }
  std::vector<int> vertex_of(patches, 0);
  int vertices = 0;
  bool imbalanced = false;
  for (int p = 0; p < patches; ++p) {
    const int fewest = turning[p] - free_corners[p], most = fewest + free_sectors[p];
    if (fewest <= 4 && 4 <= most) {
      vertex_of[p] = ++vertices;
      imbalanced |= turning[p] != 4;
    }
  }
  if (!imbalanced) return chosen;
  // A unit on arc node → patch re-reads one of the patch's straight sectors there as a
  // corner (the patch turns one more, the node has one quad fewer), on arc patch → node a
  // corner as straight. A patch must receive 4 − its turning; a node sends what it has
  // over its target, and what it cannot send to (or get from) patches goes to (comes from)
  // a sink at node_price a unit: an irregular vertex. Costs in thousandths of a quarter
  // turn (the algorithm wants integers).
  std::map<int, int> node_vertex;  // node → graph vertex
  for (const SectorChoice& s : sectors)
    if (s.free && s.patch >= 0 && vertex_of[s.patch] && !node_vertex.count(s.node))
      node_vertex[s.node] = 0;
  for (auto& [node, vertex] : node_vertex) vertex = ++vertices;
  const int sink = ++vertices;
  struct VertexData {
    double rhs;
  };
  struct ArcData {
    double low, cap, cost, x;
  };
  std::unique_ptr<glp_graph, GraphDeleter> graph(
      glp_create_graph(sizeof(VertexData), sizeof(ArcData)));
  glp_graph* g = graph.get();
  glp_add_vertices(g, vertices);
  auto rhs = [&](int vertex) -> double& {
    return static_cast<VertexData*>(g->v[vertex]->data)->rhs;
  };
  for (int v = 1; v <= vertices; ++v) rhs(v) = 0;
  auto add_arc = [&](int from, int to, double cap, double cost) {
    glp_arc* a = glp_add_arc(g, from, to);
    *static_cast<ArcData*>(a->data) = {0, cap, std::round(1000 * cost), 0};
    return a;
  };
  double supply = 0;  // what the patches and nodes send in all; the sink takes it
  for (int p = 0; p < patches; ++p)
    if (vertex_of[p]) supply += rhs(vertex_of[p]) = turning[p] - 4;  // < 0: needs turning
  std::map<int, int> node_sum;  // Σ quarters as read, nodes in the program
  for (const SectorChoice& s : sectors)
    if (node_vertex.count(s.node)) node_sum[s.node] += s.quarters;
  const double unbounded = 4.0 * static_cast<double>(sectors.size()) + 8;
  for (const auto& [node, vertex] : node_vertex) {
    const auto target = node_target.find(node);
    supply += rhs(vertex) = node_sum[node] - (target != node_target.end() ? target->second : 4);
    const auto own = node_prices.find(node);
    const double price = own != node_prices.end() ? own->second : node_price;
    add_arc(vertex, sink, unbounded, price);
    add_arc(sink, vertex, unbounded, price);
  }
  rhs(sink) = -supply;
  std::vector<glp_arc*> arc_of(sectors.size(), nullptr);
  for (size_t i = 0; i < sectors.size(); ++i) {
    const SectorChoice& s = sectors[i];
    if (!s.free || s.patch < 0 || !vertex_of[s.patch]) continue;
    const int patch = vertex_of[s.patch], node = node_vertex[s.node];
    const double cost =
        deviation(s.angle, 3 - s.quarters) - deviation(s.angle, s.quarters) + s.side_cost;
    arc_of[i] = s.quarters == 2 ? add_arc(node, patch, 1, cost) : add_arc(patch, node, 1, cost);
  }
  double total = 0;
  const int code = glp_mincost_okalg(g, offsetof(VertexData, rhs), offsetof(ArcData, low),
                                     offsetof(ArcData, cap), offsetof(ArcData, cost), &total,
                                     offsetof(ArcData, x), -1);
  if (code != 0) return chosen;
  for (size_t i = 0; i < sectors.size(); ++i)
    if (arc_of[i] && static_cast<ArcData*>(arc_of[i]->data)->x > 0.5)
      chosen[i] = 3 - sectors[i].quarters;
  return chosen;
}

namespace {

// How far a patch whose nodes read `quarters` is from a rectangle: Σ over its two pairs of
// opposite sides of 2 |difference| / sum of their targets (`after`: the target of the arc
// after each node), as best_corners weighs it; -1 if it does not turn 4.
double side_imbalance(const std::vector<int>& quarters, const std::vector<double>& after) {
  const int m = static_cast<int>(quarters.size());
  int first = 0, turning = 0;
  for (int q : quarters) turning += 2 - q;
  while (first < m && quarters[first] == 2) ++first;
  if (turning != 4 || first == m) return -1;
  double side[4] = {0, 0, 0, 0};
  for (int t = 0, k = -1; t < m; ++t) {
    const int i = (first + t) % m;
    k += quarters[i] < 2 ? 2 - quarters[i] : 0;
    side[k] += after[i];
  }
  double imbalance = 0;
  for (int k = 0; k < 2; ++k)
    imbalance += 2 * std::abs(side[k] - side[k + 2]) / std::max(side[k] + side[k + 2], 1e-9);
  return imbalance;
}

}  // namespace

// (quad/detail/layout.h)
int node_quarters(const Surface& s, const Layout& layout, int h_out, int valence) {
  if (layout.on_loop[s.from(h_out)]) return -1;
  // The curves' halfedges leaving the node, counter-clockwise from h_out.
  std::vector<int> spokes{h_out};
  for (int g = h_out, guard = 0;; ++guard) {
    int c = s.mesh.prev_halfedge_handle(s.mesh.halfedge_handle(g)).idx() ^ 1;
    for (int turn = 0; layout.edge_curve[c >> 1] < 0 && c != g && turn < 256; ++turn)
      c = s.mesh.prev_halfedge_handle(s.mesh.halfedge_handle(c)).idx() ^ 1;
    if (c == g || guard > 64) return -1;  // one curve only, or lost
    if (c == h_out) break;
    spokes.push_back(c);
    g = c;
  }
  // Read from the lowest halfedge on, so that every sector of the node is read from the
  // same grid whichever one is asked for.
  const int m = static_cast<int>(spokes.size());
  const int start = static_cast<int>(std::min_element(spokes.begin(), spokes.end()) - spokes.begin());
  std::vector<double> at{0};  // each curve's direction in quarter turns from the first's
  for (int t = 0; t < m; ++t) {
    const int g = spokes[(start + t) % m], next = spokes[(start + t + 1) % m];
    at.push_back(at.back() + sector_angle(s, layout, g, next ^ 1, valence) / (kPi / 2));
  }
  const double total = at.back();
  if (std::abs(total - std::round(total)) > 0.5 - 1e-9) return -1;
  // The offset that puts the directions closest to the grid (one of them on it).
  double offset = 0, best = 1e300;
  for (int j = 0; j < m; ++j) {
    const double o = std::round(at[j]) - at[j];
    double miss = 0;
    for (int k = 0; k < m; ++k) miss += std::abs(at[k] + o - std::round(at[k] + o));
    if (miss < best - 1e-12) best = miss, offset = o;
  }
  const int t = (m - start) % m;  // h_out's place from the first
  return static_cast<int>(std::lround(at[t + 1] + offset) - std::lround(at[t] + offset));
}

// (quad/detail/layout.h)
std::vector<int> best_corners(const std::vector<Corner>& nodes, const std::vector<double>& after,
                              double* best_cost) {
  const int m = static_cast<int>(nodes.size());
  int cusps = 0;
  for (const Corner& k : nodes) cusps += k.quarters == 0;
  const int wanted = 4 - 2 * cusps;
  std::vector<int> best;
  *best_cost = 1e300;
  if (wanted < 0 || m - cusps < wanted || m > 40) return best;
  std::vector<int> quarters(m, 2);
  for (int i = 0; i < m; ++i)
    if (nodes[i].quarters == 0) quarters[i] = 0;
  auto cost_of = [&]() {
    double cost = 0, side[4] = {0, 0, 0, 0};
    int first = 0;
    while (quarters[first] == 2) ++first;
    for (int t = 0, k = -1; t < m; ++t) {
      const int i = (first + t) % m;
      const double want = quarters[i] * kPi / 2;
      cost += std::abs(nodes[i].angle - want) / (kPi / 2);
      k += quarters[i] < 2 ? 2 - quarters[i] : 0;
      side[k] += after[i];
    }
    for (int k = 0; k < 2; ++k)
      cost += 2 * std::abs(side[k] - side[k + 2]) / std::max(side[k] + side[k + 2], 1e-9);
    return cost;
  };
  // Every choice of `left` more corners among the non-cusp nodes from index i on.
  std::function<void(int, int)> choose = [&](int i, int left) {
    if (left == 0) {
      const double cost = cost_of();
      if (cost < *best_cost) *best_cost = cost, best = quarters;
      return;
    }
    for (int j = i; j <= m - left; ++j)
      if (quarters[j] == 2) {
        quarters[j] = 1;
        choose(j + 1, left - 1);
        quarters[j] = 2;
      }
  };
  choose(0, wanted);
  return best;
}

// (quad/detail/layout.h)
int read_with_override(const std::map<int, int>& quarter_override, const Corner& k, bool stalled) {
  const auto o = quarter_override.find(k.halfedge_out);
  return o != quarter_override.end() && !(stalled && k.read == 4) ? o->second : k.read;
}

// (quad/detail/layout.h)
bool passes_a_vertex_twice(const Surface& s, const std::vector<Cycle>& cycles) {
  if (cycles.size() != 1) return false;
  std::vector<int> cv;
  for (int h : cycles[0].halfedges) cv.push_back(s.from(h));
  std::sort(cv.begin(), cv.end());
  return std::adjacent_find(cv.begin(), cv.end()) != cv.end();
}

// (quad/detail/layout.h)
int read_corners_together(const Surface& s, const Layout& layout, const QuadOptions& options,
                          const std::map<int, int>& singular_valence, const PatchLayout& out,
                          const std::vector<Examined*>& patches, bool stalled,
                          std::map<int, int>& quarter_override) {
  std::vector<SectorChoice> sectors;
  std::vector<int> sector_halfedge;
  std::map<int, int> node_sum;  // Σ quarters as read, per node
  const int n = static_cast<int>(patches.size());
  for (int p = 0; p < n; ++p) {
    Examined& patch = *patches[p];
    bool disk =
        patch.cycles.size() == 1 && patch.chi == 1 && !passes_a_vertex_twice(s, patch.cycles);
    int turning = 0;
    for (Cycle& c : patch.cycles)
      for (Corner& k : c.nodes) {
        k.quarters = read_with_override(quarter_override, k, stalled);
        disk &= k.quarters <= 2;
        turning += 2 - k.quarters;
      }
    const size_t first = sectors.size();
    std::vector<int> quarters;
    std::vector<double> after;  // target of the arc after each node
    for (const Cycle& c : patch.cycles)
      for (const Corner& k : c.nodes) {
        SectorChoice sector;
        sector.patch = disk ? p : -1;
        sector.node = s.from(k.halfedge_out);
        sector.angle = k.angle;
        sector.quarters = k.quarters;
        sector.free = k.quarters == 1 || k.quarters == 2;
        sectors.push_back(sector);
        sector_halfedge.push_back(k.halfedge_out);
        node_sum[sector.node] += k.quarters;
        quarters.push_back(k.quarters);
        after.push_back(out.arcs[out.halfedge_arc[k.halfedge_out] / 2].target);
      }
    // A patch one corner off: what re-reading each sector alone does to its sides (the flow
    // cannot weigh a rectangle's sides, which best_corners does: without this the joint
    // reading leaves many quads oversized).
    if (!disk || std::abs(turning - 4) != 1) continue;
    for (size_t i = 0; i < quarters.size(); ++i) {
      if (!sectors[first + i].free) continue;
      std::vector<int> changed = quarters;
      changed[i] = 3 - changed[i];
      sectors[first + i].side_cost =
          kCornerSideWeight * std::max(0.0, side_imbalance(changed, after));
    }
  }
  // What a node's sectors should add up to: a traced singularity's valence, 4 inside, and
  // on a loop what they read (the boundary's own turn there).
  std::map<int, int> target;
  for (const auto& [v, sum] : node_sum) {
    const auto singular = singular_valence.find(v);
    target[v] = layout.on_loop[v] ? sum : singular != singular_valence.end() ? singular->second : 4;
  }
  // Nodes near where an earlier cage of this layout had irregular vertices away from
  // singularities (Layout::costly_nodes).
  std::map<int, double> prices;
  for (const auto& [v, sum] : node_sum)
    if (layout.costly(s.point[v])) prices[v] = options.off_node_price;
  const std::vector<int> chosen =
      choose_corners(sectors, n, target, kCornerNodePrice, prices);
  int reread = 0;
  for (size_t i = 0; i < sectors.size(); ++i)
    if (chosen[i] != sectors[i].quarters) {
      quarter_override[sector_halfedge[i]] = chosen[i];
      ++reread;
    }
  return reread;
}

}  // namespace genbrep::quad_detail
