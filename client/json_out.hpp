#pragma once
// JSON helpers shared by the subcommands.
#include <nlohmann/json.hpp>

#include "core/common/vec3.hpp"
#include "core/lab/cost.hpp"

namespace demcal::cli {

inline nlohmann::json to_json(const Vec3& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

/// The cost block of a lab result: time step and its limit, steps, times, throughput, phases.
inline nlohmann::json to_json(const lab::RunCost& c) {
  nlohmann::json phases = nlohmann::json::array();
  for (const auto& p : c.phases)
    phases.push_back({{"name", p.name},
                      {"target", p.target},
                      {"steps", p.steps},
                      {"simulated_time_s", p.simulated_time},
                      {"wall_seconds", p.wall_seconds},
                      {"reached", p.reached}});
  return {{"time_step_s", c.time_step},
          {"critical_time_step_s", c.critical_time_step},
          {"time_step_limit", c.time_step_limit},
          {"particles", c.particles},
          {"steps", c.steps},
          {"simulated_time_s", c.simulated_time},
          {"wall_seconds", c.wall_seconds},
          {"particle_steps_per_second", c.particle_steps_per_second()},
          {"phases", phases}};
}

}  // namespace demcal::cli
