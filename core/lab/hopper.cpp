// hopper (seed 000 §2.7.6): a wedge hopper slice with periodic front and back is filled with the
// gate closed, the bed settles, the gate opens, and the discharged mass is recorded over time.
//
// The reference rate is Beverloo's law for the outlet used, corrected for the converging walls:
//
// 1. Beverloo (C = 0.58, k = 1.5, the circular-orifice constants) in its slot form through the
//    hydraulic diameter: the circular law W = C rho_b sqrt(g) D^(5/2) written as
//    W = (4/pi) C rho_b sqrt(g) A sqrt(D_h) (A = pi D^2/4, D_h = D) holds for any orifice with
//    its area A and hydraulic diameter D_h = 4 A / perimeter, both shrunk by the empty annulus
//    k d. A slot of width b and length L >> b (here L is the periodic slice depth, no end walls)
//    has A = L (b - k d) and D_h = 2 (b - k d), so
//      W_B = (4 sqrt(2) / pi) C rho_b sqrt(g) L (b - k d)^(3/2)
//    (= 1.04 rho_b sqrt(g) L (b-kd)^1.5, close to the slot coefficient 1.03 of Myers and
//    Sellers). rho_b is the bulk density of the settled bed (measured: solid fraction in a box in
//    the middle of the bed times the particle density) and d the largest particle diameter.
// 2. Beverloo's law is for a flat-bottomed bin, where the flowing core is bounded by stagnant
//    material at about phi_d from the horizontal. Walls steeper than that boundary (half angle
//    theta from the vertical < 90 deg - phi_d) speed the flow up by Rose and Tanaka's factor
//      F = (tan theta tan phi_d)^(-0.35),   F = 1 otherwise
//    (Rose & Tanaka 1956; Nedderman, Statics and Kinematics of Granular Materials, 1992, ch. 10),
//    with phi_d = 45 deg, the usual value for a flat bottom. The 20 deg default wedge has
//    F = 1.42.
#include "core/lab/hopper.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"
#include "core/common/line_fit.hpp"
#include "core/common/rng.hpp"
#include "core/io/vtk.hpp"
#include "core/lab/bed.hpp"
#include "core/metrics/bulk.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::lab {

namespace {
constexpr double kBeverlooC = 0.58, kBeverlooK = 1.5;
constexpr double kStagnantZoneAngle = 45.0 * M_PI / 180.0;  // phi_d from the horizontal
}  // namespace

double rose_tanaka_factor(double half_angle) {
  if (half_angle >= 0.5 * M_PI - kStagnantZoneAngle) return 1.0;
  return std::pow(std::tan(half_angle) * std::tan(kStagnantZoneAngle), -0.35);
}

LabOutput run_hopper(const MaterialModel& material, const Settings& values,
                     const RunOptions& options) {
  const auto s = read_settings<HopperSettings>(values, "settings");
  sim::World w = make_material_world(material, options);
  const auto sizes = material.simulated_sizes();
  const double density = material.simulated_density();
  const double r_max = particles::max_radius(sizes);
  const double d = 2.0 * r_max;
  const double b = s.outlet * d, depth = s.depth * d;
  const double theta = s.half_angle * M_PI / 180.0;

  // Size the hopper for the bed: the wedge of height h holds (b + h tan) h depth of bulk; the
  // particles (solid fraction ~0.6) should fill the wedge and a little of the bin above.
  Rng rng(options.seed);
  const double solid = expected_solid_volume(sizes, s.particles, options.seed);
  const double area = solid / (0.6 * depth);  // x-z area of the settled bed
  const double t = std::tan(theta);
  // (b + h t) h = area  ->  h = (-b + sqrt(b^2 + 4 t area)) / (2 t)
  const double h = std::max(4.0 * d, (-b + std::sqrt(b * b + 4.0 * t * area)) / (2.0 * t));
  const double top = b + 2.0 * h * t;             // width at the top of the wedge
  const double bin = 3.0 * area / top + 4.0 * d;  // room for the loose insertion
  w.domain.lo = {-1e3, 0.0, -1e3};
  w.domain.hi = {1e3, depth, 1e3};
  w.domain.periodic = {false, true, false};
  w.walls.push_back(walls::make_wall(
      "hopper", walls::make_wedge_hopper(theta, b, h, bin, -2.0 * d, depth + 2.0 * d), kWallDie));
  w.walls.push_back(walls::make_wall("gate", walls::Plane{{0, 0, 0}, {0, 0, 1}}, kWallBottom));

  particles::InsertRequest req = material_insert_request(
      material, particles::BoxRegion{{-0.5 * top, 0.0, h}, {0.5 * top, depth, h + bin}},
      static_cast<std::size_t>(s.particles));
  // Spheres stay inside the region, so none overlaps a periodic image across y = 0 / depth.
  const PhaseCost filled = timed_fill(w, req, rng, s.time_step_safety, material.factors().time);

  sim::HealthLimits limits;
  limits.lo = {-top - bin, -1e3, -(h + bin) * 4.0 - 1.0};
  limits.hi = {top + bin, 1e3, 2.0 * (h + bin)};
  limits.max_kinetic_energy =
      1e3 * w.particles.total_mass() * std::max(norm(w.gravity), 1.0) * (h + bin);

  // 1. Fill, prepare (a lid at the top of the fill region) and settle with the gate closed.
  BedSpec settle_spec;
  settle_spec.max_settle_time = 1.5;
  const PreparedBed built =
      prepare_and_settle(w, material, settle_spec, limits, h + bin, options.seed);

  // Bulk density of the settled bed: a box in the middle of the wedge, two diameters from the
  // walls (at its height the wedge is wider than the box).
  const double z0 = 0.3 * h, z1 = std::min(0.9 * h, metrics::bed_top(w) - 2.0 * d);
  const double half = 0.5 * (b + 2.0 * z0 * t) - 2.0 * d;
  double phi = 0.6;
  if (half > d && z1 > z0 + d)
    phi = metrics::solid_fraction(w, {-half, 0.0, z0}, {half, depth, z1});
  const double rho_b = phi * density;

  LabOutput out;
  out.add_phase(filled, {});
  if (built.prepared.steps > 0) out.add_phase(built.prepared, {});
  out.add_phase(built.settled, {"bulk_density", "beverloo_ratio"});
  if (!options.snapshot_dir.empty()) {
    io::write_particles_vtk(options.snapshot_dir + "/hopper_settled_particles.vtk", w);
    io::write_walls_vtk(options.snapshot_dir + "/hopper_walls.vtk", w, top);
    out.snapshots = {options.snapshot_dir + "/hopper_settled_particles.vtk",
                     options.snapshot_dir + "/hopper_walls.vtk"};
  }

  // 2. Open the gate (moved far away: no wall is removed, so the bed keeps its contact history).
  std::get<walls::Plane>(w.walls[1].shape).point = {0, 0, -1e3};
  w.walls[1].pivot = {0, 0, -1e3};

  // Discharged particles (centre below z = -2 d) are parked, kinematic, on a lattice under the
  // hopper, so they neither fall for ever nor touch anything.
  const double total_mass = w.particles.total_mass();
  const double park_z = -(h + bin) * 2.0;
  const int per_row = std::max(1, static_cast<int>(top / (3.0 * r_max)));
  const int per_col = std::max(1, static_cast<int>(depth / (3.0 * r_max)));
  int parked = 0;
  std::vector<char> gone(w.particles.size(), 0);
  double discharged = 0.0, last_discharge = 0.0;
  const double t0 = w.time;
  Series curve{{"time", "discharged_mass"}, {}};
  curve.rows.push_back({0.0, 0.0});
  bool arched = false;
  const long check = std::max<long>(1, std::lround(0.002 / w.dt));
  auto each = [&](sim::World& world) {
    if (world.step_count % check != 0) return true;
    auto& p = world.particles;
    bool any = false;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (gone[i] || p.x[i].z > -2.0 * d) continue;
      any = true;
      const int k = parked++;
      discharged += p.park(i,
                           {-0.5 * top + 3.0 * r_max * (k % per_row + 0.5),
                            3.0 * r_max * ((k / per_row) % per_col + 0.5),
                            park_z - 3.0 * r_max * (k / (per_row * per_col))},
                           gone);
    }
    const double tt = world.time - t0;
    if (any) {
      last_discharge = tt;
      curve.rows.push_back({tt, discharged});
    }
    if (discharged >= 0.999 * total_mass) return false;
    if (tt - last_discharge > s.arch_time) {
      arched = true;
      return false;
    }
    if (options.progress) options.progress(std::min(1.0, tt / s.max_time));
    return tt < s.max_time;
  };
  limits.lo.z = park_z - 3.0 * r_max * (s.particles / (per_row * per_col) + 2) - 1.0;
  const PhaseClock discharge_clock(w);
  run_checked(w, std::lround(s.max_time / w.dt) + 1, limits, each);
  out.add_phase(discharge_clock.stop(w, "discharge", "hopper empty or arched within max_time",
                                     arched || discharged >= 0.999 * total_mass),
                {"discharge_rate", "beverloo_ratio", "arched", "discharged_fraction"});

  // Discharge rate: least-squares slope of the mass-time curve between 15 % and 75 % of the
  // discharged mass (after the start-up, before the hopper runs empty).
  const double m_end = discharged;
  LineFit fit;
  for (const auto& row : curve.rows)
    if (row[1] >= 0.15 * m_end && row[1] <= 0.75 * m_end) fit.add(row[0], row[1]);
  double rate = 0.0;
  if (fit.points() >= 3 && fit.defined())
    rate = fit.slope();
  else if (curve.rows.size() >= 2 && curve.rows.back()[0] > 0.0)
    rate = m_end / curve.rows.back()[0];

  // Beverloo slot form with the hopper's wall factor (header comment).
  const double g = norm(w.gravity);
  const double opening = std::max(0.0, b - kBeverlooK * d);
  const double beverloo = 4.0 * std::sqrt(2.0) / M_PI * kBeverlooC * rho_b * std::sqrt(g) * depth *
                          std::pow(opening, 1.5) * rose_tanaka_factor(theta);
  out.metrics["discharge_rate"] = rate;
  out.metrics["arched"] = arched ? 1.0 : 0.0;
  out.metrics["beverloo_rate"] = beverloo;
  out.metrics["beverloo_ratio"] = beverloo > 0.0 ? rate / beverloo : 0.0;
  out.metrics["discharged_fraction"] = m_end / total_mass;
  out.metrics["bulk_density"] = rho_b;
  out.series["discharge"] = std::move(curve);
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
