// mesh/file_check.cpp — the first reading of OBJ, OFF and STL files (see
// detail/file_check.h); PLY is in file_check_ply.cpp.
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "mesh/detail/file_check.h"
#include "mesh/mesh.h"

namespace genbrep::detail {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext;
}

std::vector<std::string> words_of(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

// The whole token as a number, or false (trailing characters, empty, not a number).
bool parse_number(const std::string& token, double* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size();
}

bool parse_integer(const std::string& token, long* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *value = std::strtol(token.c_str(), &end, 10);
  return end == token.c_str() + token.size() && errno == 0;
}

// "line 12: " for messages.
std::string at_line(long line) { return "line " + std::to_string(line) + ": "; }

// A text format must not hold NUL or other control bytes: random or binary data named
// .obj would otherwise read as an empty mesh.
void check_text(const std::string& path, const char* format) {
  std::ifstream in(path, std::ios::binary);
  char buffer[65536];
  in.read(buffer, sizeof buffer);
  const std::streamsize n = in.gcount();
  for (std::streamsize i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(buffer[i]);
    if (c < 32 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      throw_file_problem(path, std::string("is not a text ") + format + " file: byte " +
                                   std::to_string(i) + " is " + hex + " (binary data)");
    }
  }
}

// Three coordinates from words[first..]: the problem with them, or "".
std::string vertex_problem(const std::vector<std::string>& words, size_t first) {
  if (words.size() < first + 3) return "has " + std::to_string(words.size() - first) +
                                        " coordinates; a vertex needs 3";
  for (size_t k = first; k < first + 3; ++k) {
    double x = 0;
    if (!parse_number(words[k], &x)) return "has a coordinate '" + words[k] + "' that is not a number";
    const std::string problem = coordinate_problem(x, words[k]);
    if (!problem.empty()) return "has " + problem;
  }
  return "";
}

bool is_obj_statement(const std::string& word) {
  static const char* const kKeywords[] = {
      "v",    "vt",   "vn",    "vp",   "f",       "l",     "p",    "o",      "g",    "s",
      "mtllib", "usemtl", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm",
      "trim", "hole", "scrv",  "sp",   "end",     "con",   "mg",   "lod",    "bevel", "c_interp",
      "d_interp", "usemap", "maplib", "shadow_obj", "trace_obj", "ctech", "stech", "call", "csh"};
  if (word[0] == '#') return true;
  for (const char* k : kKeywords)
    if (word == k) return true;
  return false;
}

// OBJ: vertices and faces as the reader will take them. Face indices count from 1;
// negative ones count back from the last vertex read so far.
void check_obj(const std::string& path) {
  check_text(path, "OBJ");
  std::ifstream in(path);
  std::string line, first_unknown;
  long line_number = 0, vertices = 0, faces = 0, unknown_line = 0;
  long largest = 0, largest_line = 0, largest_face = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::vector<std::string> words = words_of(line);
    if (words.empty()) continue;
    if (!is_obj_statement(words[0])) {
      if (unknown_line == 0) unknown_line = line_number, first_unknown = words[0];
      continue;
    }
    if (words[0] == "v") {
      ++vertices;
      const std::string problem = vertex_problem(words, 1);
      if (!problem.empty())
        throw_file_problem(path, at_line(line_number) + "vertex " + std::to_string(vertices) + " " + problem);
    } else if (words[0] == "f") {
      ++faces;
      const std::string face = "face " + std::to_string(faces);
      if (words.size() < 4)
        throw_file_problem(path, at_line(line_number) + face + " has " + std::to_string(words.size() - 1) +
                                     " corners; a face needs at least 3");
      for (size_t k = 1; k < words.size(); ++k) {
        long index = 0;
        if (!parse_integer(words[k].substr(0, words[k].find('/')), &index))
          throw_file_problem(path, at_line(line_number) + face + " has a corner '" + words[k] +
                                       "' that is not a vertex number");
        if (index == 0)
          throw_file_problem(path, at_line(line_number) + face + " uses vertex 0; OBJ numbers vertices from 1");
        if (index < 0 && vertices + index < 0)
          throw_file_problem(path, at_line(line_number) + face + " uses vertex " + std::to_string(index) +
                                       ", which counts back past the first vertex (" +
                                       std::to_string(vertices) + " vertices before it)");
        if (index > largest) largest = index, largest_line = line_number, largest_face = faces;
      }
    }
  }
  if (largest > vertices)
    throw_file_problem(path, at_line(largest_line) + "face " + std::to_string(largest_face) + " uses vertex " +
                                 std::to_string(largest) + " but the file has " +
                                 std::to_string(vertices) + " vertices");
  if (vertices == 0 && faces == 0 && unknown_line > 0)
    throw_file_problem(path, "is not an OBJ file: " + at_line(unknown_line) + "'" + first_unknown.substr(0, 40) +
                                 "' is not an OBJ statement, and there are no vertices or faces");
}

// Text OFF: header keyword, counts, then the vertex and face rows ('#' starts a comment).
void check_off(const std::string& path) {
  {
    std::ifstream in(path, std::ios::binary);
    std::string head;
    std::getline(in, head);
    if (head.find("BINARY") != std::string::npos) return;  // OpenMesh's binary reader decides
  }
  check_text(path, "OFF");
  std::ifstream in(path);
  std::string line;
  long line_number = 0;
  auto next_words = [&]() {
    while (std::getline(in, line)) {
      ++line_number;
      const size_t hash = line.find('#');
      if (hash != std::string::npos) line.erase(hash);
      std::vector<std::string> words = words_of(line);
      if (!words.empty()) return words;
    }
    return std::vector<std::string>{};
  };
  std::vector<std::string> words = next_words();
  const std::string keyword = words.empty() ? "" : words[0];
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0)
    throw_file_problem(path, "does not start with OFF: not an OFF file (it starts with '" +
                                 keyword.substr(0, 40) + "')");
  if (keyword.find('4') != std::string::npos || keyword.find('n') != std::string::npos) return;
  words.erase(words.begin());
  if (words.empty()) words = next_words();
  long counts[3] = {0, 0, 0};
  if (words.size() < 2 || !parse_integer(words[0], &counts[0]) || !parse_integer(words[1], &counts[1]) ||
      counts[0] < 0 || counts[1] < 0)
    throw_file_problem(path, at_line(line_number) + "the counts '" + line.substr(0, 40) +
                                 "' are not whole numbers of vertices and faces");
  const long vertices = counts[0], faces = counts[1];
  auto truncated = [&](const std::string& where) {
    throw_file_problem(path, "is truncated: its header announces " + std::to_string(vertices) +
                                 " vertices and " + std::to_string(faces) + " faces; the data ends " + where);
  };
  for (long v = 0; v < vertices; ++v) {
    words = next_words();
    if (words.empty()) truncated("after " + std::to_string(v) + " vertices");
    const std::string problem = vertex_problem(words, 0);
    if (!problem.empty()) throw_file_problem(path, at_line(line_number) + "vertex " + std::to_string(v) + " " + problem);
  }
  for (long f = 0; f < faces; ++f) {
    words = next_words();
    if (words.empty()) truncated("after " + std::to_string(f) + " faces");
    const std::string face = at_line(line_number) + "face " + std::to_string(f);
    long corners = 0;
    if (!parse_integer(words[0], &corners) || corners < 3)
      throw_file_problem(path, face + " has '" + words[0] + "' corners; a face needs at least 3");
    if (static_cast<long>(words.size()) - 1 < corners)
      throw_file_problem(path, face + " announces " + std::to_string(corners) + " corners but lists " +
                                   std::to_string(words.size() - 1));
    for (long k = 1; k <= corners; ++k) {
      long index = 0;
      if (!parse_integer(words[k], &index))
        throw_file_problem(path, face + " has a corner '" + words[k] + "' that is not a vertex number");
      if (index < 0 || index >= vertices)
        throw_file_problem(path, face + " uses vertex " + std::to_string(index) + " but the file has " +
                                     std::to_string(vertices) + " vertices (OFF numbers them from 0)");
    }
  }
}

// Binary STL: an 80-byte header, a triangle count, 50 bytes per triangle. OpenMesh takes
// a file of any other size for ASCII, so a truncated one must be caught here.
void check_stl(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  char header[84] = {};
  in.read(header, sizeof header);
  std::uint32_t count = 0;
  std::memcpy(&count, header + 80, 4);
  const std::uintmax_t expected = 84 + 50 * static_cast<std::uintmax_t>(count);
  if (size >= 84 && size == expected) {
    char record[50];
    for (std::uint32_t t = 0; t < count && in.read(record, sizeof record); ++t)
      for (int k = 0; k < 9; ++k) {
        float x = 0;
        std::memcpy(&x, record + 12 + 4 * k, 4);
        std::ostringstream text;
        text << x;
        const std::string problem = coordinate_problem(x, text.str());
        if (!problem.empty())
          throw_file_problem(path, "triangle " + std::to_string(t) + " has " + problem);
      }
    return;
  }
  std::string start(header, static_cast<size_t>(std::min<std::uintmax_t>(size, 84)));
  const size_t first = start.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && start.compare(first, 5, "solid") == 0) {
    check_text(path, "ASCII STL");
    std::ifstream text(path);
    std::string line;
    long line_number = 0, vertex_lines = 0;
    while (std::getline(text, line)) {
      ++line_number;
      const std::vector<std::string> words = words_of(line);
      if (words.empty() || words[0] != "vertex") continue;
      ++vertex_lines;
      const std::string problem = vertex_problem(words, 1);
      if (!problem.empty()) throw_file_problem(path, at_line(line_number) + "vertex " + problem);
    }
    if (vertex_lines % 3 != 0)
      throw_file_problem(path, "is truncated: it has " + std::to_string(vertex_lines) +
                                   " vertex lines, not a whole number of triangles");
    return;
  }
  if (size < 84)
    throw_file_problem(path, "is not an STL file: " + std::to_string(size) +
                                 " bytes, too short for a binary STL header (84) and not ASCII ('solid')");
  // A count far beyond the size is no STL header at all (random bytes), not a short copy.
  const bool truncated = size < expected && expected / 16 <= size;
  throw_file_problem(path, std::string(truncated ? "is truncated" : "is not an STL file") +
                               ": it does not start with 'solid', and as binary STL its header "
                               "announces " + std::to_string(count) + " triangles (" +
                               std::to_string(expected) + " bytes) but the file has " +
                               std::to_string(size) + " bytes");
}

}  // namespace

std::string coordinate_problem(double value, const std::string& token) {
  const std::string quoted = " ('" + token.substr(0, 40) + "')";
  if (std::isnan(value)) return "a NaN coordinate" + quoted;
  if (std::isinf(value)) return "an infinite coordinate" + quoted;
  if (std::abs(value) > kMaxCoordinate) {
    std::ostringstream out;
    out << "a coordinate of " << value << ", beyond ±" << kMaxCoordinate;
    return out.str();
  }
  return "";
}

void throw_file_problem(const std::string& path, const std::string& problem) {
  throw Error(Code::InvalidInput, "'" + path + "' " + problem, "mesh");
}

void check_mesh_file(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status))
    throw Error(Code::FileError, "cannot open '" + path + "': no such file", "mesh");
  if (fs::is_directory(status))
    throw Error(Code::FileError, "cannot read '" + path + "': it is a directory, not a mesh file", "mesh");
  errno = 0;
  if (!std::ifstream(path).good()) {
    const std::string reason = errno == EACCES ? "permission denied" : "not readable";
    throw Error(Code::FileError, "cannot open '" + path + "': " + reason, "mesh");
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (!ec && size == 0) throw_file_problem(path, "is empty (0 bytes)");
  const std::string ext = lower_extension(path);
  if (ext == ".obj") check_obj(path);
  else if (ext == ".off") check_off(path);
  else if (ext == ".stl") check_stl(path, size);
  else if (ext == ".ply") check_ply_file(path);
  else
    throw Error(Code::FileError,
                "cannot read '" + path + "': the extension '" + ext +
                    "' is none of .obj, .ply, .stl and .off",
                "mesh");
}

}  // namespace genbrep::detail
