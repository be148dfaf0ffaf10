// quad/square.cpp — the kept cage's corners brought closer to square on the surface
// (square_cage), and the squared copy a layout choice is judged or kept with.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <thread>
#include <vector>

#include "quad/detail/attempt.h"
#include "quad/detail/edit.h"

namespace genbrep::quad_detail {

namespace {

// square_cage: what a relative change of edge length costs against a corner's change in
// radians.
constexpr double kStretchWeight = 1.0;
// square_cage: what the rows' unevenness (second differences along them, over the edge
// length, squared) costs against corners; without it squaring makes the rows wave.
constexpr double kFairWeight = 1.0;

// square_cage's state: the cage's rows and ideal corners as filled, and per vertex what a
// sweep reads and writes.
class Squarer {
 public:
  Squarer(const CageChecks& checks, QuadCage& cage, double density);
  int run(int sweeps, int threads);

 private:
  Vec3 point(int v) const { return Vec3(cage.vertices.row(v).transpose()); }
  void find_rows();
  void ideal_corners();
  void hold_crowded();
  void colour_vertices();
  double rest_length(int v, int w) const;
  double stretch(int v, int w, const Vec3& p) const;
  double energy(int v, const Vec3& p) const;
  bool step_vertex(int v);

  const CageChecks& checks;
  const ComponentLocator& locator;
  const DesignNormals& normals;
  QuadCage& cage;
  const double density;
  const int nv;
  const CageIncidence incidence;
  const std::vector<char>& fixed;
  const std::vector<std::vector<int>>& quads_of;
  // The rows through each free vertex of four quads: its neighbours in turn (one quad's
  // previous corner is the next quad's next), so ring[0], ring[2] and ring[1], ring[3]
  // are the rows' two sides.
  std::vector<std::array<int, 4>> ring;
  std::vector<char> in_rows;
  std::vector<double> ideal;   // each vertex's ideal corner
  std::vector<double> scale2;  // each vertex's mean squared edge length as filled
  std::vector<std::array<double, 4>> rest;  // each free vertex's edge lengths as filled
  // A vertex is looked at again only once it or a neighbour has moved.
  // Each vertex's and quad centroid's last triangle (ComponentLocator::closest); a quad's
  // is written only by its corners, which never step at once (below).
  std::vector<char> active, moved_now;
  std::vector<int> hint, quad_hint;
  std::vector<double> last_step;  // over the vertex's mean edge length
  std::vector<std::vector<int>> by_colour;  // vertices that may step at once
};

Squarer::Squarer(const CageChecks& checks, QuadCage& cage, double density)
    : checks(checks),
      locator(checks.locator),
      normals(checks.normals),
      cage(cage),
      density(density),
      nv(static_cast<int>(cage.vertices.rows())),
      incidence(cage),
      fixed(incidence.on_chain),
      quads_of(incidence.quads_of),
      ring(nv),
      in_rows(nv, 0),
      ideal(nv, kPi / 2),
      scale2(nv, 1.0),
      rest(nv) {
  find_rows();
  ideal_corners();
  hold_crowded();
  active = in_rows;
  moved_now.assign(nv, 0);
  hint.assign(nv, -1);
  quad_hint.assign(cage.quads.rows(), -1);
  last_step.assign(nv, 0.1);
  colour_vertices();
}

void Squarer::find_rows() {
  for (int v = 0; v < nv; ++v) {
    if (fixed[v] || quads_of[v].size() != 4) continue;
    std::array<int, 4> next_of, after;
    for (int i = 0; i < 4; ++i) {
      const auto c = corners_from(cage, quads_of[v][i], v);
      next_of[i] = c[1], after[i] = c[3];
    }
    int at = 0;
    bool closed = true;
    for (int i = 0; i < 4 && closed; ++i) {
      ring[v][i] = next_of[at];
      const int* found = std::find(next_of.begin(), next_of.end(), after[at]);
      closed = found != next_of.end();
      at = static_cast<int>(found - next_of.begin());
    }
    in_rows[v] = closed && ring[v][0] == next_of[at] &&
                 std::set<int>(ring[v].begin(), ring[v].end()).size() == 4;
  }
}

void Squarer::ideal_corners() {
  // Each vertex's ideal corner: a full turn shared by its quads inside, its angle sum
  // (as filled) shared evenly on a chain, where the loop decides the sum.
  // Each vertex's mean squared edge length as filled (scales second differences).
  for (int v = 0; v < nv; ++v) {
    const int n = static_cast<int>(quads_of[v].size());
    if (!n) continue;
    double sum = 0, squares = 0;
    for (int q : quads_of[v]) {
      const auto c = corners_from(cage, q, v);
      sum += corner_angle(point(v), point(c[1]), point(c[3]));
      squares += (point(c[1]) - point(v)).squaredNorm();
    }
    ideal[v] = fixed[v] ? sum / n : 2 * kPi / n;
    if (squares > 0) scale2[v] = squares / n;
  }
  // Each free vertex's edges' lengths as filled, in ring order (a relative change costs
  // like a corner's in radians, so squaring does not trade the layout's spacing for thin
  // rectangles).
  for (int v = 0; v < nv; ++v)
    if (in_rows[v])
      for (int i = 0; i < 4; ++i) rest[v][i] = (point(ring[v][i]) - point(v)).norm();
}

double Squarer::rest_length(int v, int w) const {
  return rest[v][std::find(ring[v].begin(), ring[v].end(), w) - ring[v].begin()];
}

double Squarer::stretch(int v, int w, const Vec3& p) const {
  const double r = rest_length(v, w);
  const double x = r > 0 ? ((p - point(w)).norm() - r) / r : 0;
  return x * x;
}

  // What moves with v at p: its corners, its two neighbours' corners in each of its quads,
  // its edges (each in two quads, so half each time), and the rows through v and through
  // its neighbours.
double Squarer::energy(int v, const Vec3& p) const {
  double e = 0;
  for (int q : quads_of[v]) {
    const auto c = corners_from(cage, q, v);
    const int a = c[1], d = c[2], b = c[3];
    const Vec3 pa = point(a), pb = point(b), pd = point(d);
    const double at_v = corner_angle(p, pa, pb) - ideal[v];
    const double at_a = corner_angle(pa, pd, p) - ideal[a];
    const double at_b = corner_angle(pb, p, pd) - ideal[b];
    e += at_v * at_v + at_a * at_a + at_b * at_b +
         0.5 * kStretchWeight * (stretch(v, a, p) + stretch(v, b, p));
  }
  if (!in_rows[v]) return e;
  const auto& r = ring[v];
  double rows = ((point(r[0]) + point(r[2]) - 2 * p).squaredNorm() +
                 (point(r[1]) + point(r[3]) - 2 * p).squaredNorm()) / scale2[v];
  for (int w : r) {
    if (!in_rows[w]) continue;
    const auto& s = ring[w];
    const int j = static_cast<int>(std::find(s.begin(), s.end(), v) - s.begin());
    if (j < 4) rows += (p + point(s[(j + 2) % 4]) - 2 * point(w)).squaredNorm() / scale2[w];
  }
  return e + kFairWeight * rows;
}

void Squarer::hold_crowded() {
  // Within two rings of a vertex of six or more quads (left by a collapse) nothing moves
  // (nor do the rows through such vertices count): the limit surface folds there first
  // (better_cage), and squaring beside one can make the fit fold.
  std::vector<char> crowded(nv, 0);
  for (int v = 0; v < nv; ++v) crowded[v] = quads_of[v].size() >= 6;
  for (int grow = 0; grow < 2; ++grow) {
    std::vector<char> next = crowded;
    for (int q = 0; q < cage.quads.rows(); ++q)
      for (int k = 0; k < 4; ++k)
        if (crowded[cage.quads(q, k)])
          for (int j = 0; j < 4; ++j) next[cage.quads(q, j)] = 1;
    crowded.swap(next);
  }
  for (int v = 0; v < nv; ++v) in_rows[v] &= !crowded[v];
}

  // One vertex's step; true if it moved. Reads the corners of its quads and the far ends
  // of the rows through its neighbours, writes only its own position and state.
bool Squarer::step_vertex(int v) {
  const Vec3 old = point(v);
  Vec3 normal;
  const Vec3 at = locator.closest(old, &normal, &hint[v]);
  double length = 0;
  for (int w : ring[v]) length += 0.25 * (point(w) - at).norm();
  if (length <= 0) return false;
  // No edge grows past twice the target length unless it came longer (oversized
  // quads, QuadStats, are those past 2.5x), nor shrinks under half of it unless it
  // came shorter.
  const int near = normals.nearest_vertex(at);
  const double target = near >= 0 ? checks.surface.vertex_size[near] / density
                                  : std::numeric_limits<double>::quiet_NaN();
  auto out_of_range = [&](const Vec3& p) {
    if (!(target > 0)) return false;
    for (int w : ring[v]) {
      const double now = (p - point(w)).norm(), was = rest_length(v, w);
      if ((now > 2 * target && now > was) || (now < 0.5 * target && now < was)) return true;
    }
    return false;
  };
  // A gradient step in the tangent plane (forward differences), at most a tenth of
  // the edges around: the vertex's last good step, or half of it until the energy
  // drops; a good step grows by half for the next sweep.
  const Vec3 t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
  const double h = 1e-5 * length;
  const double before = energy(v, at);
  const Vec3 gradient =
      t1 * (energy(v, at + h * t1) - before) / h + t2 * (energy(v, at + h * t2) - before) / h;
  const double slope = gradient.norm();
  if (slope == 0) return false;
  double step = std::min({0.1 * length, before / slope, last_step[v] * length});
  for (int tries = 0; tries < 4; ++tries, step *= 0.5) {
    Vec3 landed_normal;
    int landed_hint = hint[v];
    const Vec3 landed =
        locator.closest(at - step * gradient / slope, &landed_normal, &landed_hint);
    if (landed_normal.dot(normal) < 0.5) continue;
    if (energy(v, landed) >= before || out_of_range(landed)) continue;
    cage.vertices.row(v) = landed.transpose();
    bool ok = true;
    for (int q : quads_of[v])
      ok = ok && !quad_is_bad(locator, normals, cage, q, kMinCornerDegrees, &quad_hint[q]);
    if (ok) {
      hint[v] = landed_hint;
      last_step[v] = 1.5 * step / length;
      return true;
    }
    cage.vertices.row(v) = old.transpose();
  }
  return false;
}

void Squarer::colour_vertices() {
  // Vertices that read each other's positions never step at once: they get different
  // colours (greedy, in vertex order), and a sweep takes the colours in turn, the
  // vertices of one colour on `threads` threads. The result does not depend on the
  // number of threads.
  std::vector<std::vector<int>> reads(nv);  // symmetric
  for (int v = 0; v < nv; ++v) {
    if (!in_rows[v]) continue;
    auto link = [&](int u) {
      if (u != v) reads[v].push_back(u), reads[u].push_back(v);
    };
    for (int q : quads_of[v])
      for (int k = 0; k < 4; ++k) link(cage.quads(q, k));
    for (int w : ring[v])
      if (in_rows[w])
        for (int u : ring[w]) link(u);
  }
  std::vector<int> colour(nv, -1);
  std::vector<int> taken_by(nv, -1);  // colour → the last vertex that saw it taken
  for (int v = 0; v < nv; ++v) {
    if (!in_rows[v]) continue;
    for (int u : reads[v])
      if (colour[u] >= 0) taken_by[colour[u]] = v;
    int c = 0;
    while (taken_by[c] == v) ++c;
    colour[v] = c;
    if (c >= static_cast<int>(by_colour.size())) by_colour.resize(c + 1);
    by_colour[c].push_back(v);
  }
}

int Squarer::run(int sweeps, int threads) {
  const int workers = std::max(1, threads);
  int moved = 0;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    std::fill(moved_now.begin(), moved_now.end(), 0);
    for (const std::vector<int>& group : by_colour) {
      auto run = [&](size_t first, size_t last) {
        for (size_t i = first; i < last; ++i)
          if (active[group[i]]) moved_now[group[i]] = step_vertex(group[i]);
      };
      const size_t n = group.size();
      if (workers == 1 || n < 64) {
        run(0, n);
        continue;
      }
      std::vector<std::thread> pool;
      for (int t = 1; t < workers; ++t)
        pool.emplace_back(run, n * t / workers, n * (t + 1) / workers);
      run(0, n / workers);
      for (auto& thread : pool) thread.join();
    }
    moved = 0;
    for (int v = 0; v < nv; ++v) moved += moved_now[v];
    for (int v = 0; v < nv; ++v) {
      if (!in_rows[v]) continue;
      active[v] = moved_now[v];
      for (int w : ring[v]) active[v] |= moved_now[w];
    }
  }
  return moved;
}


}  // namespace

int square_cage(const CageChecks& checks, QuadCage& cage, int sweeps, double density, int threads) {
  return Squarer(checks, cage, density).run(sweeps, threads);
}

std::optional<Squared> square_copy(const quad_detail::CageChecks& checks, double density,
                                   int threads, const QuadCage& cage, const QuadStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  Squared out{cage};
  out.moved = quad_detail::square_cage(checks, out.cage, 10, density, threads);
  const QuadStats measured = quad_detail::measure_cage(out.cage, checks);
  if (measured.flipped_quads || measured.degenerate_quads ||
      measured.mean_angle_deviation_deg >= stats.mean_angle_deviation_deg)
    return std::nullopt;
  out.mean_deg = measured.mean_angle_deviation_deg;
  out.max_deg = measured.max_angle_deviation_deg;
  out.skewed_quads = measured.skewed_quads;
  out.oversized_quads = quad_detail::oversized_quads(checks, out.cage, density, kOversized);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

// The kept cage takes its squared copy (square_copy, or the one its attempt made already),
// reported. Only the kept cage: layout choices are compared as filled and evened out,
// where a distorted layout (a fan of rows over collapsed slivers) still shows in its
// angles; squaring would hide that.
void keep_squared(Squared&& squared, int c, QuadCage* cage, QuadStats* stats,
                  Diagnostics* notes) {
  char text[200];
  std::snprintf(text, sizeof text,
                "component %d: corners squared (%d cage vertices moved in the last sweep, "
                "%.1f s): mean deviation from 90° %.1f° → %.1f°",
                c, squared.moved, squared.seconds, stats->mean_angle_deviation_deg,
                squared.mean_deg);
  notes->push_back(text);
  // Vertices moved, the topology did not: only the angles change.
  stats->mean_angle_deviation_deg = squared.mean_deg;
  stats->max_angle_deviation_deg = squared.max_deg;
  stats->skewed_quads = squared.skewed_quads;
  stats->oversized_quads = squared.oversized_quads;
  stats->seconds += squared.seconds;
  *cage = std::move(squared.cage);
}

void square_kept(const quad_detail::CageChecks& checks, double density, int c, int threads,
                 QuadCage* cage, QuadStats* stats, Diagnostics* notes) {
  if (auto squared = square_copy(checks, density, threads, *cage, *stats))
    keep_squared(std::move(*squared), c, cage, stats, notes);
}


}  // namespace genbrep::quad_detail
