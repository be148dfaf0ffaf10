// mesh/file_check_ply.cpp — the first reading of PLY files (see detail/file_check.h):
// the header, then every row of every element, ASCII or binary, so that a truncated
// file, a NaN coordinate or a face index beyond the vertices is named with its row.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "mesh/detail/file_check.h"

namespace genbrep::detail {
namespace {

enum class Format { Ascii, BinaryLittle, BinaryBig };

struct Property {
  std::string name;
  std::string type;        // value type; for a list, its item type
  std::string count_type;  // empty unless a list
};

struct Element {
  std::string name;
  long count = 0;
  std::vector<Property> properties;
};

// Bytes of a PLY scalar type, 0 if the name is none.
int type_size(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32") return 4;
  if (type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// Reads the values of the body one at a time, as text tokens or as binary scalars.
class BodyReader {
 public:
  BodyReader(std::ifstream& in, Format format) : in_(in), format_(format) {}

  // The next value of `type`; false at the end of the file. `text` is how to quote it.
  bool next(const std::string& type, double* value, std::string* text, bool* number) {
    *number = true;
    if (format_ == Format::Ascii) {
      if (!(in_ >> *text)) return false;
      char* end = nullptr;
      *value = std::strtod(text->c_str(), &end);
      *number = end == text->c_str() + text->size();
      return true;
    }
    const int size = type_size(type);
    unsigned char bytes[8];
    if (!in_.read(reinterpret_cast<char*>(bytes), size)) return false;
    if (format_ == Format::BinaryBig) std::reverse(bytes, bytes + size);
    *value = decode(type, bytes);
    std::ostringstream out;
    out << *value;
    *text = out.str();
    return true;
  }

 private:
  static double decode(const std::string& type, const unsigned char* b) {
    auto as = [b](auto v) {
      std::memcpy(&v, b, sizeof v);
      return static_cast<double>(v);
    };
    if (type == "char" || type == "int8") return as(std::int8_t{});
    if (type == "uchar" || type == "uint8") return as(std::uint8_t{});
    if (type == "short" || type == "int16") return as(std::int16_t{});
    if (type == "ushort" || type == "uint16") return as(std::uint16_t{});
    if (type == "int" || type == "int32") return as(std::int32_t{});
    if (type == "uint" || type == "uint32") return as(std::uint32_t{});
    if (type == "float" || type == "float32") return as(float{});
    return as(double{});
  }
  std::ifstream& in_;
  Format format_;
};

// The header up to end_header; leaves `in` at the first byte of the body.
std::vector<Element> read_header(const std::string& path, std::ifstream& in, Format* format) {
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != "ply") {
    std::string shown = line.substr(0, 40);
    for (char& c : shown)
      if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    throw_file_problem(path, "does not start with 'ply': not a PLY file (its first line is '" + shown + "')");
  }
  std::vector<Element> elements;
  bool have_format = false;
  for (long number = 2; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    const std::string where = "line " + std::to_string(number) + ": ";
    if (word == "end_header") {
      if (!have_format) throw_file_problem(path, "has no 'format' line in its header");
      return elements;
    }
    if (word == "format") {
      std::string name;
      words >> name;
      if (name == "ascii") *format = Format::Ascii;
      else if (name == "binary_little_endian") *format = Format::BinaryLittle;
      else if (name == "binary_big_endian") *format = Format::BinaryBig;
      else throw_file_problem(path, where + "unknown PLY format '" + name.substr(0, 40) + "'");
      have_format = true;
    } else if (word == "element") {
      Element e;
      if (!(words >> e.name >> e.count) || e.count < 0)
        throw_file_problem(path, where + "an element needs a name and a count ('" + line.substr(0, 40) + "')");
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) throw_file_problem(path, where + "a property before any element");
      Property p;
      words >> p.type;
      if (p.type == "list") words >> p.count_type >> p.type;
      words >> p.name;
      if (type_size(p.type) == 0 || (!p.count_type.empty() && type_size(p.count_type) == 0) || p.name.empty())
        throw_file_problem(path, where + "unknown property type in '" + line.substr(0, 60) + "'");
      elements.back().properties.push_back(p);
    } else if (word != "comment" && word != "obj_info" && !word.empty()) {
      throw_file_problem(path, where + "'" + word.substr(0, 40) + "' is not a PLY header keyword");
    }
    if (number > 100000) break;
  }
  throw_file_problem(path, "has no end_header line: its header is incomplete");
}

}  // namespace

void check_ply_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  Format format = Format::Ascii;
  const std::vector<Element> elements = read_header(path, in, &format);
  long vertices = -1, faces = 0;
  for (const Element& e : elements) {
    if (e.name == "vertex" && vertices < 0) vertices = e.count;
    if (e.name == "face") faces = e.count;
  }
  if (vertices < 0) throw_file_problem(path, "has no vertex element in its header");
  BodyReader body(in, format);
  double value = 0;
  std::string text;
  bool number = true;
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    for (long row = 0; row < e.count; ++row) {
      const std::string what = e.name + " " + std::to_string(row);
      auto next = [&](const std::string& type) {
        if (!body.next(type, &value, &text, &number))
          throw_file_problem(path, "is truncated: its header announces " + std::to_string(vertices) +
                                       " vertices and " + std::to_string(faces) + " faces; the data ends in " + what);
        if (!number) throw_file_problem(path, what + " has a value '" + text.substr(0, 40) + "' that is not a number");
      };
      for (const Property& p : e.properties) {
        if (p.count_type.empty()) {
          next(p.type);
          const bool coordinate = is_vertex && (p.name == "x" || p.name == "y" || p.name == "z");
          const std::string problem = coordinate ? coordinate_problem(value, text) : "";
          if (!problem.empty()) throw_file_problem(path, what + " has " + problem);
          continue;
        }
        next(p.count_type);
        const double corners = value;
        const bool indices = is_face && (p.name == "vertex_indices" || p.name == "vertex_index");
        if (indices && corners < 3)
          throw_file_problem(path, what + " has " + text + " corners; a face needs at least 3");
        if (!(corners >= 0 && corners < 1e9))
          throw_file_problem(path, what + " has a list of " + text + " values");
        for (long k = 0; k < static_cast<long>(corners); ++k) {
          next(p.type);
          if (indices && (value < 0 || value >= static_cast<double>(vertices) || value != std::floor(value)))
            throw_file_problem(path, what + " uses vertex " + text + " but the file has " + std::to_string(vertices) +
                                         " vertices (PLY numbers them from 0)");
        }
      }
    }
  }
}

}  // namespace genbrep::detail
