#include "pipeline/output.h"

#include <cstdint>
#include <fstream>

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

}  // namespace

void write_text_file(const std::string& path, const std::string& text) {
  auto out = open_for_writing(path, std::ios::out | std::ios::trunc);
  out << text << '\n';
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
}

void write_cage_obj(const std::string& path, const QuadCage& cage) {
  auto out = open_for_writing(path, std::ios::out | std::ios::trunc);
  out.precision(17);
  out << "# genbrep cage of organic component " << cage.component << "\n";
  for (Eigen::Index v = 0; v < cage.vertices.rows(); ++v) {
    out << "v " << cage.vertices(v, 0) << ' ' << cage.vertices(v, 1) << ' ' << cage.vertices(v, 2) << '\n';
  }
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    out << "f " << cage.quads(q, 0) + 1 << ' ' << cage.quads(q, 1) + 1 << ' ' << cage.quads(q, 2) + 1 << ' '
        << cage.quads(q, 3) + 1 << '\n';
  }
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
}

void write_composed(const std::string& obj_path, const std::string& ply_path, const TriangleMesh& mesh) {
  auto obj = open_for_writing(obj_path, std::ios::out | std::ios::trunc);
  obj.precision(17);
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    obj << "v " << mesh.vertices(v, 0) << ' ' << mesh.vertices(v, 1) << ' ' << mesh.vertices(v, 2) << '\n';
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    obj << "f " << mesh.triangles(t, 0) + 1 << ' ' << mesh.triangles(t, 1) + 1 << ' ' << mesh.triangles(t, 2) + 1 << '\n';
  }
  if (!obj) throw Error(Code::FileError, "cannot write '" + obj_path + "'", "output");
  auto ply = open_for_writing(ply_path, std::ios::out | std::ios::binary | std::ios::trunc);
  ply << "ply\nformat binary_little_endian 1.0\ncomment genbrep composed solid\n"
      << "element vertex " << mesh.vertices.rows() << "\n"
      << "property double x\nproperty double y\nproperty double z\n"
      << "element face " << mesh.triangles.rows() << "\n"
      << "property list uchar int vertex_indices\nproperty int source\nend_header\n";
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    for (int k = 0; k < 3; ++k) put<double>(ply, mesh.vertices(v, k));
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    put<uint8_t>(ply, 3);
    for (int k = 0; k < 3; ++k) put<int32_t>(ply, mesh.triangles(t, k));
    put<int32_t>(ply, mesh.triangle_source[t]);
  }
  if (!ply) throw Error(Code::FileError, "cannot write '" + ply_path + "'", "output");
}

void write_partition_ply(const std::string& path, const TriangleMesh& design,
                         const Partition& partition) {
  auto out = open_for_writing(path, std::ios::out | std::ios::binary | std::ios::trunc);
  out << "ply\nformat binary_little_endian 1.0\ncomment genbrep partition\n"
      << "element vertex " << design.vertices.rows() << "\n"
      << "property double x\nproperty double y\nproperty double z\n"
      << "element face " << design.triangles.rows() << "\n"
      << "property list uchar int vertex_indices\nproperty int solid\nproperty int component\n"
      << "end_header\n";
  for (Eigen::Index v = 0; v < design.vertices.rows(); ++v) {
    for (int k = 0; k < 3; ++k) put<double>(out, design.vertices(v, k));
  }
  for (Eigen::Index t = 0; t < design.triangles.rows(); ++t) {
    put<uint8_t>(out, 3);
    for (int k = 0; k < 3; ++k) put<int32_t>(out, design.triangles(t, k));
    put<int32_t>(out, partition.face_solid[t]);
    put<int32_t>(out, partition.face_component[t]);
  }
  if (!out) throw Error(Code::FileError, "cannot write '" + path + "'", "output");
}

}  // namespace genbrep
