// relax/smooth.cpp — step (b) of §5.3: surface-restricted curve smoothing of the loops.
// After Hofer & Pottmann (2004), a loop vertex moves towards the mean of its two loop
// neighbours and is projected back onto the design. Plain Laplacian steps shrink a
// closed curve (and so the organic region on its convex side); Taubin's λ|μ pair
// (Taubin 1995) alternates a shrinking and a slightly larger inflating step, which damps
// the voxel zigzag (the highest frequencies) while keeping the loop's overall shape.
// Every move is checked before it is made: the new position is projected onto the
// original design, must stay within d of the original loops (or get closer to them), and
// no incident triangle may turn against the design normal or lose its area. A refused
// move is halved up to four times, then skipped; the inflating μ step of a vertex is
// scaled by the share of its λ step that was taken, so a held-back vertex is not pushed
// outwards alone. Channel vertices off the label borders then follow (Laplacian step to
// their neighbours' mean, projected, same checks), which gives the next round room.
#include <algorithm>

#include "relax/detail/relax_detail.h"

namespace genbrep::relax_detail {
namespace {

constexpr const char* kStage = "relax";
constexpr int kHalvings = 4;
constexpr int kChannelSweeps = 2;
// repair_folds treats a triangle whose normal is within about 84° of the design's as fine.
constexpr double kFoldCosine = 0.1;
constexpr int kFoldRounds = 5;

class Smoother {
 public:
  Smoother(TriMesh& mesh, const SurfaceProjector& projector, const PolylineDistance& original,
           double d, double min_cosine)
      : mesh_(mesh),
        projector_(projector),
        original_(original),
        d_(d),
        min_cosine_(min_cosine),
        normal_(mesh.n_vertices(), Vec3::Zero()),
        known_(mesh.n_vertices(), 0) {}

  Vec3 position(int v) const {
    const auto& p = mesh_.point(mesh_.vertex_handle(v));
    return Vec3(p[0], p[1], p[2]);
  }

  // Unit design normal where v projects (cached, updated when v moves).
  const Vec3& surface_normal(int v) {
    if (!known_[v]) {
      normal_[v] = projector_.normal(projector_.nearest(position(v)).triangle);
      known_[v] = 1;
    }
    return normal_[v];
  }

  // Moves v towards `target` (the whole way, or a half, a quarter, ...), projected onto
  // the design; `capped` applies the d limit of loop vertices. Returns the fraction of
  // the way taken, 0 if v did not move.
  double try_move(int v, const Vec3& target, bool capped) {
    const Vec3 p = position(v);
    const double current = capped ? original_.nearest(p).distance : 0;
    double t = 1;
    for (int attempt = 0; attempt <= kHalvings; ++attempt, t *= 0.5) {
      const auto hit = projector_.nearest(p + t * (target - p));
      if (capped) {
        const double distance = original_.nearest(hit.point).distance;
        if (distance > d_ && distance > current) continue;
      }
      const Vec3& normal = projector_.normal(hit.triangle);
      if (!keeps_orientation(v, hit.point, normal)) continue;
      mesh_.set_point(mesh_.vertex_handle(v),
                      TriMesh::Point(hit.point.x(), hit.point.y(), hit.point.z()));
      normal_[v] = normal;
      known_[v] = 1;
      return t;
    }
    return 0;
  }

 private:
  // No triangle around v may end up facing against the design or without area; one
  // whose best agreement is already below min_cosine may not get worse.
  bool keeps_orientation(int v, const Vec3& q, const Vec3& q_normal) {
    const auto vh = mesh_.vertex_handle(v);
    for (const auto f : mesh_.vf_range(vh)) {
      Vec3 corner[3], moved[3], normal[3], moved_normal[3];
      int k = 0;
      for (const auto w : mesh_.fv_range(f)) {
        corner[k] = position(w.idx());
        normal[k] = surface_normal(w.idx());
        moved[k] = w == vh ? q : corner[k];
        moved_normal[k] = w == vh ? q_normal : normal[k];
        ++k;
      }
      const Agreement after =
          normal_agreement(moved[0], moved[1], moved[2], projector_, moved_normal);
      if (after.centroid <= 0) return false;
      if (after.best >= min_cosine_) continue;
      if (after.best < normal_agreement(corner[0], corner[1], corner[2], projector_, normal).best) {
        return false;
      }
    }
    return true;
  }

  TriMesh& mesh_;
  const SurfaceProjector& projector_;
  const PolylineDistance& original_;
  double d_;
  double min_cosine_;
  std::vector<Vec3> normal_;
  std::vector<char> known_;
};

}  // namespace

Smoothing smooth_loops(TriMesh& mesh, const std::vector<int>& labels,
                       const std::vector<BoundaryLoop>& loops, const SurfaceProjector& projector,
                       const PolylineDistance& original, double d, const RelaxOptions& options,
                       const Context& context) {
  Smoothing out;
  Smoother smoother(mesh, projector, original, d, options.min_normal_cosine);

  // Label-border edges per vertex: 2 on a plain loop vertex, more where borders meet.
  std::vector<int> border_edges(mesh.n_vertices(), 0);
  for (const auto e : mesh.edges()) {
    const auto h = mesh.halfedge_handle(e, 0);
    if (labels[mesh.face_handle(h).idx()] == labels[mesh.opposite_face_handle(h).idx()]) continue;
    ++border_edges[mesh.from_vertex_handle(h).idx()];
    ++border_edges[mesh.to_vertex_handle(h).idx()];
  }
  std::vector<int> loop_vertices;
  for (const auto& loop : loops) {
    loop_vertices.insert(loop_vertices.end(), loop.vertices.begin(), loop.vertices.end());
    for (int v : loop.vertices) out.fixed_vertices += border_edges[v] > 2;
  }
  // Channel vertices free to follow: near a loop, on no label border.
  const std::vector<char> near = vertex_rings(mesh, loop_vertices, options.channel_rings);
  std::vector<int> channel;
  for (int v = 0; v < static_cast<int>(mesh.n_vertices()); ++v) {
    if (near[v] && border_edges[v] == 0) channel.push_back(v);
  }

  // One Taubin half-step; `taken` holds per vertex the fraction of its λ step that was
  // accepted, and scales its μ step, so a vertex held back on the way in is not pushed
  // out alone (which would grow a spike).
  std::vector<double> taken(mesh.n_vertices(), 1.0);
  const auto loop_step = [&](double factor, bool inflating) {
    for (const auto& loop : loops) {
      const int n = static_cast<int>(loop.vertices.size());
      std::vector<Vec3> target(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) {  // Jacobi: targets from the positions before the step
        const int v = loop.vertices[i];
        const Vec3 p = smoother.position(v);
        const Vec3 mean = 0.5 * (smoother.position(loop.vertices[(i + n - 1) % n]) +
                                 smoother.position(loop.vertices[(i + 1) % n]));
        target[i] = p + factor * (inflating ? taken[v] : 1.0) * (mean - p);
      }
      for (int i = 0; i < n; ++i) {
        const int v = loop.vertices[i];
        if (border_edges[v] > 2) continue;
        const double t = smoother.try_move(v, target[i], true);
        if (!inflating) taken[v] = t;
        if (t > 0) {
          ++out.accepted_moves;
        } else {
          ++out.skipped_moves;
        }
      }
    }
  };
  const auto relax_channel = [&]() {
    for (int v : channel) {
      Vec3 mean = Vec3::Zero();
      int count = 0;
      for (const auto w : mesh.vv_range(mesh.vertex_handle(v))) {
        mean += smoother.position(w.idx());
        ++count;
      }
      smoother.try_move(v, mean / std::max(count, 1), false);
    }
  };

  // Loop vertices that the remesh left beyond d go back towards the original loop first.
  for (int v : loop_vertices) {
    const auto hit = original.nearest(smoother.position(v));
    if (hit.distance > d && border_edges[v] <= 2) smoother.try_move(v, hit.point, true);
  }
  for (int iteration = 0; iteration < options.smoothing_iterations; ++iteration) {
    loop_step(options.taubin_lambda, false);
    loop_step(options.taubin_mu, true);
    for (int sweep = 0; sweep < kChannelSweeps; ++sweep) relax_channel();
    context.step(kStage, 0.5 + 0.4 * (iteration + 1) / options.smoothing_iterations);
  }
  return out;
}

}  // namespace genbrep::relax_detail

namespace genbrep::relax_detail {

FoldRepair repair_folds(TriMesh& mesh, const std::vector<int>& labels,
                        const std::vector<int>& origin, const SurfaceProjector& projector) {
  const auto position = [&](TriMesh::VertexHandle v) {
    const auto& p = mesh.point(v);
    return Vec3(p[0], p[1], p[2]);
  };
  const auto agreement = [&](TriMesh::FaceHandle f) {
    Vec3 c[3];
    int k = 0;
    for (const auto v : mesh.fv_range(f)) c[k++] = position(v);
    return normal_agreement(c[0], c[1], c[2], projector).centroid;
  };
  const auto worst_around = [&](TriMesh::VertexHandle v) {
    double worst = 1;
    for (const auto f : mesh.vf_range(v)) worst = std::min(worst, agreement(f));
    return worst;
  };
  const auto on_border = [&](TriMesh::VertexHandle v) {
    for (const auto h : mesh.voh_range(v)) {
      if (labels[mesh.face_handle(h).idx()] != labels[mesh.opposite_face_handle(h).idx()])
        return true;
    }
    return false;
  };
  std::vector<int> folded;
  for (const auto f : mesh.faces()) {
    if (origin[f.idx()] < 0 && agreement(f) <= kFoldCosine) folded.push_back(f.idx());
  }
  FoldRepair out;
  out.folded = static_cast<int>(folded.size());
  for (int round = 0; round < kFoldRounds && !folded.empty(); ++round) {
    std::vector<int> still;
    for (const int index : folded) {
      const auto f = mesh.face_handle(index);
      const double before = agreement(f);
      if (before > kFoldCosine) continue;
      still.push_back(index);
      // A folded cap: flip its longest edge if that leaves both triangles facing out.
      TriMesh::HalfedgeHandle longest;
      double length = -1;
      for (const auto h : mesh.fh_range(f)) {
        const double l = mesh.calc_edge_length(h);
        if (l > length) length = l, longest = h;
      }
      const auto e = mesh.edge_handle(longest);
      const auto g = mesh.opposite_face_handle(longest);
      if (labels[f.idx()] == labels[g.idx()] && mesh.is_flip_ok(e)) {
        const double worst = std::min(before, agreement(g));
        mesh.flip(e);
        if (std::min(agreement(f), agreement(g)) > worst) continue;
        mesh.flip(e);  // flipping twice restores the pair
      }
      // Otherwise move a corner off the label borders to its neighbours' mean.
      for (const auto v : mesh.fv_range(f)) {
        if (on_border(v)) continue;
        const Vec3 p = position(v);
        Vec3 mean = Vec3::Zero();
        int count = 0;
        for (const auto w : mesh.vv_range(v)) mean += position(w), ++count;
        const double worst = worst_around(v);
        const Vec3 q = projector.nearest(mean / std::max(count, 1)).point;
        mesh.set_point(v, TriMesh::Point(q.x(), q.y(), q.z()));
        if (worst_around(v) > worst) break;
        mesh.set_point(v, TriMesh::Point(p.x(), p.y(), p.z()));
      }
    }
    folded = std::move(still);
  }
  for (const int index : folded) out.remaining += agreement(mesh.face_handle(index)) <= kFoldCosine;
  return out;
}

}  // namespace genbrep::relax_detail
