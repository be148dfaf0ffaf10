#include "core/error.h"

namespace genbrep {

const char* code_name(Code code) {
  switch (code) {
    case Code::InvalidInput: return "invalid_input";
    case Code::FileError: return "file_error";
    case Code::Cancelled: return "cancelled";
    case Code::StageFailure: return "stage_failure";
    case Code::Internal: return "internal";
  }
  return "internal";
}

Error::Error(Code code, std::string message, std::string stage)
    : std::runtime_error(std::move(message)), code_(code), stage_(std::move(stage)) {}

Error Error::with_stage(const std::string& stage) const {
  return Error(code_, what(), stage_.empty() ? stage : stage_);
}

}  // namespace genbrep
