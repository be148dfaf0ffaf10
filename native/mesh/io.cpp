// mesh/io.cpp — file reading through OpenMesh's reader modules with a recording importer.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/ImporterT.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <unordered_map>

#include "mesh/detail/file_check.h"
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

// The numbers at the start of `line` (as many as parse, at most `most`).
std::vector<double> leading_numbers(const std::string& line, size_t most) {
  std::vector<double> numbers;
  const char* at = line.c_str();
  while (numbers.size() < most) {
    char* end = nullptr;
    const double x = std::strtod(at, &end);
    if (end == at) break;
    numbers.push_back(x);
    at = end;
  }
  return numbers;
}

// The file name's extension, lower case ("" if none).
std::string extension_of(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  std::string extension = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return extension;
}

// The vertex coordinates of a text OBJ, OFF or ASCII PLY file as doubles, in file order;
// empty for other formats or layouts this does not follow (binary files, STL, whose
// reader merges equal points, PLY vertex lists, OFF of other dimensions).
std::vector<Vec3> text_coordinates(const std::string& path) {
  const std::string extension = extension_of(path);
  std::ifstream in(path);
  std::vector<Vec3> points;
  std::string line;
  auto point = [&](const std::vector<double>& xyz, size_t x, size_t y, size_t z) {
    if (std::max({x, y, z}) >= xyz.size()) return false;
    points.emplace_back(xyz[x], xyz[y], xyz[z]);
    return true;
  };
  if (extension == "obj") {
    while (std::getline(in, line)) {
      const size_t start = line.find_first_not_of(" \t");
      if (start == std::string::npos || line.compare(start, 1, "v") != 0 || line.size() < start + 2 ||
          !std::isspace(static_cast<unsigned char>(line[start + 1])))
        continue;
      if (!point(leading_numbers(line.substr(start + 1), 3), 0, 1, 2)) return {};
    }
  } else if (extension == "off") {
    // Header (OFF, COFF, NOFF, STOFF, ...), then the counts, then one vertex per line.
    auto next_content = [&]() {
      while (std::getline(in, line)) {
        const size_t hash = line.find('#');
        if (hash != std::string::npos) line.erase(hash);
        if (line.find_first_not_of(" \t\r") != std::string::npos) return true;
      }
      return false;
    };
    if (!next_content()) return {};
    std::istringstream header(line);
    std::string keyword;
    header >> keyword;
    if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0 ||
        keyword.find('4') != std::string::npos || keyword.find('n') != std::string::npos)
      return {};
    std::string rest;
    std::getline(header, rest);
    if (rest.find("BINARY") != std::string::npos) return {};
    std::vector<double> counts = leading_numbers(rest, 1);
    if (counts.empty()) {
      if (!next_content()) return {};
      counts = leading_numbers(line, 1);
    }
    if (counts.empty() || counts[0] < 0) return {};
    for (long v = 0; v < static_cast<long>(counts[0]); ++v)
      if (!next_content() || !point(leading_numbers(line, 3), 0, 1, 2)) return {};
  } else if (extension == "ply") {
    // The header names the elements in body order; each ASCII row is one line.
    long skip = 0, vertices = -1;
    std::vector<std::string> properties;
    bool ascii = false, in_vertex = false, vertex_list = false;
    while (std::getline(in, line)) {
      std::istringstream words(line);
      std::string word, a, b;
      words >> word;
      if (word == "format") words >> a, ascii = a == "ascii";
      if (word == "element") {
        long count = 0;
        words >> a >> count;
        in_vertex = a == "vertex" && vertices < 0;
        if (in_vertex) vertices = count;
        else if (vertices < 0) skip += count;
      }
      if (word == "property" && in_vertex) {
        words >> a;
        if (a == "list") vertex_list = true;
        while (words >> b) a = b;
        properties.push_back(a);
      }
      if (word == "end_header") break;
    }
    if (!ascii || vertex_list || vertices < 0) return {};
    auto column = [&](const char* name) {
      return static_cast<size_t>(std::find(properties.begin(), properties.end(), name) -
                                 properties.begin());
    };
    auto next_row = [&]() {
      while (std::getline(in, line))
        if (line.find_first_not_of(" \t\r") != std::string::npos) return true;
      return false;
    };
    for (long row = 0; row < skip; ++row)
      if (!next_row()) return {};
    for (long v = 0; v < vertices; ++v) {
      if (!next_row()) return {};
      if (!point(leading_numbers(line, properties.size()), column("x"), column("y"), column("z")))
        return {};
    }
  }
  return points;
}

// OpenMesh's readers pass every coordinate on as a float, also from files that hold more
// digits (OBJ, OFF and ASCII PLY written with %.17g, or PLY's "property double"): a
// keep-in read from them would not be the solid the user gave. For the text formats the
// coordinates are read again as doubles and replace OpenMesh's when there are as many
// and each lies within one float step of OpenMesh's value; otherwise OpenMesh's stand.
void restore_double_coordinates(const std::string& path, std::vector<Vec3>& points) {
  const std::vector<Vec3> exact = text_coordinates(path);
  if (exact.size() != points.size()) return;
  for (size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const float read = static_cast<float>(points[i][k]), near = static_cast<float>(exact[i][k]);
      if (read != near && std::nextafter(read, near) != near) return;
    }
  points = exact;
}

// A text OFF file with its '#' comments taken out, or nothing (not OFF, binary, or no
// comment). OpenMesh's OFF reader takes a comment line for data: a tetrahedron with a
// comment after its header came out as "face 0 has 0 corners", one after the counts as
// coordinates that cannot be read.
std::optional<std::string> off_without_comments(const std::string& path) {
  if (extension_of(path) != "off") return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  std::string header;
  std::getline(in, header);
  if (header.find("BINARY") != std::string::npos) return std::nullopt;
  in.seekg(0);
  std::string text, line;
  bool comments = false;
  while (std::getline(in, line)) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) {
      comments = true;
      line.erase(hash);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    }
    text += line;
    text += '\n';
  }
  if (!comments) return std::nullopt;
  return text;
}

}  // namespace

PolygonSoup read_polygon_file(const std::string& path) {
  detail::check_mesh_file(path);
  PolyMesh mesh;
  std::vector<Vec3> points;
  PolygonSoup soup;
  RecordingImporter importer(mesh, points, soup.offsets, soup.indices);
  OpenMesh::IO::Options options;
  // OpenMesh reports repairs of non-manifold faces on its error stream; our validation
  // reports them with counts instead.
  omerr().disable();
  omlog().disable();
  bool ok = false;
  if (const auto text = off_without_comments(path)) {
    std::istringstream stream(*text);
    ok = OpenMesh::IO::IOManager().read(stream, "off", importer, options);
  } else {
    ok = OpenMesh::IO::IOManager().read(path, importer, options);
  }
  omerr().enable();
  omlog().enable();
  if (!ok) {
    throw Error(Code::FileError,
                "cannot read '" + path + "': not a readable OBJ, PLY, STL or OFF file", "mesh");
  }
  // check_mesh_file has seen every vertex and index; a corner the reader still could not
  // place is one of its own limits (binary OFF, for one). Say so rather than guess.
  const auto unplaced = std::count(soup.indices.begin(), soup.indices.end(), -1);
  if (unplaced > 0) {
    throw Error(Code::InvalidInput,
                "'" + path + "' has " + std::to_string(unplaced) +
                    " face corners that the reader could not place on a vertex (an unreadable "
                    "vertex or an index beyond the vertices)",
                "mesh");
  }
  restore_double_coordinates(path, points);
  soup.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) soup.vertices.row(i) = points[i];
  return soup;
}

}  // namespace genbrep
