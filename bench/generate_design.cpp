// generate_design — writes one seeded level-set design with its solids and meta.json
// (tests/support/corpus_design.h says what it draws). The same arguments give the same bytes.
//   generate_design --seed N --out DIR [--variation V] [--extraction E] [--lattice yes|no]
#include <iostream>
#include <string>

#include "corpus_design.h"

int main(int argc, char** argv) {
  const char* usage =
      "usage: generate_design --seed N --out DIR [--variation none|scale|rotate|move|nudge|tolerance]\n"
      "                       [--extraction smoothed|staircase|shrunk] [--lattice yes|no]\n";
  genbrep::testing::GenerateOptions options;
  std::string out, seed;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) {
      std::cerr << "generate_design: " << flag << " needs a value\n" << usage;
      return 2;
    }
    const std::string value = argv[++i];
    if (flag == "--seed") seed = value;
    else if (flag == "--out") out = value;
    else if (flag == "--variation") options.variation = value;
    else if (flag == "--extraction") options.extraction = value;
    else if (flag == "--lattice") options.lattice = value;
    else {
      std::cerr << "generate_design: unknown option '" << flag << "'\n" << usage;
      return 2;
    }
  }
  if (seed.empty() || out.empty() || seed.find_first_not_of("0123456789") != std::string::npos) {
    std::cerr << usage;
    return 2;
  }
  try {
    const auto generated = genbrep::testing::generate_case(std::stoull(seed), options);
    genbrep::testing::write_case(out, generated);
    std::cout << "wrote " << out << " (" << generated.design.triangles.rows() << " design triangles, "
              << generated.solids.size() << " solids)\n";
  } catch (const std::exception& e) {
    std::cerr << "generate_design: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
