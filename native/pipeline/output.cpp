#include "pipeline/output.h"

#include <cstdint>
#include <fstream>
#include <utility>
#include <vector>

namespace genbrep {
namespace {

std::ofstream open_for_writing(const std::string& path, std::ios::openmode mode) {
  std::ofstream out(path, mode);
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
  return out;
}

template <typename T>
void put(std::ofstream& out, T value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));  // x86/ARM: little-endian
}

// An OBJ of the faces' rows (triangles or quads), 1-based, full double precision.
template <typename Faces>
void write_obj(const std::string& path, const std::string& comment, const Vertices& vertices,
               const Faces& faces) {
  auto out = open_for_writing(path, std::ios::out | std::ios::trunc);
  out.precision(17);
  if (!comment.empty()) out << "# " << comment << "\n";
  for (Eigen::Index v = 0; v < vertices.rows(); ++v) {
    out << "v " << vertices(v, 0) << ' ' << vertices(v, 1) << ' ' << vertices(v, 2) << '\n';
  }
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    out << 'f';
    for (Eigen::Index k = 0; k < faces.cols(); ++k) out << ' ' << faces(f, k) + 1;
    out << '\n';
  }
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
}

// A binary PLY of a triangle mesh with one int face property per entry of `properties`
// (name, one value per triangle).
void write_labelled_ply(const std::string& path, const std::string& comment, const TriangleMesh& mesh,
                        const std::vector<std::pair<std::string, const std::vector<int>*>>& properties) {
  auto out = open_for_writing(path, std::ios::out | std::ios::binary | std::ios::trunc);
  out << "ply\nformat binary_little_endian 1.0\ncomment " << comment << "\n"
      << "element vertex " << mesh.vertices.rows() << "\n"
      << "property double x\nproperty double y\nproperty double z\n"
      << "element face " << mesh.triangles.rows() << "\n"
      << "property list uchar int vertex_indices\n";
  for (const auto& property : properties) out << "property int " << property.first << "\n";
  out << "end_header\n";
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    for (int k = 0; k < 3; ++k) put<double>(out, mesh.vertices(v, k));
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    put<uint8_t>(out, 3);
    for (int k = 0; k < 3; ++k) put<int32_t>(out, mesh.triangles(t, k));
    for (const auto& property : properties) put<int32_t>(out, (*property.second)[t]);
  }
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
}

}  // namespace

void write_text_file(const std::string& path, const std::string& text) {
  auto out = open_for_writing(path, std::ios::out | std::ios::trunc);
  out << text << '\n';
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
}

void write_cage_obj(const std::string& path, const QuadCage& cage) {
  write_obj(path, "genbrep cage of organic component " + std::to_string(cage.component), cage.vertices,
            cage.quads);
}

void write_composed(const std::string& obj_path, const std::string& ply_path, const TriangleMesh& mesh) {
  write_obj(obj_path, "", mesh.vertices, mesh.triangles);
  write_labelled_ply(ply_path, "genbrep composed solid", mesh, {{"source", &mesh.triangle_source}});
}

void write_partition_ply(const std::string& path, const TriangleMesh& design,
                         const Partition& partition) {
  write_labelled_ply(path, "genbrep partition", design,
                     {{"solid", &partition.face_solid}, {"component", &partition.face_component}});
}

}  // namespace genbrep
