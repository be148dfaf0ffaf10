// relax/remesh.cpp — step (a) of §5.3: isotropic remeshing of the boundary channel.
// CGAL's remesher (Botsch & Kobbelt 2004: split, collapse, flip, tangential relaxation,
// projection) runs on the channel's triangles only; triangles just outside are split
// where a channel border edge is, so the mesh stays conforming. The partition label is
// the face patch: an edge between two labels is a constraint, which CGAL may split or
// collapse and whose vertices slide along it (relax_constraints), so a label border
// stays a chain of edges and the loops keep their place while their sampling evens out.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <string>

#include "core/error.h"
#include "relax/detail/relax_detail.h"

namespace genbrep::relax_detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

}  // namespace

LabelledMesh remesh_channel(const TriangleMesh& input, const std::vector<int>& labels,
                            const std::vector<char>& in_channel, double target_edge_length,
                            int iterations, const SurfaceProjector& projector) {
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vertex(static_cast<size_t>(input.vertices.rows()));
  for (Eigen::Index v = 0; v < input.vertices.rows(); ++v) {
    vertex[v] =
        mesh.add_vertex(Point(input.vertices(v, 0), input.vertices(v, 1), input.vertices(v, 2)));
  }
  auto label = mesh.add_property_map<Mesh::Face_index, int>("f:label", -1).first;
  std::vector<Mesh::Face_index> channel;
  for (Eigen::Index t = 0; t < input.triangles.rows(); ++t) {
    const auto f = mesh.add_face(vertex[input.triangles(t, 0)], vertex[input.triangles(t, 1)],
                                 vertex[input.triangles(t, 2)]);
    GENBREP_CHECK(f != Mesh::null_face(), Code::Internal,
                  "relax: the remesher rejected triangle " + std::to_string(t));
    label[f] = labels[t];
    if (in_channel[t]) channel.push_back(f);
  }

  // Interior vertices are projected onto the original design (not onto the channel as
  // CGAL would by default), so repeated iterations never drift off the design surface.
  const auto project = [&](Mesh::Vertex_index v) {
    const Point& p = mesh.point(v);
    const Vec3 q = projector.nearest(Vec3(p.x(), p.y(), p.z())).point;
    return Point(q.x(), q.y(), q.z());
  };
  PMP::isotropic_remeshing(
      channel, target_edge_length, mesh,
      PMP::parameters::number_of_iterations(static_cast<unsigned int>(iterations))
          .face_patch_map(label)
          .protect_constraints(false)
          .collapse_constraints(true)
          .relax_constraints(true)
          .projection_functor(project));
  mesh.collect_garbage();

  LabelledMesh out;
  out.mesh.vertices.resize(static_cast<Eigen::Index>(mesh.number_of_vertices()), 3);
  for (const auto v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    out.mesh.vertices.row(static_cast<Eigen::Index>(v.idx())) << p.x(), p.y(), p.z();
  }
  out.mesh.triangles.resize(static_cast<Eigen::Index>(mesh.number_of_faces()), 3);
  out.labels.reserve(mesh.number_of_faces());
  for (const auto f : mesh.faces()) {
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      GENBREP_CHECK(k < 3, Code::Internal, "relax: the remesher made a non-triangle");
      out.mesh.triangles(static_cast<Eigen::Index>(f.idx()), k++) = static_cast<int>(v.idx());
    }
    out.labels.push_back(label[f]);
  }
  return out;
}

}  // namespace genbrep::relax_detail
