#include "core/sim/threads.hpp"

#include <unistd.h>

#include <cstdlib>

namespace demcal::sim {

void wait_passively(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;  // the caller's choice stands
  if (::setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
  ::execv("/proc/self/exe", argv);  // returns only on failure
}

}  // namespace demcal::sim
