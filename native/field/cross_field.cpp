// field/cross_field.cpp — the smooth 4-RoSy cross field of one organic component (§6.1).
// Formulation of Knöppel, Crane, Pinkall, Schröder, "Globally optimal direction fields"
// (SIGGRAPH 2013): a cross at angle θ in face f's frame is the complex number u = e^{4iθ},
// so the four arms are one value and no period jumps are unknowns. Smoothness is the
// connection Dirichlet energy Σ_e w_e |u_g − r_fg u_f|², r_fg = e^{4i(α_g − α_f)} transporting
// f's frame to g's across their shared edge (α: the edge's angle in each frame). Alignment
// with curvature is the data term Σ_f W_f |u_f − q_f|², q_f = e^{4iφ_f} (φ_f: the principal
// direction), W_f = alignment_weight · c_f · A_f / ℓ², c_f the anisotropy confidence, so the
// field follows curvature over about one target edge length ℓ where the surface is
// anisotropic and is merely smooth where it is umbilic or flat. Minimising is one sparse
// Hermitian positive definite solve; the result is normalised per face. This replaces MIQ's
// greedy rounding, which the paper cites [32,60] and which is fragile.
// Boundary (the paper's regularity constraint along ∂O, §6): triangles touching a loop are
// Dirichlet-fixed to the loop tangent, interpolated across each boundary vertex's fan so the
// field turns with the loop; triangles within the channel are fixed to the smoothest
// extension of those values (a small solve over the channel alone, free on its inner side).
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <limits>
#include <queue>

#include "field/detail/field_detail.h"

namespace genbrep::field_detail {
namespace {

struct EdgeLink {
  int f, g;   // local face indices
  double w;   // dual-edge weight
  Complex r;  // transport of u from f to g
};

enum State : int { kExcluded = -1, kFree = 0, kFixed = 1 };

Vec3 point(const TriMesh& mesh, OpenMesh::VertexHandle v) {
  const auto& p = mesh.point(v);
  return Vec3(p[0], p[1], p[2]);
}

// Minimises the energy over the faces with state kFree, the kFixed ones entering through
// `value`. Faces kExcluded are cut off (natural boundary). Returns the free faces' u in
// `value`. `shift` (per unit area) keeps closed components without any data term
// positive definite.
bool solve(const std::vector<EdgeLink>& links, const std::vector<int>& state,
           const std::vector<double>& area, const std::vector<double>& data_weight,
           const std::vector<Complex>& target, double shift, std::vector<Complex>* value) {
  const int n = static_cast<int>(state.size());
  std::vector<int> unknown(n, -1);
  int count = 0;
  for (int i = 0; i < n; ++i)
    if (state[i] == kFree) unknown[i] = count++;
  if (count == 0) return true;
  std::vector<Eigen::Triplet<Complex>> triplets;
  triplets.reserve(4 * links.size() + count);
  Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(count);
  for (const auto& link : links) {
    const int sf = state[link.f], sg = state[link.g];
    if (sf == kExcluded || sg == kExcluded || (sf == kFixed && sg == kFixed)) continue;
    // E = w |u_g − r u_f|²: ∂/∂ū_g = w (u_g − r u_f), ∂/∂ū_f = w (u_f − r̄ u_g).
    if (sf == kFree) triplets.emplace_back(unknown[link.f], unknown[link.f], link.w);
    if (sg == kFree) triplets.emplace_back(unknown[link.g], unknown[link.g], link.w);
    if (sf == kFree && sg == kFree) {
      triplets.emplace_back(unknown[link.g], unknown[link.f], -link.w * link.r);
      triplets.emplace_back(unknown[link.f], unknown[link.g], -link.w * std::conj(link.r));
    } else if (sf == kFree) {
      rhs[unknown[link.f]] += link.w * std::conj(link.r) * (*value)[link.g];
    } else {
      rhs[unknown[link.g]] += link.w * link.r * (*value)[link.f];
    }
  }
  for (int i = 0; i < n; ++i) {
    if (state[i] != kFree) continue;
    triplets.emplace_back(unknown[i], unknown[i], data_weight[i] + shift * area[i]);
    rhs[unknown[i]] += data_weight[i] * target[i];
  }
  Eigen::SparseMatrix<Complex> matrix(count, count);
  matrix.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<Complex>> solver(matrix);
  if (solver.info() != Eigen::Success) return false;
  Eigen::VectorXcd u;
  if (rhs.norm() > 0) {
    u = solver.solve(rhs);
  } else {
    // Nothing drives the field (a closed component with alignment off): the smoothest
    // field, Knöppel's smallest eigenvector, by inverse iteration on the same factors.
    u = Eigen::VectorXcd::Ones(count);
    for (int iteration = 0; iteration < 20; ++iteration) {
      for (int i = 0; i < n; ++i)
        if (state[i] == kFree) u[unknown[i]] *= area[i];
      u = solver.solve(u);
      u /= u.norm();
    }
  }
  if (solver.info() != Eigen::Success || !u.allFinite()) return false;
  for (int i = 0; i < n; ++i)
    if (state[i] == kFree) (*value)[i] = u[unknown[i]];
  return true;
}

}  // namespace

void solve_component_field(const TriMesh& mesh, const Partition& partition,
                           const FaceFrames& frames, const ComponentInput& input,
                           const FieldOptions& options, double edge_length,
                           std::vector<double>* theta, CrossField* field) {
  const std::vector<int>& faces = input.faces;
  const std::vector<int>& position = *input.position;
  const int n = static_cast<int>(faces.size());
  auto in_component = [&](OpenMesh::FaceHandle f) {
    return f.is_valid() && partition.face_component[f.idx()] == input.component;
  };

  // Connection over the component's interior edges. Weight: the ratio of dual to primal
  // edge length, 3|e|²/(2(A_f + A_g)) (√3 on equilateral triangles), with the area floored
  // so slivers from the level-set extraction cannot dominate.
  std::vector<EdgeLink> links;
  std::vector<double> area(n);
  for (int i = 0; i < n; ++i) area[i] = frames.area[faces[i]];
  for (int i = 0; i < n; ++i) {
    for (auto h : mesh.fh_range(mesh.face_handle(faces[i]))) {
      const auto g = mesh.opposite_face_handle(h);
      if (!in_component(g) || g.idx() < faces[i]) continue;  // each edge once
      const int f = faces[i];
      const Vec3 e =
          point(mesh, mesh.to_vertex_handle(h)) - point(mesh, mesh.from_vertex_handle(h));
      const double w = 1.5 * e.squaredNorm() /
                       std::max(frames.area[f] + frames.area[g.idx()], 0.01 * e.squaredNorm());
      const double transport = frames.angle(g.idx(), e) - frames.angle(f, e);
      links.push_back({i, position[g.idx()], w, std::polar(1.0, 4 * transport)});
    }
  }

  // Ring 0: the fans of the loop vertices. In a fan unfolded around v (spoke v→next at
  // angle 0, spoke v→prev at the interior angle α), the loop tangent turns from 0 to α − π;
  // each face takes the tangent interpolated at its middle, the two faces on loop edges the
  // exact edge direction. A face in several fans takes the 4-RoSy mean.
  std::vector<Complex> value(n, Complex(0, 0));
  std::vector<int> state(n, kFree);
  for (const BoundaryLoop* loop : input.loops) {
    const int count = static_cast<int>(loop->vertices.size());
    for (int k = 0; k < count; ++k) {
      const auto v = mesh.vertex_handle(loop->vertices[k]);
      const BoundaryFan fan = boundary_fan(mesh, partition, input.component, v,
                                           mesh.vertex_handle(loop->vertices[(k + 1) % count]));
      for (size_t j = 0; j < fan.spokes.size(); ++j) {
        const int f = mesh.face_handle(fan.spokes[j]).idx();
        const Vec3 spoke = point(mesh, mesh.to_vertex_handle(fan.spokes[j])) - point(mesh, v);
        const double local = frames.angle(f, spoke) + fan.tangent[j] - fan.before[j];
        value[position[f]] += std::polar(1.0, 4 * local);
        state[position[f]] = kFixed;
      }
    }
  }
  int cancelled = 0;
  for (int i = 0; i < n; ++i) {
    if (state[i] != kFixed) continue;
    if (std::abs(value[i]) < 1e-9) {  // opposite tangents cancel: keep it fixed to any cross
      value[i] = Complex(1, 0);
      ++cancelled;
    }
    value[i] /= std::abs(value[i]);
  }
  if (cancelled > 0) {
    field->diagnostics.push_back("field: component " + std::to_string(input.component) + ": " +
                                 std::to_string(cancelled) +
                                 " boundary triangles with contradicting tangents");
  }

  // Channel: Dijkstra from ring 0 along face centres, up to the channel width.
  const double width = options.channel_width * edge_length;
  std::vector<double> distance(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  for (int i = 0; i < n; ++i)
    if (state[i] == kFixed) queue.push({distance[i] = 0, i});
  std::vector<std::vector<std::pair<int, double>>> neighbours(n);
  for (const auto& link : links) {
    const double d = (frames.centroid[faces[link.f]] - frames.centroid[faces[link.g]]).norm();
    neighbours[link.f].push_back({link.g, d});
    neighbours[link.g].push_back({link.f, d});
  }
  while (!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > distance[i]) continue;
    for (const auto& [j, step] : neighbours[i]) {
      if (d + step < distance[j] && d + step < width) queue.push({distance[j] = d + step, j});
    }
  }
  for (int i = 0; i < n; ++i)
    field->constraint[faces[i]] = state[i] == kFixed ? 1 : distance[i] < width ? 2 : 0;

  // Curvature alignment targets and confidence (all faces, for the report).
  std::vector<double> data_weight(n, 0.0);
  std::vector<Complex> target(n, Complex(0, 0));
  const double tau = options.anisotropy_threshold;
  for (int i = 0; i < n; ++i) {
    const int f = faces[i];
    const double k1 = field->kappa1[f], k2 = field->kappa2[f];
    const double relative =
        std::abs(k1 - k2) / (std::abs(k1) + std::abs(k2) + 1.0 / input.component_size);
    const double confidence = relative * relative / (relative * relative + tau * tau);
    field->alignment[f] = confidence;
    data_weight[i] = options.alignment_weight * confidence * area[i] / (edge_length * edge_length);
    const Vec3 d1 = field->principal1.row(f).transpose();
    target[i] = std::polar(1.0, 4 * frames.angle(f, d1));
  }

  // Pass 1: the channel alone, fixed on ring 0, free on its inner side, no alignment.
  const double shift = 1e-8 / (edge_length * edge_length);
  std::vector<int> channel_state(n);
  for (int i = 0; i < n; ++i)
    channel_state[i] = field->constraint[faces[i]] == 1   ? kFixed
                       : field->constraint[faces[i]] == 2 ? kFree
                                                          : kExcluded;
  const std::vector<double> no_weight(n, 0.0);
  bool ok = solve(links, channel_state, area, no_weight, target, shift, &value);
  // Pass 2: everything else, with the whole channel fixed.
  for (int i = 0; i < n; ++i) state[i] = field->constraint[faces[i]] == 0 ? kFree : kFixed;
  for (int i = 0; i < n; ++i)
    if (state[i] == kFixed && std::abs(value[i]) > 0) value[i] /= std::abs(value[i]);
  ok = ok && solve(links, state, area, data_weight, target, shift, &value);
  if (!ok) {
    throw Error(Code::StageFailure,
                "cross field solve failed on organic component " + std::to_string(input.component) +
                    " (" + std::to_string(n) + " triangles)",
                "field");
  }

  int vanishing = 0;
  double largest = 0;
  for (const auto& u : value) largest = std::max(largest, std::abs(u));
  for (int i = 0; i < n; ++i) {
    if (std::abs(value[i]) <= 1e-12 * largest) ++vanishing;
    (*theta)[faces[i]] = std::arg(value[i]) / 4;
  }
  if (vanishing > 0) {
    field->diagnostics.push_back("field: component " + std::to_string(input.component) + ": " +
                                 std::to_string(vanishing) + " triangles where the field vanishes");
  }
}

}  // namespace genbrep::field_detail
