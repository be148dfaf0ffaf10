// core/error.h — the one exception type every stage throws.
// Bad input, or a stage that cannot recover, throws genbrep::Error{code, message, stage}.
// The CLI prints it as one line; the Python binding maps it to genbrep_native.ConversionError.
// Numerical trouble a stage can handle is reported as a diagnostic instead (see Diagnostics).
#pragma once
#include <stdexcept>
#include <string>
#include <vector>

namespace genbrep {

enum class Code {
  InvalidInput,   // the user's data is unusable as given (names the object and the problem)
  FileError,      // a file cannot be read or written
  Cancelled,      // progress callback asked to stop
  StageFailure,   // a stage could not produce a valid result
  Internal,       // a broken invariant inside genbrep (a bug)
};

const char* code_name(Code code);

class Error : public std::runtime_error {
 public:
  Error(Code code, std::string message, std::string stage = {});
  Code code() const { return code_; }
  const std::string& stage() const { return stage_; }
  // Stages may catch and re-throw with their name attached.
  Error with_stage(const std::string& stage) const;

 private:
  Code code_;
  std::string stage_;
};

// Human-readable notes a stage attaches to its result: counts of handled trouble,
// tolerances chosen, repairs made. They go into report.json, never to stdout.
using Diagnostics = std::vector<std::string>;

}  // namespace genbrep

// Invariant checks that input can break: throw in every build, never assert/abort.
#define GENBREP_CHECK(condition, code, message)                     \
  do {                                                              \
    if (!(condition)) throw ::genbrep::Error((code), (message));    \
  } while (0)
