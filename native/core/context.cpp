#include "core/context.h"

#include "core/error.h"

namespace genbrep {

void Context::step(const std::string& stage, double fraction) const {
  if (progress_ && !progress_(stage, fraction)) {
    throw Error(Code::Cancelled, "conversion cancelled during " + stage, stage);
  }
}

}  // namespace genbrep
