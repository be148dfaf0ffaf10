// quad/quantize.cpp — exact quantization of the patch layout (quad/quad.h step 2): the
// integer count of cage edges on every arc, so that the two pairs of opposite sides of
// every patch have equal sums (the integer-grid condition of §6 for a patch layout).
// Formulation (min-cost flow, as suggested in issue 5): each patch gives two conservation
// constraints, one per pair of opposite sides ("u" and "v"); an arc lies on at most two
// patch sides, so every arc is one edge of a network whose nodes are the (patch, pair)
// constraints, plus one free "ground" node for the boundary loops' side (arcs on a loop
// have one constraint only). Signs are made consistent by 2-colouring the constraints
// (flipping a constraint's sign); then Σ(side a) − Σ(side b) = 0 is flow conservation.
// Costs are convex in the count: (n − t)² / t with t = length / target size, so successive
// shortest paths on unit increments from the separable optimum round(t) give the exact
// integer optimum with n ≥ 1 (no rounding heuristics, no oscillation).
// Complexity: O(imbalance · nodes · arcs) (Bellman–Ford per unit), small in practice.
#include <algorithm>
#include <cmath>
#include <deque>
#include <string>

#include "quad/detail/layout.h"

namespace genbrep::quad_detail {

namespace {

// One exact solve with per-arc lower bounds (0 or 1).
bool solve(PatchLayout& layout, const QuadOptions& options, const std::vector<int>& lower,
           int* fixed_arcs, std::string* failure) {
  const int arcs = static_cast<int>(layout.arcs.size());
  const int nodes = 2 * static_cast<int>(layout.patches.size());
  // Incidences per arc: (node, sign) with sign +1 on sides 0/1, −1 on sides 2/3; an arc on
  // both opposite sides of one patch cancels there (its count is free in that patch).
  std::vector<std::vector<std::pair<int, int>>> incidence(arcs);
  for (size_t p = 0; p < layout.patches.size(); ++p)
    for (int side = 0; side < 4; ++side)
      for (auto& [a, reversed] : layout.patches[p].sides[side]) {
        const int node = 2 * static_cast<int>(p) + side % 2, sign = side < 2 ? 1 : -1;
        auto& list = incidence[a];
        auto same = std::find_if(list.begin(), list.end(), [&](auto& x) { return x.first == node; });
        if (same == list.end()) list.emplace_back(node, sign);
        else if (same->second == -sign) list.erase(same);
        else same->second += sign;  // ±2: not a network edge, rejected below
      }
  for (int a = 0; a < arcs; ++a)
    for (auto& [node, sign] : incidence[a])
      if (std::abs(sign) != 1 || incidence[a].size() > 2) {
        *failure = "arc " + std::to_string(a) + " appears twice on one side of a patch";
        return false;
      }
  // 2-colouring: flip[N] · sign must be opposite at the two ends of every arc.
  std::vector<std::vector<std::pair<int, int>>> adjacent(nodes);  // (other node, parity)
  for (int a = 0; a < arcs; ++a)
    if (incidence[a].size() == 2) {
      const auto [n0, s0] = incidence[a][0];
      const auto [n1, s1] = incidence[a][1];
      adjacent[n0].emplace_back(n1, -s0 * s1);
      adjacent[n1].emplace_back(n0, -s0 * s1);
    }
  // Around singularities a T-mesh can have cycles of odd twist (Lyon et al. 2021: T-mesh
  // quantization is not a network problem in general). Arcs closing such a cycle end with
  // the same sign at both constraints ("bidirected"); they get a fixed count below and the
  // network balances the rest.
  std::vector<int> flip(nodes, 0);
  for (int root = 0; root < nodes; ++root) {
    if (flip[root]) continue;
    flip[root] = 1;
    std::deque<int> queue{root};
    while (!queue.empty()) {
      const int n = queue.front();
      queue.pop_front();
      for (auto [m, parity] : adjacent[n])
        if (!flip[m]) flip[m] = flip[n] * parity, queue.push_back(m);
    }
  }
  // Network: arc a runs tail → head (head: effective sign +1). Ground = node `nodes`.
  const int ground = nodes;
  std::vector<int> tail(arcs, -1), head(arcs, -1);
  std::vector<double> target(arcs);
  std::vector<int> count(arcs);
  std::vector<int> bidirected;  // arcs with the same effective sign at both ends
  bool has_ground = false;
  for (int a = 0; a < arcs; ++a) {
    target[a] = std::max(layout.arcs[a].target * options.density, 1e-3);
    count[a] = std::max(lower[a], static_cast<int>(std::lround(target[a])));
    tail[a] = head[a] = ground;
    int sum = 0;
    for (auto [node, sign] : incidence[a]) {
      (sign * flip[node] > 0 ? head[a] : tail[a]) = node;
      sum += sign * flip[node];
    }
    if (std::abs(sum) == 2) bidirected.push_back(a), tail[a] = head[a] = -1;
    has_ground |= incidence[a].size() == 1;
  }
  *fixed_arcs = static_cast<int>(bidirected.size());
  // Without a boundary the fixed arcs must balance among themselves: Σ(++) = Σ(−−).
  if (!has_ground && !bidirected.empty()) {
    auto eff = [&](int a) { return incidence[a][0].second * flip[incidence[a][0].first]; };
    for (int guard = 0; guard < 100000; ++guard) {
      int balance = 0;
      for (int a : bidirected) balance += eff(a) * count[a];
      if (!balance) break;
      int pick = -1, delta = 0;
      double best = 1e300;
      for (int a : bidirected)
        for (int d : {1, -1}) {
          if (eff(a) * d * balance >= 0 || count[a] + d < lower[a]) continue;
          const double now = count[a] - target[a], cost = ((now + d) * (now + d) - now * now) / target[a];
          if (cost < best) best = cost, pick = a, delta = d;
        }
      if (pick < 0) {
        *failure = "the twisted side constraints of a closed layout cannot balance";
        return false;
      }
      count[pick] += delta;
    }
  }
  auto marginal = [&](int a, int delta) {  // cost of count[a] += delta (delta = ±1)
    const double now = count[a] - target[a], next = now + delta;
    return (next * next - now * now) / std::max(target[a], 1.0);
  };
  // Successive shortest paths, one unit at a time: from a node with positive excess (or the
  // ground) to a node with negative excess (or the ground). Residual moves of arc a: +1
  // (tail → head) always, −1 (head → tail) while count > 1. Returns the excess left.
  std::vector<double> dist(nodes + 1);
  std::vector<int> via(nodes + 1);  // arc · 2 + (0: increase, 1: decrease), −1 = source
  auto settle = [&](std::vector<int>& count) {
    std::vector<int> excess(nodes + 1, 0);  // inflow − outflow; the ground's is ignored
    for (int a = 0; a < arcs; ++a)
      if (tail[a] != head[a] && tail[a] >= 0) excess[head[a]] += count[a], excess[tail[a]] -= count[a];
    for (int a : bidirected)
      for (auto [node, sign] : incidence[a]) excess[node] += sign * flip[node] * count[a];
    for (bool from_positive = true;;) {
      bool positive = false, negative = false;
      for (int n = 0; n < nodes; ++n) positive |= excess[n] > 0, negative |= excess[n] < 0;
      if (!positive && !negative) return 0;
      from_positive = from_positive && positive;
      std::fill(dist.begin(), dist.end(), 1e300);
      std::fill(via.begin(), via.end(), -2);
      for (int n = 0; n < nodes; ++n)
        if (from_positive && excess[n] > 0) dist[n] = 0, via[n] = -1;
      if (!from_positive) dist[ground] = 0, via[ground] = -1;
      for (int pass = 0, changed = 1; changed && pass <= nodes + 1; ++pass) {
        changed = 0;
        for (int a = 0; a < arcs; ++a) {
          if (tail[a] == head[a] || tail[a] < 0) continue;
          if (dist[tail[a]] < 1e299 && dist[tail[a]] + marginal(a, 1) < dist[head[a]] - 1e-12)
            dist[head[a]] = dist[tail[a]] + marginal(a, 1), via[head[a]] = 2 * a, changed = 1;
          if (count[a] > lower[a] && dist[head[a]] < 1e299 &&
              dist[head[a]] + marginal(a, -1) < dist[tail[a]] - 1e-12)
            dist[tail[a]] = dist[head[a]] + marginal(a, -1), via[tail[a]] = 2 * a + 1, changed = 1;
        }
      }
      int sink = -1;
      for (int n = 0; n <= nodes; ++n) {
        const bool wanted = n == ground ? from_positive : excess[n] < 0;
        if (wanted && via[n] != -1 && dist[n] < 1e299 && (sink < 0 || dist[n] < dist[sink])) sink = n;
      }
      if (sink < 0) {
        if (from_positive && negative) { from_positive = false; continue; }
        int left = 0;
        for (int n = 0; n < nodes; ++n) left += std::abs(excess[n]);
        return left;
      }
      if (sink != ground) ++excess[sink];
      for (int n = sink, guard = 0; via[n] != -1 && guard <= nodes + 1; ++guard) {
        const int a = via[n] / 2;
        const bool increase = via[n] % 2 == 0;
        count[a] += increase ? 1 : -1;
        n = increase ? tail[a] : head[a];
        if (via[n] == -1 && n != ground) --excess[n];
      }
    }
  };
  // The fixed (bidirected) arcs: if the network cannot balance them, move them one unit at
  // a time, greedily by the excess left (a small local search; reported as fixed arcs).
  std::vector<int> best = count;
  int left = settle(best);
  for (int round = 0; left && round < 4 * static_cast<int>(bidirected.size()) + 4; ++round) {
    std::vector<int> pick;
    int pick_left = left;
    auto consider = [&](std::vector<int> trial) {
      std::vector<int> settled = trial;
      const int l = settle(settled);
      if (l < pick_left) pick_left = l, pick = std::move(trial), best = std::move(settled);
    };
    // Single moves of ±1, ±2 and paired ±1 moves of two fixed arcs.
    const int b = static_cast<int>(bidirected.size());
    for (int i = 0; i < b; ++i)
      for (int d : {1, -1, 2, -2}) {
        const int a = bidirected[i];
        if (count[a] + d < lower[a]) continue;
        std::vector<int> trial = count;
        trial[a] += d;
        consider(trial);
        if (std::abs(d) == 2) continue;
        for (int j = i + 1; j < b; ++j)
          for (int e : {1, -1}) {
            const int c = bidirected[j];
            if (count[c] + e < lower[c]) continue;
            std::vector<int> pair = trial;
            pair[c] += e;
            consider(pair);
          }
      }
    if (pick.empty()) break;
    count = pick, left = pick_left;
  }
  if (left) {
    *failure = "no integer counts ≥ 1 make opposite sides equal (" + std::to_string(left) +
               " units of imbalance left; " + std::to_string(bidirected.size()) + " twisted arcs)";
    return false;
  }
  count = best;
  for (int a = 0; a < arcs; ++a) layout.arcs[a].count = count[a];
  return true;
}

}  // namespace

// Interior arcs shorter than one target edge (sliver arcs between nearby T-junctions and
// nodes) may get 0 edges: their end nodes then merge in the cage (zero-length arcs as in
// Campen et al. 2015, QGP), and a patch whose two opposite sides both get 0 collapses onto
// its other pair (fill.cpp glues them). Loop arcs keep ≥ 1 so every chain stays on its
// loop: a collapsing patch that touches a loop gets a lower bound of 1 on the longest arc
// of its vanishing side, and the solve is repeated.
bool quantize(PatchLayout& layout, const QuadOptions& options, int* fixed_arcs,
              std::string* failure) {
  const int arcs = static_cast<int>(layout.arcs.size());
  std::vector<int> sides_of(arcs, 0);
  for (const Patch& patch : layout.patches)
    for (const auto& side : patch.sides)
      for (auto& [a, reversed] : side) ++sides_of[a];
  std::vector<int> lower(arcs, 1);
  for (int a = 0; a < arcs; ++a)
    if (sides_of[a] == 2 && layout.arcs[a].target * options.density < 1.0) lower[a] = 0;
  for (int round = 0; round <= 4 * arcs; ++round) {
    if (!solve(layout, options, lower, fixed_arcs, failure)) return false;
    bool vanished = false;
    for (const Patch& patch : layout.patches) {
      bool on_loop = false;
      for (const auto& side : patch.sides)
        for (auto& [a, reversed] : side) on_loop |= sides_of[a] == 1;
      for (const auto& side : patch.sides) {
        int sum = 0, longest = -1;
        for (auto& [a, reversed] : side) {
          sum += layout.arcs[a].count;
          if (longest < 0 || layout.arcs[a].target > layout.arcs[longest].target) longest = a;
        }
        if (on_loop && sum == 0 && longest >= 0 && !lower[longest])
          lower[longest] = 1, vanished = true;
      }
    }
    if (!vanished) return true;
  }
  *failure = "patch sides kept vanishing";
  return false;
}

}  // namespace genbrep::quad_detail
