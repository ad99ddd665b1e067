// packing (seed 000 §2.7.1, §3.1): a bed built in a cylindrical die by one of the four methods
// of §2.7.1, its solid fraction and coordination number measured in a sampling volume away from
// the walls.
#include "core/lab/packing.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/common/rng.hpp"
#include "core/lab/bed.hpp"
#include "core/metrics/bulk.hpp"

namespace demcal::lab {
namespace {

/// The particle law with its van der Waals range cut to contact (D_max = 1.01 D_min): the
/// "cohesion when in contact" of seed 000 §2.7.1 methods 2-4.
contact::ContactLawSpec contact_only(contact::ContactLawSpec spec) {
  if (spec.cohesion.model == "van_der_waals") {
    const double d_min =
        spec.cohesion.params.count("d_min") ? spec.cohesion.params["d_min"] : 4e-10;
    spec.cohesion.params["d_max"] = 1.01 * d_min;
  }
  return spec;
}

}  // namespace

LabOutput run_packing(const MaterialModel& material, const Settings& values,
                      const RunOptions& options) {
  const auto s = read_settings<PackingSettings>(values, "settings");
  const int method = static_cast<int>(std::lround(s.method));
  BedSpec bed;
  bed.particles = static_cast<std::size_t>(s.particles);
  bed.time_step_safety = s.time_step_safety;
  const PhaseClock fill_clock;
  sim::World w = make_die_world(material, bed, options);
  const PhaseCost filled = fill_clock.stop(w, "fill", "all particles inserted", true);
  const double radius = std::get<walls::Cylinder>(w.walls[1].shape).radius;
  double top = 0.0;
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    top = std::max(top, w.particles.x[i].z + w.particles.radius[i]);
  const auto limits = die_limits(w, radius, top);
  auto& p = w.particles;
  double d_mean = 0.0;
  for (double r : p.radius) d_mean += 2.0 * r;
  d_mean /= static_cast<double>(p.size());
  const Vec3 g = w.gravity;
  const auto full_law = w.pair_law(0, 0);
  const auto touch_law = simulated_law(material, contact_only(material.particle_law));

  const PhaseClock prepare_clock(w);
  if (method == 1 || method == 2) {
    // Free motion without cohesion and gravity, under a lid at the top of the insertion region.
    contact::ContactLawSpec plain = material.particle_law;
    plain.cohesion = {"none", {}};
    w.set_pair_law(0, 0, simulated_law(material, plain));
    w.gravity = {};
    w.walls.push_back(walls::make_wall("lid", walls::Plane{{0, 0, top}, {0, 0, -1}}, kWallDie));
    const double v_a = s.agitation_speed > 0.0 ? s.agitation_speed : std::sqrt(norm(g) * d_mean);
    const double t_a = s.agitation_time > 0.0 ? s.agitation_time : 3.0 * d_mean / v_a;
    const double t_c = s.cluster_time > 0.0 ? s.cluster_time : t_a;
    Rng rng(options.seed ^ 0xa917a7e);
    for (auto& v : p.v) v = {v_a * rng.normal(), v_a * rng.normal(), v_a * rng.normal()};
    run_checked(w, std::lround(t_a / w.dt), limits);
    if (method == 1) {
      // Stop, then van der Waals on (its full range) without gravity: clusters form.
      for (auto& v : p.v) v = {};
      for (auto& o : p.omega) o = {};
      w.set_pair_law(0, 0, full_law);
    } else {
      w.set_pair_law(0, 0, touch_law);
    }
    run_checked(w, std::lround(t_c / w.dt), limits);
    w.walls.pop_back();
    w.gravity = g;
  } else {
    w.set_pair_law(0, 0, touch_law);
  }

  if (method == 3) {
    // Terminal settling velocity (Stokes drag in air, mu = 1.81e-5 Pa s) of each simulated
    // particle, or the given cap; settling takes longer, so the time limit is raised.
    constexpr double kMuAir = 1.81e-5;
    std::vector<double> cap(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double rho = p.mass[i] / (4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3));
      cap[i] = s.terminal_velocity > 0.0
                   ? s.terminal_velocity
                   : rho * norm(g) * 4.0 * p.radius[i] * p.radius[i] / (18.0 * kMuAir);
    }
    const double fall = std::max(top / *std::min_element(cap.begin(), cap.end()), 0.0);
    run_checked(w, std::lround(std::min(fall, 20.0) / w.dt), limits, [&](sim::World& world) {
      for (std::size_t i = 0; i < world.particles.size(); ++i) {
        const double v = norm(world.particles.v[i]);
        if (v > cap[i]) world.particles.v[i] *= cap[i] / v;
      }
      return true;
    });
  }
  const PhaseCost prepared = prepare_clock.stop(w, "agitate or fall", "its fixed time", true);
  const PhaseCost settled = settle(w, bed, limits);

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
  if (prepared.steps > 0) out.add_phase(prepared, {});
  out.add_phase(settled, {"solid_fraction", "coordination_number"});
  write_snapshot(w, options, "packing", out);
  out.metrics["solid_fraction"] = metrics::solid_fraction(w, region);
  out.metrics["coordination_number"] = metrics::coordination_number(w, region);
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
