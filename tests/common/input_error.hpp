#pragma once
// The field an InputError names, from a test: what `run` throws, or "" when it does not.
#include <functional>
#include <string>

#include "core/common/error.hpp"

namespace demcal::test {

inline std::string where_of(const std::function<void()>& run) {
  try {
    run();
  } catch (const InputError& e) {
    return e.where();
  }
  return "";
}

}  // namespace demcal::test
