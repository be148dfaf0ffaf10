// incidence/incidence.cpp — distance (§4.1.3) and grid (§4.1.1) incidences.
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "incidence/incidence.h"

namespace genbrep {
namespace {

constexpr const char* kStage = "incidence";

bool outside_box(const ClosedSurface& s, const Vec3& p, double margin) {
  return (p.array() < s.min_corner().array() - margin).any() ||
         (p.array() > s.max_corner().array() + margin).any();
}

// Same-role overlap: a vertex near member j's boundary but deep inside another member k
// of j's union group lies on a part of ∂S_j that is interior to the union.
bool buried_in_union(const SolidSet& solids, int j, const Vec3& p, double d) {
  for (int k = 0; k < solids.size(); ++k) {
    if (k == j || solids.union_group(k) != solids.union_group(j)) continue;
    const auto& s = solids.surface(k);
    if (!outside_box(s, p, 0) && s.inside(p) && s.distance(p) > d) return true;
  }
  return false;
}

struct VertexIncidence {
  std::vector<int> solids;
  int eroded_seed = -1;
};

// §4.1.3: I(V) = {S_j | D_j(V) <= d}; a vertex incident with a single seed that lies
// deeper than d inside it bounds the seed's eroded part.
VertexIncidence distance_incidence(const SolidSet& solids, const Vec3& p, double d,
                                   std::vector<double>* depth) {
  VertexIncidence out;
  for (int j = 0; j < solids.size(); ++j) {
    const auto& s = solids.surface(j);
    (*depth)[j] = 0;
    if (outside_box(s, p, d)) continue;
    const double dist = s.distance(p);
    // Only beyond d does the sign matter: within d the vertex is incident either way.
    if (dist > d && !s.inside(p)) continue;
    (*depth)[j] = dist > d ? dist : 0;
    if (buried_in_union(solids, j, p, d)) continue;
    out.solids.push_back(j);
  }
  if (out.solids.size() == 1 && solids.input(out.solids[0]).role == Role::Seed &&
      (*depth)[out.solids[0]] > d) {
    out.eroded_seed = out.solids[0];
  }
  return out;
}

struct GridKeyHash {
  size_t operator()(const std::array<int64_t, 3>& k) const {
    return static_cast<size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
  }
};

// §4.1.1: corner incidences I(g) = {S_i | g ∈ S_i}; a corner outside the design that is
// only in a seed marks that seed's eroded part. A vertex takes the union over the eight
// corners of its grid cell.
class GridIncidence {
 public:
  GridIncidence(const SolidSet& solids, const ClosedSurface& design, const Vec3& origin, double h)
      : solids_(solids), design_(design), origin_(origin), h_(h) {}

  VertexIncidence at(const Vec3& p) {
    const Vec3 cell = ((p - origin_) / h_).array().floor();
    VertexIncidence out;
    for (int corner = 0; corner < 8; ++corner) {
      const std::array<int64_t, 3> key{static_cast<int64_t>(cell.x()) + (corner & 1),
                                       static_cast<int64_t>(cell.y()) + ((corner >> 1) & 1),
                                       static_cast<int64_t>(cell.z()) + ((corner >> 2) & 1)};
      const Corner& c = corner_incidence(key);
      out.solids.insert(out.solids.end(), c.solids.begin(), c.solids.end());
      if (c.eroded_seed >= 0 && out.eroded_seed < 0) out.eroded_seed = c.eroded_seed;
    }
    std::sort(out.solids.begin(), out.solids.end());
    out.solids.erase(std::unique(out.solids.begin(), out.solids.end()), out.solids.end());
    return out;
  }

 private:
  struct Corner {
    std::vector<int> solids;
    int eroded_seed = -1;
  };
  const Corner& corner_incidence(const std::array<int64_t, 3>& key) {
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    const Vec3 g = origin_ + h_ * Vec3(static_cast<double>(key[0]), static_cast<double>(key[1]),
                                       static_cast<double>(key[2]));
    Corner c;
    for (int j = 0; j < solids_.size(); ++j) {
      if (solids_.surface(j).inside(g)) c.solids.push_back(j);
    }
    if (c.solids.size() == 1 && solids_.input(c.solids[0]).role == Role::Seed &&
        !design_.inside(g)) {
      c.eroded_seed = c.solids[0];
      c.solids.clear();  // I(g) = {E_i}: the seed's volume here was removed by the solver
    }
    return cache_.emplace(key, std::move(c)).first->second;
  }

  const SolidSet& solids_;
  const ClosedSurface& design_;
  Vec3 origin_;
  double h_;
  std::unordered_map<std::array<int64_t, 3>, Corner, GridKeyHash> cache_;
};

}  // namespace

double median_edge_length(const TriangleMesh& mesh) {
  std::vector<double> lengths;
  lengths.reserve(3 * static_cast<size_t>(mesh.triangles.rows()));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles(t, k), b = mesh.triangles(t, (k + 1) % 3);
      if (a < b) lengths.push_back((mesh.vertices.row(a) - mesh.vertices.row(b)).norm());
    }
  }
  if (lengths.empty()) return 0;
  auto mid = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
  std::nth_element(lengths.begin(), mid, lengths.end());
  return *mid;
}

Incidence compute_incidence(const TriangleMesh& design, const SolidSet& solids,
                            const IncidenceOptions& options, const Context& context) {
  const int n = static_cast<int>(design.vertices.rows());
  Incidence result;
  result.eroded_seed.assign(static_cast<size_t>(n), -1);
  result.incident_vertices_per_solid.assign(static_cast<size_t>(solids.size()), 0);
  const bool grid = options.mode == IncidenceOptions::Mode::Grid;
  if (grid) {
    GENBREP_CHECK(options.grid_h > 0 && std::isfinite(options.grid_h), Code::InvalidInput,
                  "grid incidence needs a voxel size h > 0");
    GENBREP_CHECK(options.grid_origin.allFinite(), Code::InvalidInput,
                  "grid incidence needs a finite grid origin");
    result.tolerance = options.grid_h;
  } else if (options.tolerance > 0) {
    result.tolerance = options.tolerance;
  } else {
    GENBREP_CHECK(options.tolerance == 0, Code::InvalidInput,
                  "the tolerance must be positive, or 0 to derive it from the design");
    result.tolerance = median_edge_length(design);
    result.tolerance_derived = true;
  }
  const double d = result.tolerance;
  std::unique_ptr<ClosedSurface> design_surface;
  std::unique_ptr<GridIncidence> grid_incidence;
  if (grid) {
    design_surface = std::make_unique<ClosedSurface>(design);
    grid_incidence = std::make_unique<GridIncidence>(solids, *design_surface, options.grid_origin,
                                                     options.grid_h);
  }
  std::vector<double> depth(static_cast<size_t>(solids.size()));
  std::vector<int> deep_in_keep_in(static_cast<size_t>(solids.size()), 0);
  std::vector<int> deep_in_keep_out(static_cast<size_t>(solids.size()), 0);
  for (int v = 0; v < n; ++v) {
    if ((v & 0x3fff) == 0) context.step(kStage, static_cast<double>(v) / std::max(n, 1));
    const Vec3 p = design.vertices.row(v);
    VertexIncidence vi = grid ? grid_incidence->at(p) : distance_incidence(solids, p, d, &depth);
    for (int j : vi.solids) {
      ++result.incident_vertices_per_solid[j];
      if (!grid && depth[j] > d) {
        if (solids.input(j).role == Role::KeepIn) ++deep_in_keep_in[j];
        if (solids.input(j).role == Role::KeepOut) ++deep_in_keep_out[j];
      }
    }
    result.solids.insert(result.solids.end(), vi.solids.begin(), vi.solids.end());
    result.offsets.push_back(static_cast<int>(result.solids.size()));
    result.eroded_seed[v] = vi.eroded_seed;
  }
  for (int j = 0; j < solids.size(); ++j) {
    if (deep_in_keep_in[j] > 0) {
      result.diagnostics.push_back(std::to_string(deep_in_keep_in[j]) +
                                   " design vertices lie deeper than d inside " +
                                   solids.describe(j) + ": the design does not contain it there");
    }
    if (deep_in_keep_out[j] > 0) {
      result.diagnostics.push_back(std::to_string(deep_in_keep_out[j]) +
                                   " design vertices lie deeper than d inside " +
                                   solids.describe(j) + ": material intrudes into it");
    }
    if (result.incident_vertices_per_solid[j] == 0) {
      result.diagnostics.push_back(solids.describe(j) + " touches no design vertex");
    }
  }
  context.step(kStage, 1.0);
  return result;
}

}  // namespace genbrep
