// quad/corners.cpp — corner readings chosen for all patches at once (quad/quad.h step 1,
// QuadOptions::global_corners).
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
// whose matrix is totally unimodular. A sector may carry a side cost too (layout.cpp: how
// far from a rectangle its patch would be, which a flow cannot weigh itself). (That LP through GLPK's simplex took 0.14–0.73 s a
// round on the 6 x 6 net; the flow about 0.05 s.)
// Complexity: one min-cost flow on (patches + nodes) vertices and (sectors + 2 nodes) arcs.
#include <glpk.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <memory>

#include "quad/detail/layout.h"

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
                                const std::map<int, int>& node_target, double node_price) {
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
    add_arc(vertex, sink, unbounded, node_price);
    add_arc(sink, vertex, unbounded, node_price);
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

}  // namespace genbrep::quad_detail
