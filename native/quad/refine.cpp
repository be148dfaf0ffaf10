// quad/refine.cpp — a finer copy of the design for tracing one component (quad/quad.h,
// step 0). Separatrices follow mesh edges, so the layout can only be as fine as the mesh:
// level-set designs have one voxel per edge and ask for cage edges of one to two voxels,
// which leaves a trace two mesh edges per cage edge to turn in (zigzag arcs, separatrices
// that cannot leave a crowded singularity, sliver patches). Splitting the component's
// edges gives the trace room without moving the surface.
// Method: first, around every interior singularity of the component (those the layout will
// not trace, cancelled pairs and ones beside a loop, too), the edges across its
// triangles are split (each split adds an edge at the singular vertex) until it has two
// edges per separatrix: a separatrix leaves along one mesh edge, midpoint splits keep
// every old vertex's valence, and a level-set vertex has about six edges, so a valence-5
// singularity's five directions can meet fewer distinct edges than separatrices, and a
// separatrix that cannot leave leaves an irregular vertex. Then every edge with the
// component on both sides is split at its midpoint, `levels` times. A triangle with three
// split edges becomes four, with two becomes three (the quadrilateral left cut along its
// shorter diagonal), with one becomes two. Edges on the component's loops and elsewhere
// in the design are not split, so the loops, the other components and the solids keep
// their vertices and triangles.
// Carried over: vertices keep their indices (midpoints are appended); triangle t keeps index
// t for its first child (others are appended) and every child copies its parent's per-face
// data: partition labels and component, and the field's direction, sizes and curvature.
// Singularities stay on their vertices (the field is constant on a parent's children, so
// no new ones arise). The surface is the same point set: midpoints of flat triangles.
// Complexity: O(F) per level; each level multiplies the component's triangles by about 4
// (the splits round singular vertices add little).
#include <array>
#include <map>
#include <vector>

#include "mesh/mesh.h"
#include "quad/detail/surface.h"

namespace genbrep::quad_detail {

namespace {

// Mesh edges wanted at a singular vertex per separatrix, and the rounds of splits at most
// (a vertex of 4 edges with 5 separatrices: 8, then 16).
constexpr int kSingularEdgesPerSeparatrix = 2;
constexpr int kSingularSplitRounds = 2;

// Appends a copy of row parent[k] for every k (left alone if it is not a per-face array).
template <typename Rows>
void append_rows(Rows& rows, const std::vector<int>& parent, Eigen::Index faces) {
  const Eigen::Index old = rows.rows();
  if (old != faces) return;
  rows.conservativeResize(old + static_cast<Eigen::Index>(parent.size()), Eigen::NoChange);
  for (size_t k = 0; k < parent.size(); ++k) rows.row(old + k) = rows.row(parent[k]);
}

// The component's interior edges (both sides in it) of `mesh`.
std::vector<char> interior_edges(const TriMesh& mesh, const Partition& partition, int component) {
  std::vector<char> split(mesh.n_edges(), 0);
  for (auto e : mesh.edges()) {
    const auto f0 = mesh.face_handle(mesh.halfedge_handle(e, 0));
    const auto f1 = mesh.face_handle(mesh.halfedge_handle(e, 1));
    split[e.idx()] = f0.is_valid() && f1.is_valid() &&
                     partition.face_component[f0.idx()] == component &&
                     partition.face_component[f1.idx()] == component;
  }
  return split;
}

// Splits the edges of `mesh` marked in `split` (at their midpoints) into `out`.
void refine_once(const TriMesh& mesh, const Partition& partition, const CrossField& in_field,
                 const std::vector<char>& split_edge, RefinedDesign* out) {
  const int nv = static_cast<int>(mesh.n_vertices()), nf = static_cast<int>(mesh.n_faces());
  TriangleMesh soup;
  std::vector<Vec3> points(nv);
  for (int v = 0; v < nv; ++v) {
    const auto p = mesh.point(mesh.vertex_handle(v));
    points[v] = Vec3(p[0], p[1], p[2]);
  }
  // Midpoint vertex per split edge.
  std::vector<int> midpoint(mesh.n_edges(), -1);
  for (auto e : mesh.edges()) {
    if (!split_edge[e.idx()]) continue;
    const auto h0 = mesh.halfedge_handle(e, 0);
    midpoint[e.idx()] = static_cast<int>(points.size());
    points.push_back(0.5 * (points[mesh.from_vertex_handle(h0).idx()] +
                            points[mesh.to_vertex_handle(h0).idx()]));
  }
  std::vector<std::array<int, 3>> first(nf), extra;
  std::vector<int> parent;  // of each extra triangle
  for (int f = 0; f < nf; ++f) {
    // Corners c[k] and the midpoint m[k] of edge c[k]–c[k+1] (-1: not split).
    int c[3], m[3], k = 0;
    for (auto h : mesh.fh_range(mesh.face_handle(f))) {
      c[k] = mesh.from_vertex_handle(h).idx();
      m[k] = midpoint[mesh.edge_handle(h).idx()];
      ++k;
    }
    std::vector<std::array<int, 3>> children;
    const int split = (m[0] >= 0) + (m[1] >= 0) + (m[2] >= 0);
    if (split == 0) {
      children.push_back({c[0], c[1], c[2]});
    } else if (split == 3) {
      children = {{m[0], m[1], m[2]}, {c[0], m[0], m[2]}, {m[0], c[1], m[1]}, {m[2], m[1], c[2]}};
    } else {
      // Rotate so that edge 0 is split (and, with two, edge 1 too: edge 2 is the whole one).
      int r = 0;
      while (!(m[r] >= 0 && (split == 1 || m[(r + 1) % 3] >= 0))) ++r;
      const int a = c[r], b = c[(r + 1) % 3], d = c[(r + 2) % 3];
      const int mab = m[r], mbd = m[(r + 1) % 3];
      if (split == 1) {
        children = {{a, mab, d}, {mab, b, d}};
      } else {
        // Corner triangle at b, and the quadrilateral a, mab, mbd, d cut along its shorter
        // diagonal.
        children.push_back({mab, b, mbd});
        if ((points[a] - points[mbd]).squaredNorm() <= (points[mab] - points[d]).squaredNorm())
          children.insert(children.end(), {{a, mab, mbd}, {a, mbd, d}});
        else
          children.insert(children.end(), {{a, mab, d}, {mab, mbd, d}});
      }
    }
    first[f] = children[0];
    for (size_t j = 1; j < children.size(); ++j) extra.push_back(children[j]), parent.push_back(f);
  }
  soup.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t v = 0; v < points.size(); ++v) soup.vertices.row(v) = points[v].transpose();
  soup.triangles.resize(nf + static_cast<Eigen::Index>(extra.size()), 3);
  for (int f = 0; f < nf; ++f)
    for (int j = 0; j < 3; ++j) soup.triangles(f, j) = first[f][j];
  for (size_t t = 0; t < extra.size(); ++t)
    for (int j = 0; j < 3; ++j) soup.triangles(nf + t, j) = extra[t][j];
  out->mesh = to_trimesh(soup);

  // Partition: labels and component of the parent; loops, solids' faces and counts as they were.
  out->partition = partition;
  Partition& p = out->partition;
  for (int f : parent) {
    const int begin = p.face_offsets[f], end = p.face_offsets[f + 1];
    for (int i = begin; i < end; ++i) p.face_solids.push_back(p.face_solids[i]);
    p.face_offsets.push_back(static_cast<int>(p.face_solids.size()));
    p.face_solid.push_back(p.face_solid[f]);
    p.face_component.push_back(p.face_component[f]);
  }
  // Field: every per-face row of the parent.
  out->field = in_field;
  CrossField& field = out->field;
  append_rows(field.direction, parent, nf);
  append_rows(field.principal1, parent, nf);
  append_rows(field.principal2, parent, nf);
  append_rows(field.kappa1, parent, nf);
  append_rows(field.kappa2, parent, nf);
  append_rows(field.alignment, parent, nf);
  append_rows(field.size_u, parent, nf);
  append_rows(field.size_v, parent, nf);
  if (field.constraint.size() == static_cast<size_t>(nf))
    for (int f : parent) field.constraint.push_back(field.constraint[f]);
}

}  // namespace

RefinedDesign refine_component(const TriMesh& design, const Partition& partition,
                               const CrossField& field, int component, int levels) {
  GENBREP_CHECK(levels >= 0, Code::Internal, "quad: refine_component needs levels >= 0");
  // The first level reads the design itself; no copy of it is made.
  RefinedDesign refined;
  bool copied = false;  // refined holds the design as split so far (else: the design itself)
  auto mesh = [&]() -> const TriMesh& { return copied ? refined.mesh : design; };
  auto parts = [&]() -> const Partition& { return copied ? refined.partition : partition; };
  auto cross = [&]() -> const CrossField& { return copied ? refined.field : field; };
  // Around the interior singularities first (each round doubles a singular vertex's edges),
  // on the coarse design: the levels below keep those edges and split the new triangles.
  for (int round = 0; round < kSingularSplitRounds; ++round) {
    const std::vector<char> interior = interior_edges(mesh(), parts(), component);
    std::vector<char> split(interior.size(), 0);
    bool any = false;
    for (const Singularity& sing : cross().singularities) {
      if (sing.component != component || sing.on_boundary || sing.index >= 4) continue;
      const auto vh = mesh().vertex_handle(sing.vertex);
      if (static_cast<int>(mesh().valence(vh)) >= kSingularEdgesPerSeparatrix * (4 - sing.index))
        continue;
      for (auto h : mesh().voh_range(vh)) {
        if (!mesh().face_handle(h).is_valid()) continue;
        const int across = mesh().edge_handle(mesh().next_halfedge_handle(h)).idx();
        if (interior[across]) split[across] = 1, any = true;
      }
    }
    if (!any) break;
    RefinedDesign next;
    refine_once(mesh(), parts(), cross(), split, &next);
    refined = std::move(next);
    copied = true;
  }
  for (int level = 0; level < levels; ++level) {
    RefinedDesign next;
    refine_once(mesh(), parts(), cross(), interior_edges(mesh(), parts(), component), &next);
    next.levels = level + 1;
    refined = std::move(next);
    copied = true;
  }
  return refined;  // as constructed (no faces) where nothing was split
}

}  // namespace genbrep::quad_detail
