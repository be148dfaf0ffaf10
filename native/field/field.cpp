// field/field.cpp — the stage's entry point: checks, per-component orchestration, debug OBJ.
// The order follows §6.1–6.2: curvature on the whole design (so tensors near a loop see
// both sides), then per organic component the cross field and its singularities, then the
// size field, which needs the field's directions.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "field/detail/field_detail.h"

namespace genbrep {

using namespace field_detail;

int CrossField::index_sum(int component) const {
  int sum = 0;
  for (const auto& s : singularities) sum += s.component == component ? s.index : 0;
  return sum;
}

CrossField compute_field(const TriMesh& design, const Partition& partition,
                         const FieldOptions& options, const Context& context) {
  const int nf = static_cast<int>(design.n_faces());
  GENBREP_CHECK(static_cast<int>(partition.face_component.size()) == nf, Code::InvalidInput,
                "field: the partition has " + std::to_string(partition.face_component.size()) +
                    " triangles, the design " + std::to_string(nf));
  GENBREP_CHECK(options.density > 0 && options.target_quads > 0 && options.channel_width >= 0 &&
                    options.alignment_weight >= 0 && options.anisotropy_threshold > 0 &&
                    options.tolerance_fraction > 0 && options.tolerance_fraction < 1 &&
                    options.curvature_percentile > 0 && options.curvature_percentile <= 1,
                Code::InvalidInput, "field: an option is out of range (see FieldOptions)");
  for (int c : partition.face_component) {
    GENBREP_CHECK(c < partition.organic_components, Code::InvalidInput,
                  "field: face component " + std::to_string(c) + " out of range");
  }
  context.step("field", 0.0);

  CrossField field;
  const FaceFrames frames = face_frames(design);
  estimate_curvature(design, frames, options.curvature_smoothing, &field);
  field.direction = FaceVectors::Zero(nf, 3);
  field.alignment = Eigen::VectorXd::Zero(nf);
  field.constraint.assign(nf, -1);
  if (frames.degenerate > 0) {
    field.diagnostics.push_back("field: " + std::to_string(frames.degenerate) +
                                " degenerate triangles took their normal from their neighbours");
  }
  context.step("field", 0.2);

  // Components: faces in ascending order, each face's position in its list, loops.
  const int components = partition.organic_components;
  std::vector<ComponentInput> inputs(components);
  std::vector<int> position(nf, -1);
  std::vector<double> component_area(components, 0.0);
  double organic_area = 0;
  for (int f = 0; f < nf; ++f) {
    const int c = partition.face_component[f];
    if (c < 0) continue;
    position[f] = static_cast<int>(inputs[c].faces.size());
    inputs[c].faces.push_back(f);
    component_area[c] += frames.area[f];
    organic_area += frames.area[f];
  }
  for (const auto& loop : partition.loops) {
    GENBREP_CHECK(loop.component >= 0 && loop.component < components, Code::InvalidInput,
                  "field: a boundary loop names component " + std::to_string(loop.component));
    inputs[loop.component].loops.push_back(&loop);
  }
  for (int c = 0; c < components; ++c) {
    inputs[c].component = c;
    inputs[c].position = &position;
    inputs[c].component_size = std::sqrt(std::max(component_area[c], 1e-300));
  }

  // ℓ: the coarsest cage edge; also the length scale of the alignment term and the channel.
  const double derived = std::sqrt(organic_area / options.target_quads);
  const double edge_length =
      (options.target_edge_length > 0 ? options.target_edge_length : derived) / options.density;

  std::vector<double> theta(nf, 0.0);
  for (int c = 0; c < components; ++c) {
    if (inputs[c].faces.empty() || edge_length <= 0) continue;
    solve_component_field(design, partition, frames, inputs[c], options, edge_length, &theta,
                          &field);
    find_singularities(design, partition, frames, inputs[c], theta, &field);
    for (int f : inputs[c].faces)
      field.direction.row(f) = frames.direction(f, theta[f]).transpose();
    context.step("field", 0.2 + 0.7 * (c + 1) / components);
  }
  std::sort(field.singularities.begin(), field.singularities.end(),
            [](const Singularity& a, const Singularity& b) {
              return std::make_pair(a.component, a.vertex) < std::make_pair(b.component, b.vertex);
            });

  compute_size_field(design, partition, options, edge_length, &field);
  std::ostringstream summary;
  summary << "field: " << components << " components, " << field.singularities.size()
          << " singularities, target edge " << field.target_edge_length << ", min edge "
          << field.min_edge_length << ", tolerance " << field.tolerance << " (kappa_max "
          << field.kappa_max << ")";
  field.notes.push_back(summary.str());
  context.step("field", 1.0);
  return field;
}

void write_field_obj(const std::string& path, const TriMesh& design, const CrossField& field) {
  std::ofstream out(path);
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "field");
  out.precision(9);
  out << "# genbrep cross field: a cross per organic face, singular vertices as points\n";
  auto vertex = [&](const Vec3& p) {
    out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  };
  int written = 0;
  out << "g cross\n";
  for (int f = 0; f < static_cast<int>(design.n_faces()); ++f) {
    const Vec3 d1 = field.direction.row(f).transpose();
    if (d1.squaredNorm() == 0) continue;  // incident face
    Vec3 corner[3];
    int k = 0;
    for (auto v : design.fv_range(design.face_handle(f))) {
      const auto& p = design.point(v);
      corner[k++] = Vec3(p[0], p[1], p[2]);
    }
    const Vec3 centre = (corner[0] + corner[1] + corner[2]) / 3.0;
    const Vec3 normal = (corner[1] - corner[0]).cross(corner[2] - corner[0]).normalized();
    const double arm = 0.4 *
                       ((corner[1] - corner[0]).norm() + (corner[2] - corner[1]).norm() +
                        (corner[0] - corner[2]).norm()) /
                       3.0;
    const Vec3 d2 = normal.allFinite() ? normal.cross(d1) : Vec3::Zero();
    for (const Vec3& d : {d1, d2}) {
      vertex(centre - arm * d);
      vertex(centre + arm * d);
      out << "l " << written + 1 << ' ' << written + 2 << '\n';
      written += 2;
    }
  }
  for (int sign : {+1, -1}) {
    out << (sign > 0 ? "g singularities_positive\n" : "g singularities_negative\n");
    for (const auto& s : field.singularities) {
      if ((s.index > 0) != (sign > 0)) continue;
      const auto& p = design.point(design.vertex_handle(s.vertex));
      vertex(Vec3(p[0], p[1], p[2]));
      out << "p " << ++written << '\n';
    }
  }
  if (!out) throw Error(Code::FileError, "failed writing '" + path + "'", "field");
}

}  // namespace genbrep
