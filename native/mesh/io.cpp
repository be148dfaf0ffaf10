// mesh/io.cpp — file reading through OpenMesh's reader modules with a recording importer.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/ImporterT.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <algorithm>
#include <fstream>
#include <unordered_map>

#include "mesh/mesh.h"

namespace genbrep {
namespace {

struct PolyTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
};
using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<PolyTraits>;

// OpenMesh's readers talk to an importer. We let the stock importer build its mesh (the
// readers set normals and colours on the handles it returns) but record every vertex and
// face as the file states them, so validation sees non-manifold input instead of the
// repaired copy. Handles are mapped because the stock importer may add vertices of its own.
class RecordingImporter : public OpenMesh::IO::ImporterT<PolyMesh> {
 public:
  RecordingImporter(PolyMesh& mesh, std::vector<Vec3>& points, std::vector<int>& offsets,
                    std::vector<int>& indices)
      : ImporterT<PolyMesh>(mesh), points_(points), offsets_(offsets), indices_(indices) {}

  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    return record(ImporterT<PolyMesh>::add_vertex(p), Vec3(p[0], p[1], p[2]));
  }
  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
    return record(ImporterT<PolyMesh>::add_vertex(p), Vec3(p[0], p[1], p[2]));
  }
  // The PLY reader adds vertices first and places them afterwards.
  OpenMesh::VertexHandle add_vertex() override {
    return record(ImporterT<PolyMesh>::add_vertex(), Vec3::Zero());
  }
  void set_point(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& p) override {
    ImporterT<PolyMesh>::set_point(vh, p);
    auto it = handle_to_point_.find(vh.idx());
    if (it != handle_to_point_.end()) points_[it->second] = Vec3(p[0], p[1], p[2]);
  }
  OpenMesh::FaceHandle add_face(const VHandles& corners) override {
    for (const auto& vh : corners) {
      auto it = handle_to_point_.find(vh.idx());
      indices_.push_back(it == handle_to_point_.end() ? -1 : it->second);
    }
    offsets_.push_back(static_cast<int>(indices_.size()));
    return ImporterT<PolyMesh>::add_face(corners);
  }

 private:
  OpenMesh::VertexHandle record(OpenMesh::VertexHandle vh, const Vec3& p) {
    handle_to_point_[vh.idx()] = static_cast<int>(points_.size());
    points_.push_back(p);
    return vh;
  }
  std::vector<Vec3>& points_;
  std::vector<int>& offsets_;
  std::vector<int>& indices_;
  std::unordered_map<int, int> handle_to_point_;
};

}  // namespace

PolygonSoup read_polygon_file(const std::string& path) {
  if (!std::ifstream(path).good()) {
    throw Error(Code::FileError, "cannot open '" + path + "': no such file or not readable",
                "mesh");
  }
  PolyMesh mesh;
  std::vector<Vec3> points;
  PolygonSoup soup;
  RecordingImporter importer(mesh, points, soup.offsets, soup.indices);
  OpenMesh::IO::Options options;
  // OpenMesh reports repairs of non-manifold faces on its error stream; our validation
  // reports them with counts instead.
  omerr().disable();
  omlog().disable();
  const bool ok = OpenMesh::IO::IOManager().read(path, importer, options);
  omerr().enable();
  omlog().enable();
  if (!ok) {
    throw Error(Code::FileError,
                "cannot read '" + path + "': not a readable OBJ, PLY, STL or OFF file", "mesh");
  }
  // A reader skips a vertex line it cannot parse ("nan", "inf", garbage); the faces that
  // use it then point nowhere. Say so rather than reporting a bad index later.
  const auto unreadable = std::count(soup.indices.begin(), soup.indices.end(), -1);
  if (unreadable > 0) {
    throw Error(Code::InvalidInput,
                "'" + path + "' has vertex coordinates that cannot be read as numbers (NaN, " +
                    "infinite or malformed): " + std::to_string(unreadable) +
                    " face corners use such vertices",
                "mesh");
  }
  soup.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) soup.vertices.row(i) = points[i];
  return soup;
}

}  // namespace genbrep
