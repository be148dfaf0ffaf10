// partition/partition.cpp — T = C ⊔ O, §5.1 repair, components (§4.3), loops (§5.2).
#include <algorithm>
#include <deque>

#include "partition/partition.h"

namespace genbrep {
namespace {

constexpr const char* kStage = "partition";

// A boundary edge separates an organic triangle from an incident one (M is closed, so
// every edge has two triangles).
bool is_boundary(const TriMesh& mesh, const std::vector<char>& organic, TriMesh::EdgeHandle e) {
  const auto f0 = mesh.face_handle(mesh.halfedge_handle(e, 0));
  const auto f1 = mesh.face_handle(mesh.halfedge_handle(e, 1));
  return organic[f0.idx()] != organic[f1.idx()];
}

// §5.1: vertices with more than two boundary edges, ascending.
std::vector<int> non_manifold_boundary_vertices(const TriMesh& mesh,
                                                const std::vector<char>& organic) {
  std::vector<int> count(mesh.n_vertices(), 0);
  for (const auto e : mesh.edges()) {
    if (!is_boundary(mesh, organic, e)) continue;
    const auto h = mesh.halfedge_handle(e, 0);
    ++count[mesh.from_vertex_handle(h).idx()];
    ++count[mesh.to_vertex_handle(h).idx()];
  }
  std::vector<int> out;
  for (size_t v = 0; v < count.size(); ++v) {
    if (count[v] > 2) out.push_back(static_cast<int>(v));
  }
  return out;
}

// The organic-side boundary halfedge leaving v: in an organic triangle, opposite an
// incident one. Unique once every boundary vertex is 2-manifold.
TriMesh::HalfedgeHandle outgoing_boundary(const TriMesh& mesh, const std::vector<char>& organic,
                                          TriMesh::VertexHandle v) {
  for (const auto h : mesh.voh_range(v)) {
    if (organic[mesh.face_handle(h).idx()] && !organic[mesh.opposite_face_handle(h).idx()]) return h;
  }
  return TriMesh::HalfedgeHandle();
}

}  // namespace

int Partition::organic_triangles() const {
  return static_cast<int>(std::count(face_solid.begin(), face_solid.end(), -1));
}

Partition partition(const TriMesh& mesh, const Incidence& incidence, int solid_count,
                    const PartitionOptions& options, const Context& context) {
  const int n_faces = static_cast<int>(mesh.n_faces());
  GENBREP_CHECK(incidence.vertex_count() == static_cast<int>(mesh.n_vertices()), Code::Internal,
                "incidence has " + std::to_string(incidence.vertex_count()) +
                    " vertices, the design " + std::to_string(mesh.n_vertices()));
  // §4.2: a triangle is incident iff all three vertices are; then I(T) is their union.
  std::vector<std::vector<int>> face_sets(static_cast<size_t>(n_faces));
  for (const auto f : mesh.faces()) {
    auto& set = face_sets[f.idx()];
    for (const auto v : mesh.fv_range(f)) {
      if (!incidence.incident(v.idx())) {
        set.clear();
        break;
      }
      set.insert(set.end(), incidence.solids.begin() + incidence.offsets[v.idx()],
                 incidence.solids.begin() + incidence.offsets[v.idx() + 1]);
    }
  }
  context.step(kStage, 0.2);
  return partition_faces(mesh, std::move(face_sets), solid_count, options, context);
}

Partition partition_faces(const TriMesh& mesh, std::vector<std::vector<int>> face_sets,
                          int solid_count, const PartitionOptions& options,
                          const Context& context) {
  const int n_faces = static_cast<int>(mesh.n_faces());
  GENBREP_CHECK(static_cast<int>(face_sets.size()) == n_faces, Code::Internal,
                "face labels for " + std::to_string(face_sets.size()) +
                    " triangles, the mesh has " + std::to_string(n_faces));
  Partition out;
  std::vector<char> organic(static_cast<size_t>(n_faces), 0);
  for (int f = 0; f < n_faces; ++f) {
    auto& set = face_sets[f];
    std::sort(set.begin(), set.end());
    set.erase(std::unique(set.begin(), set.end()), set.end());
    organic[f] = set.empty();
    for (int s : set) {
      GENBREP_CHECK(s >= 0 && s < solid_count, Code::Internal,
                    "triangle " + std::to_string(f) + " labelled with solid " + std::to_string(s) +
                        " of " + std::to_string(solid_count));
    }
  }

  // §5.1: reassign incident triangles around non-manifold boundary vertices to O until
  // every boundary vertex joins exactly two boundary edges.
  for (int round = 0;; ++round) {
    const std::vector<int> pinched = non_manifold_boundary_vertices(mesh, organic);
    if (pinched.empty()) break;
    GENBREP_CHECK(round < options.max_repair_rounds, Code::StageFailure,
                  "non-manifold boundary repair did not converge in " +
                      std::to_string(options.max_repair_rounds) + " rounds");
    for (int v : pinched) {
      for (const auto f : mesh.vf_range(mesh.vertex_handle(v))) {
        if (organic[f.idx()]) continue;
        organic[f.idx()] = 1;
        face_sets[f.idx()].clear();
        ++out.reassigned_triangles;
      }
    }
    out.repaired_vertices += static_cast<int>(pinched.size());
    ++out.repair_rounds;
    context.step(kStage, 0.2 + 0.3 * std::min(1.0, round / 10.0));
  }

  // Flat per-face results and C_i.
  out.face_solid.assign(static_cast<size_t>(n_faces), -1);
  out.face_component.assign(static_cast<size_t>(n_faces), -1);
  out.solid_faces.assign(static_cast<size_t>(solid_count), {});
  for (int f = 0; f < n_faces; ++f) {
    const auto& set = face_sets[f];
    out.face_solids.insert(out.face_solids.end(), set.begin(), set.end());
    out.face_offsets.push_back(static_cast<int>(out.face_solids.size()));
    if (!set.empty()) out.face_solid[f] = set.front();
    for (int s : set) out.solid_faces[s].push_back(f);
  }

  // §4.3: organic components by flood fill over edges, numbered by their lowest triangle.
  std::deque<int> queue;
  for (int seed = 0; seed < n_faces; ++seed) {
    if (!organic[seed] || out.face_component[seed] >= 0) continue;
    const int id = out.organic_components++;
    out.face_component[seed] = id;
    queue.push_back(seed);
    while (!queue.empty()) {
      const auto f = mesh.face_handle(queue.front());
      queue.pop_front();
      for (const auto g : mesh.ff_range(f)) {
        if (!organic[g.idx()] || out.face_component[g.idx()] >= 0) continue;
        out.face_component[g.idx()] = id;
        queue.push_back(g.idx());
      }
    }
  }
  context.step(kStage, 0.7);

  // §5.2: trace closed boundary curves from the lowest unvisited boundary halfedge.
  std::vector<char> visited(mesh.n_halfedges(), 0);
  for (const auto start : mesh.halfedges()) {
    if (visited[start.idx()] || !organic[mesh.face_handle(start).idx()] ||
        organic[mesh.opposite_face_handle(start).idx()]) {
      continue;
    }
    BoundaryLoop loop;
    loop.component = out.face_component[mesh.face_handle(start).idx()];
    TriMesh::HalfedgeHandle h = start;
    do {
      visited[h.idx()] = 1;
      loop.vertices.push_back(mesh.from_vertex_handle(h).idx());
      const auto& set = face_sets[mesh.opposite_face_handle(h).idx()];
      loop.solids.insert(loop.solids.end(), set.begin(), set.end());
      h = outgoing_boundary(mesh, organic, mesh.to_vertex_handle(h));
      GENBREP_CHECK(h.is_valid(), Code::Internal, "boundary loop broke off after repair");
    } while (h != start);
    std::sort(loop.solids.begin(), loop.solids.end());
    loop.solids.erase(std::unique(loop.solids.begin(), loop.solids.end()), loop.solids.end());
    out.loops.push_back(std::move(loop));
  }
  if (out.repaired_vertices > 0) {
    out.diagnostics.push_back("repaired " + std::to_string(out.repaired_vertices) +
                              " non-manifold boundary vertices in " +
                              std::to_string(out.repair_rounds) + " rounds, moving " +
                              std::to_string(out.reassigned_triangles) +
                              " incident triangles to the organic region");
  }
  context.step(kStage, 1.0);
  return out;
}

}  // namespace genbrep
