// core/context.h — progress and cancellation, passed by reference into long stages.
// It carries no results: a stage's output is its return value. step() forwards
// (stage, fraction in [0,1]) to the caller's callback; a false return cancels, and
// step() then throws Error{Cancelled}. Calls are cheap when no callback is set.
#pragma once
#include <functional>
#include <string>

namespace genbrep {

using ProgressCallback = std::function<bool(const std::string& stage, double fraction)>;

class Context {
 public:
  Context() = default;
  explicit Context(ProgressCallback progress) : progress_(std::move(progress)) {}
  // Reports progress of `stage`; throws Error{Cancelled} if the callback returns false.
  void step(const std::string& stage, double fraction) const;

 private:
  ProgressCallback progress_;
};

}  // namespace genbrep
