// quad/place.cpp — irregular vertices the layout left beside the field's singularities are
// edited onto them, or away (quad/quad.h step 4, after the pair cancelling of
// untangle.cpp). Around each irregular vertex no singularity explains
// (irregular_off_singularities' matching), and each chain vertex of three quads where its
// loop is smooth (PlaceSettings::chain_vertices: no singularity explains one), every
// sequence of at most two edits — an edge rotation, a diagonal collapse, a vertex split —
// in a window of a few rings is tried on the window's connectivity alone (the first edit
// changing an irregular vertex, the second one of the vertices the first changed; chain
// vertices keep their place and never gain a quad, but one of three quads where the region
// is straight may lose one, and is counted as irregular: shedding_chain_vertices), and
// where none helps every sequence of three whose first two leave at most `climb` more
// unexplained (PlaceSettings::climb), and then (up to max_edits) one edit more at a time
// after the kDeepPrefixes best sequences so far that leave no more unexplained, and as
// many of those that leave more, up to `climb` more (a 6 and a 3 beside a −1 singularity
// can need four; a 6 or a 5 whose partner is three edges away needs to pass through one
// more: an edit moves an irregular vertex only by leaving a 3–5 pair behind; where a round
// makes no edit, every window is searched again climbing by one more, up to
// PlaceSettings::climb_last); of those leaving fewer unexplained vertices, the best few
// (fewest unexplained, then fewest irregular) are evened out in turn around their changed
// vertices, and the first whose quads come out neither squeezed nor turned over is made. A
// window counts, beside its own vertices, the cage's irregular vertices beyond it that its
// singularities can explain (rivals_of), as the cage's count does.
// Such defects are a −1 singularity drawn as a 6 and a 3, or a 5 with a 3–5 pair beside it
// (a dislocation: the singular vertex one edge off); one edit rarely mends them, two often
// do, three more. A 3 and a 5 the layout left a
// few edges apart, away from any singularity (rows shifting by one where a sliver or cusp
// collapsed), need more edits than that: sequences leaving as many unexplained and no more
// irregular vertices that draw them nearer each other are ranked too, after those leaving
// fewer (draw_pairs_together), and later rounds cancel them once they meet. The caller
// opens squeezed quads and evens the whole cage out.
// Complexity: per unexplained vertex (and chain vertex that may shed a quad), (edits in the
// window)² window-sized steps, ³ where two edits do not help (pruned: the second must not
// add more than `climb` unexplained vertices), and 2 × kDeepPrefixes × (edits in the
// window) more per edit beyond three; windows searched in vain are not searched again
// until an edit touches them (or the climb is raised), nor windows whose count finds none
// unexplained; rivals: O(irregular) per window, their pairs sorted once and merged into
// each step's rather than sorted at each step.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include "quad/detail/edit.h"
#include "quad/detail/place_edits.h"

namespace genbrep::quad_detail {

namespace {

using namespace place;  // State, for_each_edit, kScoreRings (detail/place_edits.h)

constexpr int kCoreRings = 1;    // first edits: quads at vertices this close to the vertex
// The window: quads at vertices this close; one ring more than kScoreRings, so that every
// edit's quads lie in it.
constexpr int kWindowRings = 6;
// An edit whose quads come out with a corner under this (or turned over) is not made.
constexpr double kMinPlacedCorner = 5.0;
// Improving sequences kept per window, tried best first until one settles.
constexpr size_t kKeptSequences = 6;
// A chain vertex whose quads' corners sum to less than this (radians) may lose a quad.
constexpr double kShedAngle = 225.0 * M_PI / 180.0;
// Sequences of three edits or more taken on by one more where none helps (the best by
// Score among those leaving no more unexplained vertices, and as many among those leaving
// up to PlaceSettings::climb more; PlaceSettings::max_edits).
constexpr size_t kDeepPrefixes = 64;
// Drawing pairs together (PlaceSettings::draw_pairs_together): a sequence leaving as many
// unexplained vertices is made if it brings them, summed, at least kPairCloser reaches
// nearer to one of opposite sign, each counted up to kPairSpreadCap reaches away.
constexpr double kPairSpreadCap = 3.0;
constexpr double kPairCloser = 0.25;

// Unexplained vertices, then irregular ones, among the scored vertices (`scored`: the
// window's vertices within kScoreRings that are not on a chain or may shed a quad;
// vertices added since are too; a chain vertex is regular with two quads and carries
// 2 − quads),
// then with `spread` how far the unexplained ones are from one of opposite sign (in reaches,
// each up to kPairSpreadCap, summed; 0 without).
// `explains`: per window vertex, the singularities near enough to explain it where it was,
// at `start_point` (a vertex an edit moved is looked up again). `rivals` take part in the
// matching and both counts as they stand, not in `spread`.
using Score = std::tuple<int, int, double>;
// Irregular vertices outside what a window scores that compete for its singularities
// (rivals_of), with the singularities that can explain each (indices into the window's).
struct Rivals {
  std::vector<Irregular> vertices;
  // Every rival's pairs (entry: the rival's index) in the matching's order (pair_order):
  // they are the same in every state of the window, and merged with its own.
  std::vector<Explaining> pairs;
};
Score score(const State& s, const std::vector<SingularPoint>& singular,
            const std::vector<int>& scored, size_t window_vertices,
            const std::vector<std::vector<Explaining>>& explains,
            const std::vector<Vec3>& start_point, const Rivals& rivals, bool spread) {
  thread_local std::vector<Irregular> irregular;
  thread_local std::vector<Explaining> own_pairs, pairs;
  thread_local std::vector<int> left;
  irregular.clear(), own_pairs.clear(), pairs.clear();
  auto add = [&](int v) {
    // A chain vertex that may shed a quad is regular with two.
    const int regular = s.shed[v] ? 2 : 4;
    if (s.valence[v] == 0 || s.valence[v] == regular) return;
    const int entry = static_cast<int>(irregular.size());
    irregular.push_back({v, regular - s.valence[v], s.point[v], s.reach[v]});
    if (static_cast<size_t>(v) < window_vertices && s.point[v] == start_point[v]) {
      for (const Explaining& x : explains[v])
        if (singular[x.point].index * irregular.back().carries > 0)
          own_pairs.push_back({x.distance, entry, x.point});
    } else {
      explaining_pairs(irregular.back(), entry, singular, &own_pairs);
    }
  };
  for (int v : scored) add(v);
  for (size_t v = window_vertices; v < s.valence.size(); ++v) add(static_cast<int>(v));
  const size_t own = irregular.size();
  // The window's own pairs sorted, merged with the rivals' (after them in `left`): the
  // order match_pairs would sort them all into.
  auto vertex_of = [&](int entry) { return irregular[entry].vertex; };
  auto own_order = [&](const Explaining& x) { return pair_order(x, vertex_of(x.entry)); };
  sort_pairs(own_pairs, vertex_of);
  auto o = own_pairs.begin();
  for (const Explaining& x : rivals.pairs) {
    const auto rival_order = pair_order(x, rivals.vertices[x.entry].vertex);
    for (; o != own_pairs.end() && own_order(*o) < rival_order; ++o) pairs.push_back(*o);
    pairs.push_back(x);
    pairs.back().entry += static_cast<int>(own);
  }
  pairs.insert(pairs.end(), o, own_pairs.end());
  left.resize(own + rivals.vertices.size());
  for (size_t e = 0; e < own; ++e) left[e] = irregular[e].carries;
  for (size_t r = 0; r < rivals.vertices.size(); ++r) left[own + r] = rivals.vertices[r].carries;
  match_sorted_pairs(pairs, singular, &left);
  double apart = 0;
  for (size_t i = 0; spread && i < own; ++i) {
    if (!left[i]) continue;
    double nearest = kPairSpreadCap;
    for (size_t j = 0; j < own; ++j)
      if (left[j] * left[i] < 0)
        nearest = std::min(nearest, (irregular[i].point - irregular[j].point).norm() /
                                        std::max(irregular[i].reach, 1e-12));
    apart += nearest;
  }
  return {static_cast<int>(std::count_if(left.begin(), left.end(), [](int q) { return q != 0; })),
          static_cast<int>(left.size()), apart};
}

// Per cage vertex: a chain vertex, on no crease edge, of three quads or more where the
// region's angle (the quads' corners at it, summed) is under kShedAngle, so that two quads
// would cover it (a smooth stretch of the loop, not a concave corner). An edit may take a
// quad from it (for_each_edit): an interior 3 beside it, with nothing else irregular near,
// leaves their quarter turns adding up to +1 inside, which no edit of interior vertices
// alone places. The search counts it as irregular (carrying −1 with three quads): a
// sequence that sheds its quad and glides the 3–5 pair this leaves a few rows in, until
// it meets a singular vertex, passes through as many unexplained vertices as it started
// with; counting interior vertices alone, it passes through one more and is cut off. With
// PlaceSettings::chain_vertices none explains it and it starts a window of its own: a −1
// singularity a row or two in, drawn on the loop, goes inside onto it.
std::vector<char> shedding_chain_vertices(const QuadCage& cage, const CageIncidence& incidence) {
  std::vector<char> crease(cage.vertices.rows(), 0);
  for (const auto& e : cage.crease_edges) crease[e[0]] = crease[e[1]] = 1;
  std::vector<char> shed(cage.vertices.rows(), 0);
  for (size_t v = 0; v < shed.size(); ++v) {
    if (!incidence.on_chain[v] || crease[v] || incidence.quads_of[v].size() < 3) continue;
    auto point = [&](int w) -> Vec3 { return cage.vertices.row(w).transpose(); };
    double angle = 0;
    for (int q : incidence.quads_of[v])
      for (int k = 0; k < 4; ++k)
        if (cage.quads(q, k) == static_cast<int>(v))
          angle += corner_angle(point(v), point(cage.quads(q, (k + 1) % 4)),
                                point(cage.quads(q, (k + 3) % 4)));
    shed[v] = angle < kShedAngle;
  }
  return shed;
}

// The cage's irregular vertices a window does not score (`scored_vertex` false: outside it,
// or beyond kScoreRings, where no edit reaches) that one of the window's singularities
// `near` (within `extent` of `centre`) can explain, with the singularities that can explain
// them, which are appended to `near` where missing (`near_id`: per singularity, its index
// in `near` or −1). The cage's matching gives each singularity to the nearest vertex first,
// wherever it is; a window that leaves these out finds its vertex explained by a
// singularity a nearer vertex a strut or a few rings away takes (a vertex of long edges
// beside a junction's cluster of −1 singularities), and does not search.
template <class Scored>
Rivals rivals_of(const std::vector<Irregular>& irregular,
                 const std::vector<SingularPoint>& singular, const Vec3& centre, double extent,
                 Scored scored_vertex, std::vector<SingularPoint>* near,
                 std::vector<int>* near_id) {
  Rivals rivals;
  for (size_t f = 0; f < irregular.size(); ++f) {
    const Irregular& x = irregular[f];
    if (scored_vertex(x.vertex) || (x.point - centre).norm() > extent + x.reach) continue;
    std::vector<Explaining> pairs;
    explaining_pairs(x, -1, singular, &pairs);
    if (std::none_of(pairs.begin(), pairs.end(),
                     [&](const Explaining& p) { return (*near_id)[p.point] >= 0; }))
      continue;
    for (Explaining& p : pairs) {
      int& id = (*near_id)[p.point];
      if (id < 0) id = static_cast<int>(near->size()), near->push_back(singular[p.point]);
      p.point = id;
      p.entry = static_cast<int>(rivals.vertices.size());
    }
    // Ids apart from the window's local ones (ties between equal distances go by id).
    rivals.vertices.push_back({-1 - static_cast<int>(f), x.carries, x.point, x.reach});
    rivals.pairs.insert(rivals.pairs.end(), pairs.begin(), pairs.end());
  }
  sort_pairs(rivals.pairs, [&](int entry) { return rivals.vertices[entry].vertex; });
  return rivals;
}

// Puts `s` into `best` (sorted by score, best first) if it is among the `limit` best.
void keep_best(std::vector<std::pair<Score, State>>& best, const Score& now, const State& s,
               size_t limit) {
  if (best.size() == limit && !(now < best.back().first)) return;
  const auto at = std::upper_bound(best.begin(), best.end(), now,
                                   [](const auto& x, const auto& y) { return x < y.first; });
  best.insert(at, {now, s});
  if (best.size() > limit) best.pop_back();
}

// Evens out the changed vertices of `s`, their neighbours and `rings` rings more (free
// vertices within kScoreRings; `sweeps` sweeps: each to the mean of its neighbours, onto
// the component) and tells whether the quads around them are then neither squeezed (a
// corner under kMinPlacedCorner) nor turned over. `moved`: the vertices whose points
// changed.
bool settle(const CageChecks& checks, State& s, int rings, int sweeps, std::vector<int>* moved) {
  std::vector<std::vector<int>> neighbours(s.valence.size());
  for (const auto& c : s.quads)
    if (c[0] >= 0)
      for (int k = 0; k < 4; ++k)
        neighbours[c[k]].push_back(c[(k + 1) % 4]), neighbours[c[(k + 1) % 4]].push_back(c[k]);
  std::vector<char> moving(s.valence.size(), 0);
  moved->clear();
  for (int v : s.changed) {
    if (s.valence[v] == 0) continue;
    for (int w : neighbours[v]) moving[w] |= !s.fixed[w] && s.ring[w] <= kScoreRings;
    moving[v] |= !s.fixed[v];  // a chain vertex that shed a quad keeps its place
  }
  for (int r = 0; r < rings; ++r) {
    std::vector<char> wider = moving;
    for (size_t v = 0; v < moving.size(); ++v)
      if (moving[v])
        for (int w : neighbours[v]) wider[w] |= !s.fixed[w] && s.ring[w] <= kScoreRings;
    moving = std::move(wider);
  }
  for (size_t v = 0; v < moving.size(); ++v)
    if (moving[v]) moved->push_back(static_cast<int>(v));
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (int v : *moved) {
      Vec3 mean = Vec3::Zero();
      for (int w : neighbours[v]) mean += s.point[w];
      mean /= static_cast<double>(neighbours[v].size());
      Vec3 normal;
      s.point[v] = checks.locator.closest(mean, &normal);
    }
  for (const auto& c : s.quads) {
    if (c[0] < 0 || !(moving[c[0]] || moving[c[1]] || moving[c[2]] || moving[c[3]])) continue;
    const Vec3 corner[4] = {s.point[c[0]], s.point[c[1]], s.point[c[2]], s.point[c[3]]};
    if (corners_bad(checks.locator, checks.normals, corner, kMinPlacedCorner)) return false;
  }
  return true;
}

// The sequences of edits tried around one window of place_irregulars (their comments there),
// the kKeptSequences best that leave fewer unexplained vertices than `before` (or as many,
// drawn nearer), best first. `score_now` scores `s` as it stands.
template <class ScoreNow>
std::vector<std::pair<Score, State>> search_sequences(State& s, ScoreNow score_now,
                                                      const Score& before, size_t window_vertices,
                                                      int max_edits, int climb) {
  std::vector<std::pair<Score, State>> kept;
  auto keep = [&](const Score& now) {
    const auto [off, irregular_now, apart] = now;
    const auto [off_before, irregular_before, apart_before] = before;
    if (off > off_before ||
        (off == off_before &&
         !(irregular_now <= irregular_before && apart < apart_before - kPairCloser)))
      return;
    keep_best(kept, now, s, kKeptSequences);
  };
  std::vector<char> focus(s.valence.size(), 0);
  for (size_t l = 0; l < focus.size(); ++l) focus[l] = s.ring[l] <= kCoreRings;
  const std::vector<int> start = s.valence;  // the window's valences before any edit
  // Sequences of one or two edits; where none leaves fewer unexplained, of three whose
  // first two leave at most `climb` more than before (each edit after the first at the
  // vertices the edits so far changed).
  auto first_edit = [&](auto&& then) {
    for_each_edit(s, focus, [&] {
      // The first edit changes an irregular vertex.
      if (std::none_of(s.changed.begin(), s.changed.end(), [&](int v) {
            return static_cast<size_t>(v) < window_vertices && start[v] != 4;
          }))
        return;
      then();
    });
  };
  auto next_edit = [&](auto&& then) {
    std::vector<char> at_last(s.valence.size(), 0);
    for (int v : s.changed) at_last[v] = 1;
    for_each_edit(s, at_last, then);
  };
  first_edit([&] {
    keep(score_now());
    next_edit([&] { keep(score_now()); });
  });
  // Sequences that only draw a pair together do not spare the three-edit search: it finds
  // sequences that leave fewer.
  auto fewer = [&] {
    return std::any_of(kept.begin(), kept.end(), [&](const auto& k) {
      return std::get<0>(k.first) < std::get<0>(before);
    });
  };
  // A sequence of three edits or more is kept if it helps, and it is among the
  // kDeepPrefixes best to take on by one more edit (where max_edits allows) if it
  // leaves no more unexplained than before; or among the kDeepPrefixes best of those
  // climbing (up to `climb` more), so that they are not crowded out by the level ones,
  // which rank before them.
  auto keep_prefix = [&](std::vector<std::pair<Score, State>>& prefixes,
                         std::vector<std::pair<Score, State>>& climbing) {
    const Score now = score_now();
    keep(now);
    if (max_edits > 3 && std::get<0>(now) <= std::get<0>(before))
      keep_best(prefixes, now, s, kDeepPrefixes);
    else if (max_edits > 3 && std::get<0>(now) <= std::get<0>(before) + climb)
      keep_best(climbing, now, s, kDeepPrefixes);
  };
  std::vector<std::pair<Score, State>> prefixes, climbing;
  if (max_edits >= 3 && !fewer())
    first_edit([&] {
      next_edit([&] {
        if (std::get<0>(score_now()) <= std::get<0>(before) + climb)
          next_edit([&] { keep_prefix(prefixes, climbing); });
      });
    });
  // Where those do not help either, one edit more at a time after each of the
  // prefixes, up to max_edits.
  for (int edits = 4;
       edits <= max_edits && !fewer() && (!prefixes.empty() || !climbing.empty()); ++edits) {
    std::vector<std::pair<Score, State>> longer, longer_climbing;
    for (auto* pool : {&prefixes, &climbing})
      for (auto& prefix : *pool) {
        std::swap(s, prefix.second);
        next_edit([&] { keep_prefix(longer, longer_climbing); });
        std::swap(s, prefix.second);
      }
    prefixes = std::move(longer);
    climbing = std::move(longer_climbing);
  }
  return kept;
}

// The cage as a round of place_irregulars edited it (`points`, `quads`: removed quads have
// corner -1), with removed quads and vertices no quad or chain uses dropped. Returns, per
// vertex of the new cage, whether its window was searched in vain and no edit touched it.
std::vector<char> compact(QuadCage& cage, const std::vector<Vec3>& points,
                          const std::vector<std::array<int, 4>>& quads,
                          const std::vector<std::pair<int, std::vector<int>>>& searched,
                          const std::vector<char>& locked) {
  std::vector<int> used(points.size(), 0);
  for (const auto& c : quads)
    if (c[0] >= 0) for (int v : c) used[v] = 1;
  for (const auto& chain : cage.boundary_chains)
    for (int v : chain) used[v] = 1;
  std::vector<int> id(points.size(), -1);
  int kept = 0;
  for (size_t v = 0; v < points.size(); ++v)
    if (used[v]) id[v] = kept++;
  Vertices vertices(kept, 3);
  for (size_t v = 0; v < points.size(); ++v)
    if (id[v] >= 0) vertices.row(id[v]) = points[v].transpose();
  const long live = std::count_if(quads.begin(), quads.end(), [](const auto& c) { return c[0] >= 0; });
  Quads out(live, 4);
  for (long q = 0, r = 0; q < static_cast<long>(quads.size()); ++q) {
    if (quads[q][0] < 0) continue;
    for (int k = 0; k < 4; ++k) out(r, k) = id[quads[q][k]];
    ++r;
  }
  for (auto& chain : cage.boundary_chains)
    for (int& v : chain) v = id[v];
  for (auto& e : cage.crease_edges) e = {id[e[0]], id[e[1]]};
  cage.vertices = std::move(vertices);
  cage.quads = std::move(out);
  std::vector<char> still_vain(kept, 0);
  for (const auto& [vertex, window] : searched)
    if (std::none_of(window.begin(), window.end(), [&](int v) { return locked[v]; }))
      still_vain[id[vertex]] = 1;
  return still_vain;
}

// A window's connectivity in local vertex ids (`local`: cage vertex → local id, numbered as
// the window's quads reach them), with each vertex's valence, ring, point and reach.
template <class ReachOf>
State window_state(const std::set<int>& window_quads, const CageIncidence& incidence,
                   const std::vector<int>& ring, const std::vector<std::array<int, 4>>& quads,
                   const std::vector<char>& fixed, const std::vector<char>& shed,
                   const std::vector<Vec3>& points, ReachOf& reach_of, std::map<int, int>* out) {
  State s;
  std::map<int, int>& local = *out;
  auto local_id = [&](int v) {
    auto [it, added] = local.emplace(v, static_cast<int>(s.valence.size()));
    if (added) {
      s.valence.push_back(static_cast<int>(incidence.quads_of[v].size()));
      s.ring.push_back(ring[v] >= 0 ? ring[v] : kWindowRings + 1);
      s.fixed.push_back(fixed[v]);
      s.shed.push_back(shed[v]);
      s.point.push_back(points[v]);
      s.reach.push_back(reach_of(v));
    }
    return it->second;
  };
  for (int q : window_quads) {
    std::array<int, 4> c;
    for (int k = 0; k < 4; ++k) c[k] = local_id(quads[q][k]);
    s.quads.push_back(c);
    s.origin.push_back(q);
  }
  return s;
}

// A chosen sequence's state `t` written into the cage as edited this round: quads rewritten,
// added or removed; new and moved vertices (`moved`, local ids).
void apply_sequence(const State& t, const std::vector<int>& global, const std::vector<int>& moved,
                    std::vector<Vec3>& points, std::vector<std::array<int, 4>>& quads) {
  std::vector<int> to_global = global;
  for (size_t l = global.size(); l < t.valence.size(); ++l) {
    to_global.push_back(static_cast<int>(points.size()));
    points.push_back(t.point[l]);
  }
  for (int v : moved) points[to_global[v]] = t.point[v];
  for (size_t q = 0; q < t.quads.size(); ++q) {
    std::array<int, 4> c = {-1, -1, -1, -1};
    if (t.quads[q][0] >= 0)
      for (int k = 0; k < 4; ++k) c[k] = to_global[t.quads[q][k]];
    if (t.origin[q] >= 0) quads[t.origin[q]] = c;
    else quads.push_back(c);
  }
}

// How far from `centre` a singularity can explain a vertex of the window `s`.
double window_extent(const State& s, const Vec3& centre) {
  double extent = 0;
  for (size_t l = 0; l < s.point.size(); ++l)
    extent = std::max(extent, (s.point[l] - centre).norm() + s.reach[l]);
  return extent;
}

// The singularities within `extent` of `centre` (into *near), and per singularity its index
// there (-1: not near).
void singularities_within(const std::vector<SingularPoint>& singular, const Vec3& centre,
                          double extent, std::vector<SingularPoint>* near,
                          std::vector<int>* near_id) {
  for (size_t i = 0; i < singular.size(); ++i)
    if ((singular[i].point - centre).norm() <= extent)
      (*near_id)[i] = static_cast<int>(near->size()), near->push_back(singular[i]);
}

}  // namespace

int chain_vertices_to_shed(const QuadCage& cage) {
  const std::vector<char> shed = shedding_chain_vertices(cage, CageIncidence(cage));
  return static_cast<int>(std::count(shed.begin(), shed.end(), 1));
}

int place_irregulars(const CageChecks& checks, QuadCage& cage,
                     const std::vector<SingularPoint>& singular, double density, int max_rounds,
                     const PlaceSettings& settings, const Dropped& dropped, double* scored_out) {
  const int max_edits = settings.max_edits;
  double scored_count = 0;  // sequences scored (settings.max_scored)
  auto spent = [&] { return settings.max_scored > 0 && scored_count >= settings.max_scored; };
  // Raised by one (up to settings.climb_last) where a round makes no edit.
  int climb = settings.climb;
  int total = 0;
  // Vertices whose window was searched in vain and has not changed since: not again.
  std::vector<char> vain(cage.vertices.rows(), 0);
  for (int round = 0; round < max_rounds; ++round) {
    dropped.check();
    const CageIncidence incidence(cage);
    const int nv = static_cast<int>(cage.vertices.rows());
    std::vector<char> fixed = incidence.on_chain;
    for (const auto& e : cage.crease_edges) fixed[e[0]] = fixed[e[1]] = 1;
    const std::vector<char> shed = shedding_chain_vertices(cage, incidence);
    std::vector<double> reach(nv, -1);
    auto reach_of = [&](int v) {
      if (reach[v] < 0) reach[v] = singular_reach(checks, cage, incidence, v, density);
      return reach[v];
    };
    // The unexplained vertices, as the measure finds them.
    std::vector<int> left;
    const std::vector<Irregular> irregular =
        matched_irregulars(checks, cage, incidence, singular, density, &left);
    for (const Irregular& x : irregular) reach[x.vertex] = x.reach;
    // The cage as edited this round: quads (removed: -1), vertices appended.
    std::vector<std::array<int, 4>> quads(cage.quads.rows());
    for (int q = 0; q < cage.quads.rows(); ++q)
      for (int k = 0; k < 4; ++k) quads[q][k] = cage.quads(q, k);
    std::vector<Vec3> points(nv);
    for (int v = 0; v < nv; ++v) points[v] = cage.vertices.row(v).transpose();
    std::vector<char> locked(nv, 0);
    std::vector<int> ring(nv, -1);
    int now = 0;
    // The vertices whose windows were searched in vain, and those windows' vertices.
    std::vector<std::pair<int, std::vector<int>>> searched;
    // Windows start at the unexplained vertices, then at the chain vertices that may shed a
    // quad (settings.chain_vertices).
    std::vector<int> starts;
    for (size_t e = 0; e < irregular.size(); ++e)
      if (left[e]) starts.push_back(irregular[e].vertex);
    if (settings.chain_vertices)
      for (int v = 0; v < nv; ++v)
        if (shed[v]) starts.push_back(v);
    for (const int start_vertex : starts) {
      if (vain[start_vertex]) continue;
      if (spent()) break;
      dropped.check();
      // The window: rings around the vertex by breadth-first search.
      std::vector<int> reached = {start_vertex};
      ring[reached[0]] = 0;
      for (size_t i = 0; i < reached.size(); ++i) {
        const int v = reached[i];
        if (ring[v] == kWindowRings) continue;
        for (int w : incidence.neighbours[v])
          if (ring[w] < 0) ring[w] = ring[v] + 1, reached.push_back(w);
      }
      std::set<int> window_quads;
      for (int v : reached) window_quads.insert(incidence.quads_of[v].begin(), incidence.quads_of[v].end());
      // Windows edited in one round share no quad and no vertex.
      bool free = true;
      for (int q : window_quads)
        for (int v : quads[q]) free &= !locked[v];
      State s;
      std::map<int, int> local;
      if (free)
        s = window_state(window_quads, incidence, ring, quads, fixed, shed, points, reach_of, &local);
      std::vector<int> global(local.size());
      for (const auto& [g, l] : local) global[l] = g;
      for (int v : reached) ring[v] = -1;
      if (!free) continue;
      std::vector<int> scored;
      for (size_t l = 0; l < s.valence.size(); ++l)
        if (s.ring[l] <= kScoreRings && (!incidence.on_chain[global[l]] || s.shed[l]))
          scored.push_back(static_cast<int>(l));
      const size_t window_vertices = s.valence.size();
      // The singularities that can explain a vertex of the window.
      const Vec3 centre = cage.vertices.row(start_vertex).transpose();
      const double extent = window_extent(s, centre);
      std::vector<SingularPoint> near;
      std::vector<int> near_id(singular.size(), -1);
      singularities_within(singular, centre, extent, &near, &near_id);
      Rivals rivals;
      if (settings.rivals) {
        std::vector<char> is_scored(s.valence.size(), 0);
        for (int l : scored) is_scored[l] = 1;
        rivals = rivals_of(
            irregular, singular, centre, extent,
            [&](int v) {
              const auto it = local.find(v);
              return it != local.end() && is_scored[it->second];
            },
            &near, &near_id);
      }
      const std::vector<Vec3> start_point = s.point;
      std::vector<std::vector<Explaining>> explains(s.valence.size());
      for (size_t l = 0; l < explains.size(); ++l)
        for (int sign : {1, -1})  // either sign: what the vertex carries changes with edits
          if (!(settings.chain_vertices && s.shed[l]))  // none explains a chain vertex
            explaining_pairs({static_cast<int>(l), sign, s.point[l], s.reach[l]}, -1, near,
                             &explains[l]);
      // Of the sequences of edits tried, the kKeptSequences best that leave fewer
      // unexplained vertices (or as many, no more irregular ones, drawn kPairCloser nearer
      // to ones of opposite sign) are kept, best first.
      auto score_now = [&] {
        ++scored_count;
        return score(s, near, scored, window_vertices, explains, start_point, rivals,
                     settings.draw_pairs_together);
      };
      const Score before = score_now();
      // Where the window's count finds none unexplained, no sequence can leave fewer or draw
      // a pair nearer: not searched.
      if (std::get<0>(before) == 0) {
        searched.push_back({start_vertex, std::move(global)});
        continue;
      }
      std::vector<std::pair<Score, State>> kept =
          search_sequences(s, score_now, before, window_vertices, max_edits, climb);
      // The first whose quads, evened out around the changed vertices, are not squeezed or
      // turned over.
      State* chosen = nullptr;
      std::vector<int> moved;
      for (auto& [at, state] : kept)
        if (settle(checks, state, settings.settle_rings, settings.settle_sweeps, &moved)) {
          chosen = &state;
          break;
        }
      if (!chosen) {
        searched.push_back({start_vertex, std::move(global)});
        continue;
      }
      const State& t = *chosen;
      apply_sequence(t, global, moved, points, quads);
      for (int q : window_quads)
        for (int k = 0; k < 4; ++k) locked[cage.quads(q, k)] = 1;
      ++now;
    }
    // Where a round makes no edit, every window is searched again climbing by one more.
    if (!now && climb < settings.climb_last && !spent()) {
      ++climb;
      std::fill(vain.begin(), vain.end(), 0);
      continue;
    }
    if (!now) break;
    total += now;
    // Compacted: removed quads and vertices no quad or chain uses dropped.
    vain = compact(cage, points, quads, searched, locked);
  }
  if (scored_out) *scored_out += scored_count;
  return total;
}

}  // namespace genbrep::quad_detail
