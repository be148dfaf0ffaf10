// relax/relax.cpp — §5.3 driver: labels, channel, remesh (a), smoothing (b), checks,
// provenance and loop statistics. Each step's result is checked against the stage's
// guarantees and dropped (with a diagnostic) if it breaks one.
#include "relax/relax.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>

#include "mesh/mesh.h"
#include "relax/detail/relax_detail.h"

namespace genbrep {
namespace {

using namespace relax_detail;
constexpr const char* kStage = "relax";

Vec3 point(const TriangleMesh& mesh, int v) { return mesh.vertices.row(v); }

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

double typical_edge_length(const TriangleMesh& mesh) {
  std::vector<double> lengths;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      lengths.push_back(
          (point(mesh, mesh.triangles(t, k)) - point(mesh, mesh.triangles(t, (k + 1) % 3))).norm());
    }
  }
  return median(std::move(lengths));
}

// Distinct triangle incidences I(T) as small integers (the remesher's patch ids); the
// empty set (organic) is one of them. Numbered in the sets' sorted order.
struct Labels {
  std::vector<std::vector<int>> sets;
  std::vector<int> of_face;
};

Labels label_faces(const Partition& partition) {
  std::map<std::vector<int>, int> ids;
  const size_t n = partition.face_solid.size();
  std::vector<std::vector<int>> face_sets(n);
  for (size_t f = 0; f < n; ++f) {
    face_sets[f].assign(partition.face_solids.begin() + partition.face_offsets[f],
                        partition.face_solids.begin() + partition.face_offsets[f + 1]);
    ids.emplace(face_sets[f], 0);
  }
  Labels out;
  for (auto& [set, id] : ids) {
    id = static_cast<int>(out.sets.size());
    out.sets.push_back(set);
  }
  for (const auto& set : face_sets) out.of_face.push_back(ids.at(set));
  return out;
}

Partition retrace(const TriangleMesh& mesh, const Labels& labels,
                  const std::vector<int>& face_label, int solid_count, const Context& context) {
  std::vector<std::vector<int>> sets;
  sets.reserve(face_label.size());
  for (int label : face_label) sets.push_back(labels.sets[label]);
  return partition_faces(to_trimesh(mesh), std::move(sets), solid_count, {}, context);
}

double organic_area(const TriangleMesh& mesh, const Partition& partition) {
  double area = 0;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    if (partition.face_solid[t] >= 0) continue;
    const Vec3 a = point(mesh, mesh.triangles(t, 0)), b = point(mesh, mesh.triangles(t, 1)),
               c = point(mesh, mesh.triangles(t, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

TriangleMesh to_arrays(const TriMesh& mesh) {
  TriangleMesh out;
  out.vertices.resize(static_cast<Eigen::Index>(mesh.n_vertices()), 3);
  for (const auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    out.vertices.row(v.idx()) << p[0], p[1], p[2];
  }
  out.triangles.resize(static_cast<Eigen::Index>(mesh.n_faces()), 3);
  for (const auto f : mesh.faces()) {
    int k = 0;
    for (const auto v : mesh.fv_range(f)) out.triangles(f.idx(), k++) = v.idx();
  }
  return out;
}

// Finds the design's triangles in a new mesh by their corners' exact coordinates: the
// triangles the relaxation did not touch, which need no checks and keep their identity.
class OriginalTriangles {
 public:
  explicit OriginalTriangles(const TriangleMesh& design) {
    for (Eigen::Index v = 0; v < design.vertices.rows(); ++v) {
      vertex_.emplace(key(design.vertices.row(v)), static_cast<int>(v));
    }
    for (Eigen::Index t = 0; t < design.triangles.rows(); ++t) {
      triangle_.emplace(
          corners(design.triangles(t, 0), design.triangles(t, 1), design.triangles(t, 2)),
          static_cast<int>(t));
    }
  }
  // Per triangle of `mesh`, the design triangle with the same corners (same orientation), or -1.
  std::vector<int> find(const TriangleMesh& mesh) const {
    std::vector<int> design_vertex(static_cast<size_t>(mesh.vertices.rows()), -1);
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
      const auto it = vertex_.find(key(mesh.vertices.row(v)));
      if (it != vertex_.end()) design_vertex[v] = it->second;
    }
    std::vector<int> out(static_cast<size_t>(mesh.triangles.rows()), -1);
    for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
      const int a = design_vertex[mesh.triangles(t, 0)], b = design_vertex[mesh.triangles(t, 1)],
                c = design_vertex[mesh.triangles(t, 2)];
      if (a < 0 || b < 0 || c < 0) continue;
      const auto it = triangle_.find(corners(a, b, c));
      if (it != triangle_.end()) out[t] = it->second;
    }
    return out;
  }

 private:
  static std::array<double, 3> key(const Vec3& p) { return {p.x(), p.y(), p.z()}; }
  // Rotated so the smallest index comes first: keeps the orientation.
  static std::array<int, 3> corners(int a, int b, int c) {
    if (b < a && b < c) return {b, c, a};
    if (c < a && c < b) return {c, a, b};
    return {a, b, c};
  }
  std::map<std::array<double, 3>, int> vertex_;
  std::map<std::array<int, 3>, int> triangle_;
};

// The stage's guarantees on a candidate; empty if all hold, else what broke. `origin`
// marks the untouched design triangles (>= 0), which cannot face against the design.
std::string broken_guarantee(const TriangleMesh& mesh, const Partition& candidate,
                             const Partition& reference, const SurfaceProjector& projector,
                             const std::vector<int>& origin) {
  const MeshValidation validation = validate(mesh);
  if (!validation.closed_manifold()) return validation.problems();
  if (candidate.organic_components != reference.organic_components ||
      candidate.loops.size() != reference.loops.size() || candidate.repaired_vertices > 0) {
    return std::to_string(candidate.organic_components) + " organic components and " +
           std::to_string(candidate.loops.size()) + " loops instead of " +
           std::to_string(reference.organic_components) + " and " +
           std::to_string(reference.loops.size());
  }
  int flipped = 0;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    if (origin[t] >= 0) continue;
    const double agreement =
        normal_agreement(point(mesh, mesh.triangles(t, 0)), point(mesh, mesh.triangles(t, 1)),
                         point(mesh, mesh.triangles(t, 2)), projector)
            .centroid;
    flipped += agreement > -2 && agreement <= 0;
  }
  if (flipped > 0) return std::to_string(flipped) + " triangles facing against the design";
  return {};
}

// Fills the result from the final mesh and labels: provenance (the design triangle
// nearest to each new triangle's centroid, or itself if untouched), the retraced
// partition, the organic area, and per loop the original loop most of its vertices are
// nearest to, both shapes and the displacement.
void finish(const TriangleMesh& design, const Partition& partition, const Labels& labels,
            const TriangleMesh& current, const std::vector<int>& current_labels,
            const SurfaceProjector& projector, const OriginalTriangles& originals,
            const PolylineDistance& original, const Context& context, Relaxed* out) {
  const int solid_count = static_cast<int>(partition.solid_faces.size());
  out->triangle_origin.clear();
  out->loops.clear();
  out->max_displacement = 0;
  out->design = current;
  out->design.triangle_source.resize(static_cast<size_t>(current.triangles.rows()));
  const std::vector<int> untouched = originals.find(current);
  for (Eigen::Index t = 0; t < current.triangles.rows(); ++t) {
    const Vec3 centroid =
        (point(current, current.triangles(t, 0)) + point(current, current.triangles(t, 1)) +
         point(current, current.triangles(t, 2))) /
        3.0;
    const int origin = untouched[t] >= 0 ? untouched[t] : projector.nearest(centroid).triangle;
    out->triangle_origin.push_back(origin);
    out->design.triangle_source[t] =
        design.triangle_source.empty() ? origin : design.triangle_source[origin];
  }
  out->partition = retrace(current, labels, current_labels, solid_count, context);
  out->organic_area_after = organic_area(current, out->partition);

  const TriMesh input = to_trimesh(design), result = to_trimesh(current);
  for (const auto& loop : out->partition.loops) {
    LoopRelaxation stats;
    std::vector<int> votes(partition.loops.size(), 0);
    for (int v : loop.vertices) {
      const auto hit = original.nearest(point(current, v));
      if (hit.tag >= 0) ++votes[hit.tag];
      stats.max_displacement = std::max(stats.max_displacement, hit.distance);
    }
    stats.original_loop =
        static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
    stats.before = loop_shape(input, partition.loops[stats.original_loop].vertices);
    stats.after = loop_shape(result, loop.vertices);
    out->max_displacement = std::max(out->max_displacement, stats.max_displacement);
    out->loops.push_back(stats);
  }
}

}  // namespace

LoopShape loop_shape(const TriMesh& mesh, const std::vector<int>& loop) {
  LoopShape shape;
  const int n = static_cast<int>(loop.size());
  shape.vertices = n;
  if (n < 3) return shape;
  const auto position = [&](int i) {
    const auto& p = mesh.point(mesh.vertex_handle(loop[(i % n + n) % n]));
    return Vec3(p[0], p[1], p[2]);
  };
  std::vector<double> lengths;
  for (int i = 0; i < n; ++i) lengths.push_back((position(i + 1) - position(i)).norm());
  double sum = 0, sum_sq = 0;
  for (double l : lengths) sum += l, sum_sq += l * l;
  shape.mean_edge_length = sum / n;
  const double variance =
      std::max(0.0, sum_sq / n - shape.mean_edge_length * shape.mean_edge_length);
  shape.edge_length_cv =
      shape.mean_edge_length > 0 ? std::sqrt(variance) / shape.mean_edge_length : 0;
  double turning = 0;
  for (int i = 0; i < n; ++i) {
    // Tangent plane at the vertex: its area-weighted normal.
    Vec3 normal = Vec3::Zero();
    for (const auto f : mesh.vf_range(mesh.vertex_handle(loop[i]))) {
      Vec3 c[3];
      int k = 0;
      for (const auto w : mesh.fv_range(f)) {
        const auto& p = mesh.point(w);
        c[k++] = Vec3(p[0], p[1], p[2]);
      }
      normal += (c[1] - c[0]).cross(c[2] - c[0]);
    }
    if (normal.squaredNorm() > 0) normal.normalize();
    Vec3 in = position(i) - position(i - 1), out = position(i + 1) - position(i);
    in -= normal * normal.dot(in);
    out -= normal * normal.dot(out);
    const double angle = std::atan2(in.cross(out).norm(), in.dot(out));
    turning += angle;
    shape.max_turning_angle = std::max(shape.max_turning_angle, angle);
  }
  shape.mean_turning_angle = turning / n;
  return shape;
}

Relaxed relax(const TriangleMesh& design, const Partition& partition, const RelaxOptions& options,
              const Context& context) {
  const int n_faces = static_cast<int>(design.triangles.rows());
  GENBREP_CHECK(static_cast<int>(partition.face_solid.size()) == n_faces, Code::Internal,
                "relax: partition of " + std::to_string(partition.face_solid.size()) +
                    " triangles for a design of " + std::to_string(n_faces));
  const MeshValidation validation = validate(design);
  GENBREP_CHECK(validation.closed_manifold(), Code::InvalidInput,
                "relax: the design is not a closed 2-manifold: " + validation.problems());
  const int solid_count = static_cast<int>(partition.solid_faces.size());

  Relaxed out;
  out.tolerance = options.tolerance > 0 ? options.tolerance : typical_edge_length(design);
  const TriMesh input = to_trimesh(design);
  const Labels labels = label_faces(partition);
  const SurfaceProjector projector(design);
  const OriginalTriangles originals(design);
  std::vector<PolylineDistance::Segment> segments;
  std::vector<double> boundary_lengths;
  std::vector<int> loop_vertices;
  for (size_t l = 0; l < partition.loops.size(); ++l) {
    const auto& loop = partition.loops[l].vertices;
    for (size_t i = 0; i < loop.size(); ++i) {
      segments.push_back({point(design, loop[i]), point(design, loop[(i + 1) % loop.size()]),
                          static_cast<int>(l)});
      boundary_lengths.push_back((segments.back().b - segments.back().a).norm());
    }
    loop_vertices.insert(loop_vertices.end(), loop.begin(), loop.end());
  }
  const PolylineDistance original(std::move(segments));
  out.target_edge_length =
      options.target_edge_length > 0 ? options.target_edge_length : median(boundary_lengths);
  out.organic_area_before = organic_area(design, partition);
  context.step(kStage, 0.1);

  TriangleMesh current = design;
  current.triangle_source.clear();
  std::vector<int> current_labels = labels.of_face;

  // (a) Channel remesh: the triangles within channel_rings rings of the loop vertices.
  if (!partition.loops.empty() && options.remesh_iterations > 0 && out.target_edge_length > 0) {
    const std::vector<char> near =
        vertex_rings(input, loop_vertices, std::max(0, options.channel_rings - 1));
    std::vector<char> in_channel(static_cast<size_t>(n_faces), 0);
    for (const auto f : input.faces()) {
      for (const auto v : input.fv_range(f)) in_channel[f.idx()] |= near[v.idx()];
      out.channel_triangles += in_channel[f.idx()];
    }
    std::string problem;
    try {
      LabelledMesh remeshed =
          remesh_channel(design, labels.of_face, in_channel, out.target_edge_length,
                         options.remesh_iterations, projector);
      // Vertices CGAL slid along a label border sit on a chord: put them on the surface.
      for (Eigen::Index v = 0; v < remeshed.mesh.vertices.rows(); ++v) {
        remeshed.mesh.vertices.row(v) =
            projector.nearest(point(remeshed.mesh, static_cast<int>(v))).point;
      }
      TriMesh unfolded = to_trimesh(remeshed.mesh);
      const FoldRepair folds =
          repair_folds(unfolded, remeshed.labels, originals.find(remeshed.mesh), projector);
      remeshed.mesh = to_arrays(unfolded);
      if (folds.folded > 0) {
        (folds.remaining ? out.diagnostics : out.notes).push_back("channel remesh: unfolded " +
                                  std::to_string(folds.folded - folds.remaining) + " of " +
                                  std::to_string(folds.folded) + " folded triangles");
      }
      const Partition candidate =
          retrace(remeshed.mesh, labels, remeshed.labels, solid_count, context);
      problem = broken_guarantee(remeshed.mesh, candidate, partition, projector,
                                 originals.find(remeshed.mesh));
      if (problem.empty()) {
        current = std::move(remeshed.mesh);
        current_labels = std::move(remeshed.labels);
        out.remeshed = true;
      }
    } catch (const Error& error) {
      if (error.code() == Code::Cancelled) throw;
      problem = error.what();
    } catch (const std::exception& error) {  // a CGAL precondition or assertion
      problem = error.what();
    }
    if (!problem.empty()) out.diagnostics.push_back("channel remesh undone: " + problem);
  }
  context.step(kStage, 0.5);

  // (b) Curve smoothing on the (remeshed) design; connectivity stays, positions move.
  if (!partition.loops.empty() && options.smoothing_iterations > 0) {
    TriMesh mesh = to_trimesh(current);
    const Partition before = retrace(current, labels, current_labels, solid_count, context);
    const double area_before = organic_area(current, before);
    const Smoothing smoothing = smooth_loops(mesh, current_labels, before.loops, projector,
                                             original, out.tolerance, options, context);
    const TriangleMesh smoothed = to_arrays(mesh);
    const Partition candidate = retrace(smoothed, labels, current_labels, solid_count, context);
    std::string problem =
        broken_guarantee(smoothed, candidate, partition, projector, originals.find(smoothed));
    const double area_after = organic_area(smoothed, candidate);
    if (problem.empty() && area_after < (1 - options.max_area_loss) * area_before) {
      std::ostringstream message;
      message << "the organic area would shrink from " << area_before << " to " << area_after;
      problem = message.str();
    }
    if (problem.empty()) {
      current = smoothed;
      out.skipped_moves = smoothing.skipped_moves;
      if (smoothing.skipped_moves > 0) {
        out.notes.push_back(
            std::to_string(smoothing.skipped_moves) + " of " +
            std::to_string(smoothing.skipped_moves + smoothing.accepted_moves) +
            " loop smoothing moves skipped (a flip, or beyond d)");
      }
      if (smoothing.fixed_vertices > 0) {
        out.notes.push_back(std::to_string(smoothing.fixed_vertices) +
                            " loop vertices kept in place where label borders meet");
      }
    } else {
      out.diagnostics.push_back("loop smoothing undone: " + problem);
    }
  }

  finish(design, partition, labels, current, current_labels, projector, originals, original,
         context, &out);
  if (out.max_displacement > out.tolerance * (1 + 1e-9)) {
    out.diagnostics.push_back("relaxation undone: a loop vertex would move " +
                              std::to_string(out.max_displacement) +
                              " > d = " + std::to_string(out.tolerance));
    out.remeshed = false;
    out.skipped_moves = 0;
    finish(design, partition, labels, design, labels.of_face, projector, originals, original,
           context, &out);
  }
  context.step(kStage, 1.0);
  return out;
}

}  // namespace genbrep
