#include "core/types.h"

namespace genbrep {

const char* role_name(Role role) {
  switch (role) {
    case Role::KeepIn: return "keep_in";
    case Role::KeepOut: return "keep_out";
    case Role::Seed: return "seed";
  }
  return "keep_in";
}

std::string describe(const SolidInput& solid) {
  const char* role = solid.role == Role::KeepIn    ? "keep-in"
                     : solid.role == Role::KeepOut ? "keep-out"
                                                   : "seed";
  return std::string(role) + " '" + solid.name + "'";
}

bool parse_role(const std::string& name, Role* role) {
  if (name == "keep_in" || name == "keep-in") *role = Role::KeepIn;
  else if (name == "keep_out" || name == "keep-out") *role = Role::KeepOut;
  else if (name == "seed") *role = Role::Seed;
  else return false;
  return true;
}

}  // namespace genbrep
