// tests/support/corpus_design.h — seeded level-set designs drawn the way real solver output
// looks, for the corpus benchmark (bench/corpus) and its tests.
//
// A case is a design mesh, its input solids with their roles, and meta.json. From one seed
// the generator draws, in voxel units:
//   - keep-ins: boxes (some tilted), plates with holes, cylinders, tubes, and bosses: a tube
//     on a tilted axis with a coaxial keep-out bore whose wall is the boss's inner wall
//     exactly or within 1e-9 h to 1e-3 h;
//   - organic members joining keep-ins at their faces, edges and corners: struts (capsules
//     1–6 voxels thick), branching trees, thin webs; some graze a keep-out at 0.5–2 voxels;
//   - seeds (boxes, or disks round a keep-in hub) eroded by pockets and through-holes;
//   - sometimes one large lattice component of genus 20–100 joining many keep-in pads,
//     and sometimes a closed organic shell that touches no solid;
// then extracts the design on a voxel grid one of three ways (smoothed level set, raw
// staircase of thresholded density, or shrunk so that it falls short of the keep-ins by up
// to 2 h) and applies a variation a user would not expect to matter (scale 1e-3–1e3,
// rotation, a far move, solids nudged by up to h/2, tolerance 0.5–3 h). The base design
// and the variation come from separate streams, so one seed with another variation gives
// the same design under that change. Output is a pure function of the seed and options:
// the same seed gives byte-identical files.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.h"

namespace genbrep::testing {

struct GenerateOptions {
  // "random" draws from the seed; otherwise one of "none", "scale", "rotate", "move",
  // "nudge", "tolerance".
  std::string variation = "random";
  // "random" draws from the seed; otherwise "smoothed", "staircase" or "shrunk".
  std::string extraction = "random";
  // "random" draws from the seed; "yes" or "no" forces the large lattice component.
  std::string lattice = "random";
};

struct GeneratedSolid {
  std::string file;  // keep_in_0.obj, keep_out_1.obj, seed_0.obj
  std::string name;  // what it is: "boss_2", "plate_0", "bore_2"
  Role role = Role::KeepIn;
  TriangleMesh mesh;
};

struct GeneratedCase {
  TriangleMesh design;
  std::vector<GeneratedSolid> solids;
  std::string meta_json;  // roles, tolerance, voxel, grid, what was drawn
};

GeneratedCase generate_case(uint64_t seed, const GenerateOptions& options = {});

// Writes DIR/design.obj, one OBJ per solid and DIR/meta.json (creates DIR).
void write_case(const std::string& dir, const GeneratedCase& generated);

}  // namespace genbrep::testing
