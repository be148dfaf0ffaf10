// field/singularities.cpp — singular vertices of the cross field and their indices (§6.1).
// Around a vertex, crossing each spoke from one face to the next, the field's jump relative
// to the shared edge, reduced to (−π/4, π/4], is the period-jump matching of MIQ. For an
// interior vertex the index is (K_v + Σ jumps)/(2π), K_v = 2π − Σ corner angles the angle
// defect (the connection's holonomy). For a loop vertex with interior angle α the fan's
// jumps sum to R and the index is (π − α + R)/(2π): with the field aligned to both loop
// edges this is a multiple of 1/4, 0 exactly when the field turns with the loop. On the
// spokes of a loop vertex's fan the jump is matched to the loop's turning rather than
// reduced, so flat loop vertices are regular (see below). The jumps cancel pairwise over the
// component and the angle terms add up to 2πχ by Gauss–Bonnet, so the indices sum to χ
// (Poincaré–Hopf) — in quarter turns, 4χ.
#include <algorithm>
#include <cmath>
#include <map>

#include "field/detail/field_detail.h"

namespace genbrep::field_detail {
namespace {

// Jump of the field crossing spoke h (leaving its from-vertex) from the face on its right
// to the face on its left.
double jump(const TriMesh& mesh, const FaceFrames& frames, const std::vector<double>& theta,
            OpenMesh::HalfedgeHandle h) {
  const int f = mesh.opposite_face_handle(h).idx(), g = mesh.face_handle(h).idx();
  const auto& a = mesh.point(mesh.from_vertex_handle(h));
  const auto& b = mesh.point(mesh.to_vertex_handle(h));
  const Vec3 e(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
  return wrap_quarter((theta[g] - frames.angle(g, e)) - (theta[f] - frames.angle(f, e)));
}

}  // namespace

BoundaryFan boundary_fan(const TriMesh& mesh, const Partition& partition, int component,
                         OpenMesh::VertexHandle v, OpenMesh::VertexHandle next) {
  BoundaryFan fan;
  auto in_component = [&](OpenMesh::HalfedgeHandle h) {
    const auto f = mesh.face_handle(h);
    return f.is_valid() && partition.face_component[f.idx()] == component;
  };
  const auto h_out = mesh.find_halfedge(v, next);
  if (!h_out.is_valid() || !in_component(h_out)) return fan;
  for (auto h = h_out; in_component(h) && fan.spokes.size() < mesh.valence(v);
       h = mesh.opposite_halfedge_handle(mesh.prev_halfedge_handle(h))) {
    fan.spokes.push_back(h);
    fan.before.push_back(fan.alpha);
    fan.beta.push_back(corner_angle(mesh, h));
    fan.alpha += fan.beta.back();
  }
  const int m = static_cast<int>(fan.spokes.size());
  for (int j = 0; j < m; ++j) {
    const double phi = m == 1       ? 0.5 * fan.alpha
                       : j == 0     ? 0
                       : j == m - 1 ? fan.alpha
                                    : fan.before[j] + 0.5 * fan.beta[j];
    fan.tangent.push_back(fan.alpha > 0 ? (fan.alpha - kPi) * phi / fan.alpha : 0);
  }
  return fan;
}

void find_singularities(const TriMesh& mesh, const Partition& partition, const FaceFrames& frames,
                        const ComponentInput& input, const std::vector<double>& theta,
                        CrossField* field) {
  auto in_component = [&](OpenMesh::FaceHandle f) {
    return f.is_valid() && partition.face_component[f.idx()] == input.component;
  };
  int off_integer = 0;
  double worst = 0;
  auto record = [&](int vertex, double quarters, bool boundary) {
    const double rounded = std::round(quarters);
    if (std::abs(quarters - rounded) > 0.05) ++off_integer;
    worst = std::max(worst, std::abs(quarters - rounded));
    if (rounded != 0)
      field->singularities.push_back(
          {vertex, static_cast<int>(rounded), input.component, boundary});
  };

  // Period jumps on the spokes of boundary fans follow the loop: of the jumps equal modulo
  // a quarter turn, the one nearest the turn of the fan's tangent interpolation. Where a fan
  // is too coarse to turn with the loop in steps under π/4 this moves the singularity from
  // the loop vertex to the spoke's inner end, so a flat loop vertex is never singular.
  // Keyed by edge, oriented across halfedge 0 of the edge.
  std::map<int, double> loop_matched;
  auto matched = [&](OpenMesh::HalfedgeHandle h) {
    const auto e = mesh.edge_handle(h);
    const auto it = loop_matched.find(e.idx());
    if (it == loop_matched.end()) return jump(mesh, frames, theta, h);
    return h == mesh.halfedge_handle(e, 0) ? it->second : -it->second;
  };
  std::vector<char> on_loop(mesh.n_vertices(), 0);
  std::vector<std::pair<int, BoundaryFan>> fans;
  for (const BoundaryLoop* loop : input.loops) {
    const int count = static_cast<int>(loop->vertices.size());
    for (int k = 0; k < count; ++k) {
      const auto v = mesh.vertex_handle(loop->vertices[k]);
      on_loop[v.idx()] = 1;
      fans.emplace_back(v.idx(), boundary_fan(mesh, partition, input.component, v,
                                              mesh.vertex_handle(loop->vertices[(k + 1) % count])));
      const BoundaryFan& fan = fans.back().second;
      for (size_t j = 1; j < fan.spokes.size(); ++j) {
        const auto h = fan.spokes[j];
        const double intended = fan.tangent[j] - fan.tangent[j - 1];
        const double x = intended + wrap_quarter(jump(mesh, frames, theta, h) - intended);
        const auto e = mesh.edge_handle(h);
        loop_matched.emplace(e.idx(), h == mesh.halfedge_handle(e, 0) ? x : -x);
      }
    }
  }
  // Loop vertices: one fan each (partition guarantees two boundary edges per vertex).
  for (const auto& [vertex, fan] : fans) {
    if (fan.spokes.empty()) continue;
    double turning = 0;
    for (size_t j = 1; j < fan.spokes.size(); ++j) turning += matched(fan.spokes[j]);
    record(vertex, (kPi - fan.alpha + turning) / kQuarter, true);
  }

  // Interior vertices: every face around them in the component.
  std::vector<int> vertices;
  for (int f : input.faces)
    for (auto v : mesh.fv_range(mesh.face_handle(f))) vertices.push_back(v.idx());
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  for (int vi : vertices) {
    if (on_loop[vi]) continue;
    const auto v = mesh.vertex_handle(vi);
    double defect = 2 * kPi, turning = 0;
    bool interior = true;
    for (auto h : mesh.voh_range(v)) {
      if (!in_component(mesh.face_handle(h)) || !in_component(mesh.opposite_face_handle(h))) {
        interior = false;
        break;
      }
      defect -= corner_angle(mesh, h);
      turning += matched(h);
    }
    if (interior) record(vi, (defect + turning) / kQuarter, false);
  }
  if (off_integer > 0) {
    field->diagnostics.push_back(
        "field: component " + std::to_string(input.component) + ": " + std::to_string(off_integer) +
        " vertex indices off a quarter turn by up to " + std::to_string(worst) +
        " (field not aligned with both loop edges)");
  }
}

}  // namespace genbrep::field_detail
