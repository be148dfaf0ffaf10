// fit/limit.cpp — the limit surface of a cage through OpenSubdiv Far, set up the way
// Blender's Subdivision Surface modifier sets it up (intern/opensubdiv: adaptive
// refinement to `quality`, Gregory-basis end caps, infinitely sharp patches, factorized
// stencils for refined and local points). See fit/fit.h for the contract.
#include <opensubdiv/far/error.h>
#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <algorithm>
#include <map>
#include <mutex>

#include "fit/fit.h"

namespace genbrep {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {

// OpenSubdiv reports through callbacks (printf by default, and FAR_FATAL_ERROR is meant
// to end the program). Ours only remember the message; every factory result is checked.
thread_local std::string g_opensubdiv_error;
void on_opensubdiv_error(Far::ErrorType, const char* message) { g_opensubdiv_error = message; }
void on_opensubdiv_warning(const char*) {}

void install_opensubdiv_callbacks() {
  static std::once_flag once;
  std::call_once(once, [] {
    Far::SetErrorCallback(&on_opensubdiv_error);
    Far::SetWarningCallback(&on_opensubdiv_warning);
  });
}

constexpr int kMaxPatchPoints = 32;  // regular 16, Gregory basis 20

}  // namespace

struct LimitSurface::Impl {
  int vertex_count = 0;
  Quads quads;
  std::unique_ptr<Far::TopologyRefiner> refiner;
  std::unique_ptr<Far::PatchTable> patches;
  std::unique_ptr<Far::PatchMap> patch_map;
  // Patch points beyond the base vertices (refined vertices, then local points), each a
  // weighted sum of base control points: rows in CSR form.
  std::vector<int> row_offsets{0};
  std::vector<int> row_indices;
  std::vector<double> row_weights;
  Vertices points;  // base control points, then the rows above evaluated

  // Basis weights (and derivative weights, if asked) of the patch under (quad, u, v);
  // returns the patch's point indices into `points`.
  Far::ConstIndexArray basis(int quad, double u, double v, double* w, double* wu = nullptr,
                             double* wv = nullptr) const {
    GENBREP_CHECK(quad >= 0 && quad < quads.rows(), Code::Internal,
                  "limit surface: quad " + std::to_string(quad) + " out of range");
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    const Far::PatchTable::PatchHandle* h = patch_map->FindPatch(quad, u, v);
    GENBREP_CHECK(h != nullptr, Code::Internal,
                  "limit surface: no patch at quad " + std::to_string(quad));
    const Far::ConstIndexArray cvs = patches->GetPatchVertices(*h);
    GENBREP_CHECK(cvs.size() <= kMaxPatchPoints, Code::Internal, "patch with too many points");
    patches->EvaluateBasis(*h, u, v, w, wu, wv);
    return cvs;
  }
};

LimitSurface::LimitSurface(const QuadCage& cage) : impl_(std::make_unique<Impl>()) {
  install_opensubdiv_callbacks();
  Impl& s = *impl_;
  s.vertex_count = static_cast<int>(cage.vertices.rows());
  s.quads = cage.quads;
  const int quad_count = static_cast<int>(cage.quads.rows());
  GENBREP_CHECK(quad_count > 0, Code::InvalidInput, "cage has no quads");
  std::vector<int> used(s.vertex_count, 0);
  std::map<std::pair<int, int>, int> edge_count;
  for (int q = 0; q < quad_count; ++q) {
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      GENBREP_CHECK(a >= 0 && a < s.vertex_count, Code::InvalidInput,
                    "cage quad " + std::to_string(q) + " uses vertex " + std::to_string(a) +
                        " of " + std::to_string(s.vertex_count));
      GENBREP_CHECK(a != b && a != cage.quads(q, (k + 2) % 4), Code::InvalidInput,
                    "cage quad " + std::to_string(q) + " repeats vertex " + std::to_string(a));
      used[a] = 1;
      edge_count[{std::min(a, b), std::max(a, b)}] += 1;
    }
  }
  for (int v = 0; v < s.vertex_count; ++v) {
    GENBREP_CHECK(used[v], Code::InvalidInput,
                  "cage vertex " + std::to_string(v) + " belongs to no quad");
  }

  // Creases: Blender's sharpness = 10·crease²; a vertex with exactly two edges takes the
  // smaller sharpness of its two edges (Blender's topology_refiner_factory.cc does this so
  // a creased plane keeps its corners).
  GENBREP_CHECK(cage.crease_edges.size() == cage.crease_values.size(), Code::InvalidInput,
                "cage crease_edges and crease_values differ in length");
  std::vector<int> crease_pairs;
  std::vector<float> crease_sharpness;
  std::map<std::pair<int, int>, float> edge_sharpness;
  for (size_t i = 0; i < cage.crease_edges.size(); ++i) {
    const auto [a, b] = cage.crease_edges[i];
    const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
    GENBREP_CHECK(edge_count.count(key), Code::InvalidInput,
                  "cage crease on " + std::to_string(a) + "-" + std::to_string(b) +
                      ", which is not a cage edge");
    const float c = std::clamp(cage.crease_values[i], 0.0f, 1.0f);
    const float sharpness = std::min(10.0f * c * c, 10.0f);
    if (sharpness < 1e-6f) continue;
    crease_pairs.push_back(a);
    crease_pairs.push_back(b);
    crease_sharpness.push_back(sharpness);
    edge_sharpness[key] = sharpness;
  }
  std::vector<int> vertex_edges(s.vertex_count, 0);
  std::vector<float> vertex_min_sharpness(s.vertex_count, 1e30f);
  for (const auto& [key, faces] : edge_count) {
    const auto it = edge_sharpness.find(key);
    const float sharpness = it == edge_sharpness.end() ? 0.0f : it->second;
    for (int v : {key.first, key.second}) {
      vertex_edges[v] += 1;
      vertex_min_sharpness[v] = std::min(vertex_min_sharpness[v], sharpness);
    }
  }
  std::vector<int> corner_vertices;
  std::vector<float> corner_sharpness;
  for (int v = 0; v < s.vertex_count; ++v) {
    if (vertex_edges[v] == 2 && vertex_min_sharpness[v] > 0) {
      corner_vertices.push_back(v);
      corner_sharpness.push_back(vertex_min_sharpness[v]);
    }
  }

  std::vector<int> face_sizes(quad_count, 4);
  std::vector<int> face_indices(cage.quads.data(), cage.quads.data() + 4 * quad_count);
  Far::TopologyDescriptor descriptor;
  descriptor.numVertices = s.vertex_count;
  descriptor.numFaces = quad_count;
  descriptor.numVertsPerFace = face_sizes.data();
  descriptor.vertIndicesPerFace = face_indices.data();
  descriptor.numCreases = static_cast<int>(crease_sharpness.size());
  descriptor.creaseVertexIndexPairs = crease_pairs.data();
  descriptor.creaseWeights = crease_sharpness.data();
  descriptor.numCorners = static_cast<int>(corner_sharpness.size());
  descriptor.cornerVertexIndices = corner_vertices.data();
  descriptor.cornerWeights = corner_sharpness.data();

  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(cage.scheme.boundary_smooth_all
                                      ? Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                      : Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  sdc.SetCreasingMethod(Sdc::Options::CREASE_UNIFORM);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  g_opensubdiv_error.clear();
  s.refiner.reset(Factory::Create(descriptor, Factory::Options(Sdc::SCHEME_CATMARK, sdc)));
  GENBREP_CHECK(s.refiner != nullptr, Code::InvalidInput,
                "OpenSubdiv rejects the cage topology: " + g_opensubdiv_error);

  const int level = std::clamp(cage.scheme.quality, 1, 10);
  Far::TopologyRefiner::AdaptiveOptions adaptive(level);
  adaptive.useInfSharpPatch = true;
  s.refiner->RefineAdaptive(adaptive);

  Far::StencilTableFactoryReal<double>::Options stencil_options;
  stencil_options.generateOffsets = true;
  stencil_options.generateIntermediateLevels = true;
  std::unique_ptr<const Far::StencilTableReal<double>> stencils(
      Far::StencilTableFactoryReal<double>::Create(*s.refiner, stencil_options));
  GENBREP_CHECK(stencils != nullptr, Code::StageFailure,
                "OpenSubdiv made no stencil table: " + g_opensubdiv_error);

  Far::PatchTableFactory::Options patch_options(level);
  patch_options.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  patch_options.useInfSharpPatch = true;
  patch_options.SetPatchPrecision<double>();
  s.patches.reset(Far::PatchTableFactory::Create(*s.refiner, patch_options));
  GENBREP_CHECK(s.patches != nullptr, Code::StageFailure,
                "OpenSubdiv made no patch table: " + g_opensubdiv_error);
  if (const auto* local = s.patches->GetLocalPointStencilTable<double>()) {
    const auto* all = Far::StencilTableFactoryReal<double>::AppendLocalPointStencilTable(
        *s.refiner, stencils.get(), local);
    GENBREP_CHECK(all != nullptr, Code::StageFailure,
                  "OpenSubdiv could not append local points: " + g_opensubdiv_error);
    stencils.reset(all);
  }
  s.patch_map = std::make_unique<Far::PatchMap>(*s.patches);

  const int rows = stencils->GetNumStencils();
  const auto& sizes = stencils->GetSizes();
  const auto& offsets = stencils->GetOffsets();
  const auto& indices = stencils->GetControlIndices();
  const auto& weights = stencils->GetWeights();
  for (int r = 0; r < rows; ++r) {
    for (int k = offsets[r]; k < offsets[r] + sizes[r]; ++k) {
      GENBREP_CHECK(indices[k] >= 0 && indices[k] < s.vertex_count, Code::Internal,
                    "OpenSubdiv stencil refers to a non-base vertex");
      s.row_indices.push_back(indices[k]);
      s.row_weights.push_back(weights[k]);
    }
    s.row_offsets.push_back(static_cast<int>(s.row_indices.size()));
  }
  s.points.setZero(s.vertex_count + rows, 3);
  set_control_points(cage.vertices);
}

LimitSurface::~LimitSurface() = default;
LimitSurface::LimitSurface(LimitSurface&&) noexcept = default;
LimitSurface& LimitSurface::operator=(LimitSurface&&) noexcept = default;

int LimitSurface::quad_count() const { return static_cast<int>(impl_->quads.rows()); }
int LimitSurface::control_point_count() const { return impl_->vertex_count; }
const Quads& LimitSurface::quads() const { return impl_->quads; }

void LimitSurface::set_control_points(const Vertices& control_points) {
  Impl& s = *impl_;
  GENBREP_CHECK(control_points.rows() == s.vertex_count, Code::Internal,
                "limit surface: " + std::to_string(control_points.rows()) +
                    " control points for a cage of " + std::to_string(s.vertex_count));
  s.points.topRows(s.vertex_count) = control_points;
  const int rows = static_cast<int>(s.row_offsets.size()) - 1;
  for (int r = 0; r < rows; ++r) {
    Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
    for (int k = s.row_offsets[r]; k < s.row_offsets[r + 1]; ++k) {
      p += s.row_weights[k] * control_points.row(s.row_indices[k]);
    }
    s.points.row(s.vertex_count + r) = p;
  }
}

LimitSample LimitSurface::evaluate(int quad, double u, double v) const {
  const Impl& s = *impl_;
  double w[kMaxPatchPoints], wu[kMaxPatchPoints], wv[kMaxPatchPoints];
  const Far::ConstIndexArray cvs = s.basis(quad, u, v, w, wu, wv);
  LimitSample out;
  for (int i = 0; i < cvs.size(); ++i) {
    const Vec3 p = s.points.row(cvs[i]).transpose();
    out.position += w[i] * p;
    out.du += wu[i] * p;
    out.dv += wv[i] * p;
  }
  return out;
}

LimitWeights LimitSurface::weights(int quad, double u, double v) const {
  const Impl& s = *impl_;
  double w[kMaxPatchPoints];
  const Far::ConstIndexArray cvs = s.basis(quad, u, v, w);
  LimitWeights out;
  for (int i = 0; i < cvs.size(); ++i) {
    if (cvs[i] < s.vertex_count) {
      out.emplace_back(cvs[i], w[i]);
      continue;
    }
    const int r = cvs[i] - s.vertex_count;
    for (int k = s.row_offsets[r]; k < s.row_offsets[r + 1]; ++k) {
      out.emplace_back(s.row_indices[k], w[i] * s.row_weights[k]);
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  LimitWeights merged;
  for (const auto& [index, weight] : out) {
    if (!merged.empty() && merged.back().first == index) {
      merged.back().second += weight;
    } else {
      merged.emplace_back(index, weight);
    }
  }
  return merged;
}

}  // namespace genbrep
