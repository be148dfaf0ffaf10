// mesh/detail/file_check.h — a first reading of a mesh file, before OpenMesh's.
// OpenMesh's readers skip what they cannot parse: a vertex line with "nan" or "1e300"
// disappears and the faces using it point nowhere, random bytes read as an empty OBJ, a
// truncated binary STL is taken for ASCII. check_mesh_file reads the file once in its own
// terms and throws Error{FileError} (cannot open) or Error{InvalidInput} (contents) with
// the file, the problem and where it is (line, vertex or face number). A file it passes
// holds well-formed numbers and in-range face indices, so OpenMesh reads it as written.
// Complexity: one pass over the file, O(1) memory beyond one line or one PLY row.
#pragma once
#include <string>

namespace genbrep::detail {

void check_mesh_file(const std::string& path);

// The PLY part of check_mesh_file (file_check_ply.cpp); `path` is open and non-empty.
void check_ply_file(const std::string& path);

// "a NaN coordinate ('nan')", "an infinite coordinate ('1e999')", "a coordinate of 1e+300,
// beyond ±1e+12", or "" for a usable value; `token` is the text it was read from.
std::string coordinate_problem(double value, const std::string& token);

// Error{InvalidInput, "'<path>' <problem>", "mesh"}.
[[noreturn]] void throw_file_problem(const std::string& path, const std::string& problem);

}  // namespace genbrep::detail
