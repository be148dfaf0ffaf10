// pipeline/output.h — files the command line writes into its output folder.
// partition.ply: the design mesh (binary little-endian PLY, double coordinates) with int
// face properties `solid` (first incident solid, -1 organic) and `component` (organic
// component, -1 incident). Throws Error{FileError} when a file cannot be written.
#pragma once
#include <string>

#include "pipeline/pipeline.h"

namespace genbrep {

void write_text_file(const std::string& path, const std::string& text);
// A cage as an OBJ of quads (Blender imports it as an editable mesh; add a Subdivision
// Surface modifier with the cage's scheme to see the fitted surface).
void write_cage_obj(const std::string& path, const QuadCage& cage);
// composed.obj (plain) and composed.ply with an int face property `source`: the input
// solid's index, or -1 - c for organic component c.
void write_composed(const std::string& obj_path, const std::string& ply_path, const TriangleMesh& mesh);
void write_partition_ply(const std::string& path, const TriangleMesh& design,
                         const Partition& partition);

}  // namespace genbrep
