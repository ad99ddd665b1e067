#pragma once
// JSON helpers shared by the subcommands.
#include <nlohmann/json.hpp>

#include "core/common/vec3.hpp"

namespace demcal::cli {

inline nlohmann::json to_json(const Vec3& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

}  // namespace demcal::cli
