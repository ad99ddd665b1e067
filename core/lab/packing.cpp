// packing (seed 000 §2.7.1, §3.1): a bed built in a cylindrical die, its solid fraction and
// coordination number measured in a sampling volume away from the walls.
#include "core/lab/packing.hpp"

#include <algorithm>
#include <array>

#include "core/lab/bed.hpp"
#include "core/metrics/bulk.hpp"

namespace demcal::lab {

LabOutput run_packing(const MaterialModel& material, const Settings& values,
                      const RunOptions& options) {
  const auto s = read_settings<PackingSettings>(values, "settings");
  BedSpec bed;
  bed.particles = static_cast<std::size_t>(s.particles);
  bed.time_step_safety = s.time_step_safety;
  sim::World w = make_die_world(material, bed, options);
  const double radius = std::get<walls::Cylinder>(w.walls[1].shape).radius;
  double top = 0.0;
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    top = std::max(top, w.particles.x[i].z + w.particles.radius[i]);
  settle(w, bed, die_limits(w, radius, top));

  const double d_max =
      2.0 * *std::max_element(w.particles.radius.begin(), w.particles.radius.end());
  const double margin = s.wall_margin * d_max;
  const double bed_top = metrics::bed_top(w);
  const metrics::SamplingCylinder region{radius - margin, margin, bed_top - margin};
  if (region.radius <= 0.0 || region.z_hi <= region.z_lo)
    throw InputError("settings.particles", "the bed is too small for a sampling volume " +
                                               std::to_string(s.wall_margin) +
                                               " diameters from its walls; use more particles");
  LabOutput out;
  out.metrics["solid_fraction"] = metrics::solid_fraction(w, region);
  out.metrics["coordination_number"] = metrics::coordination_number(w, region);
  return out;
}

}  // namespace demcal::lab
