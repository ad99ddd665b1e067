// packing (seed 000 §2.7.1, §3.1): a bed built in a cylindrical die by the material's
// preparation (one of the four methods of §2.7.1), its solid fraction and coordination number
// measured in a sampling volume away from the walls.
#include <algorithm>
#include <array>
#include <cmath>

#include "core/common/rng.hpp"
#include "core/lab/bed.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/piston.hpp"
#include "core/metrics/bulk.hpp"
#include "core/model/packing_settings.hpp"

namespace demcal::lab {

LabOutput PackingTest::run(const MaterialModel& material, const Settings& values,
                           const RunOptions& options) {
  const auto s = read_settings<PackingSettings>(values, "settings");
  BedSpec bed;
  bed.particles = static_cast<std::size_t>(s.particles);
  bed.time_step_safety = s.time_step_safety;
  const PhaseClock fill_clock;
  sim::World w = make_die_world(material, bed, options);
  const PhaseCost filled = fill_clock.stop(w, "fill", "all particles inserted", true);
  const double radius = die_radius(w);
  const double top = metrics_top(w);
  const auto limits = die_limits(w, radius, top);
  const PreparedBed built = prepare_and_settle(w, material, bed, limits, top, options.seed);
  auto& p = w.particles;
  // The settled bed before any cut, sampled as the piston tests sample theirs.
  const double h0 = metrics_top(w);
  const metrics::SamplingCylinder settled = bed_sample(w, radius, h0);
  const bool sampled = settled.radius > 0.0 && settled.z_hi > settled.z_lo;
  Series settled_bed{{"h0_m", "solid_fraction", "coordination_number"},
                     {{h0, sampled ? metrics::solid_fraction(w, settled) : 0.0,
                       sampled ? metrics::coordination_number(w, settled) : 0.0}}};

  if (s.cut_fraction < 1.0) {
    // The bed cut to height (seed 000 §2.7.1: the simulation box shrunk after settling).
    const double cut = s.cut_fraction * metrics::bed_top(w);
    std::vector<char> drop(p.size(), 0);
    for (std::size_t i = 0; i < p.size(); ++i) drop[i] = p.x[i].z > cut ? 1 : 0;
    w.remove_particles(drop);
    w.prepare();
  }

  const double d_max = 2.0 * *std::max_element(p.radius.begin(), p.radius.end());
  const double margin = s.wall_margin * d_max;
  const double bed_top = metrics::bed_top(w);
  const metrics::SamplingCylinder region{radius - margin, margin, bed_top - margin};
  if (region.radius <= 0.0 || region.z_hi <= region.z_lo)
    throw InputError("settings.particles", "the bed is too small for a sampling volume " +
                                               std::to_string(s.wall_margin) +
                                               " diameters from its walls; use more particles");
  LabOutput out;
  out.add_phase(filled, {});
  if (built.prepared.steps > 0) out.add_phase(built.prepared, {});
  out.add_phase(built.settled, {"solid_fraction", "coordination_number"});
  write_snapshot(w, options, "packing", out);
  out.metrics["solid_fraction"] = metrics::solid_fraction(w, region);
  out.metrics["coordination_number"] = metrics::coordination_number(w, region);
  out.series["settled_bed"] = std::move(settled_bed);
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
