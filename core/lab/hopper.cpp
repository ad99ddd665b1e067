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
#include "core/lab/bed.hpp"
#include "core/lab/stages.hpp"
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

namespace {

/// The wedge sized for its bed, filled, prepared and settled on the closed gate.
struct Hopper {
  sim::World w;
  sim::HealthLimits limits;
  double r_max = 0.0, d = 0.0;  ///< largest simulated particle radius and diameter (m)
  double b = 0.0, depth = 0.0;  ///< slot width and periodic slice depth (m)
  double theta = 0.0;           ///< wall angle from the vertical (rad)
  double h = 0.0, bin = 0.0;    ///< wedge height and the bin above it (m)
  double top = 0.0;             ///< width at the top of the wedge (m)
  double rho_b = 0.0;           ///< bulk density of the settled bed (kg/m^3)
};

/// What the hopper keeps beside its world, in a checkpoint record (core/lab/stages.hpp).
template <class A, RecordOf<Hopper> H>
void record_fields(A& a, H& hp) {
  a.field(hp.limits);
  for (auto* v :
       {&hp.r_max, &hp.d, &hp.b, &hp.depth, &hp.theta, &hp.h, &hp.bin, &hp.top, &hp.rho_b})
    a.field(*v);
}

/// Sizes the hopper for the bed (the wedge of height h holds (b + h tan) h depth of bulk; the
/// particles, solid fraction ~0.6, fill the wedge and a little of the bin above), fills,
/// prepares (a lid at the top of the fill region) and settles with the gate closed, and reads
/// the bulk density in a box in the middle of the wedge, two diameters from the walls.
Hopper build_hopper(const MaterialModel& material, const HopperSettings& s,
                    const RunOptions& options, LabOutput& out) {
  Hopper hp;
  sim::World& w = hp.w;
  w = make_material_world(material, options);
  const auto sizes = material.simulated_sizes();
  hp.r_max = particles::max_radius(sizes);
  hp.d = 2.0 * hp.r_max;
  const double d = hp.d;
  hp.b = s.outlet * d;
  hp.depth = s.depth * d;
  hp.theta = s.half_angle * M_PI / 180.0;
  Rng rng(options.seed);
  const double solid = expected_solid_volume(sizes, s.particles, options.seed);
  const double area = solid / (0.6 * hp.depth);  // x-z area of the settled bed
  const double t = std::tan(hp.theta);
  // (b + h t) h = area  ->  h = (-b + sqrt(b^2 + 4 t area)) / (2 t)
  hp.h = std::max(4.0 * d, (-hp.b + std::sqrt(hp.b * hp.b + 4.0 * t * area)) / (2.0 * t));
  hp.top = hp.b + 2.0 * hp.h * t;
  hp.bin = 3.0 * area / hp.top + 4.0 * d;  // room for the loose insertion
  w.domain.lo = {-1e3, 0.0, -1e3};
  w.domain.hi = {1e3, hp.depth, 1e3};
  w.domain.periodic = {false, true, false};
  w.walls.push_back(walls::make_wall(
      "hopper",
      walls::make_wedge_hopper(hp.theta, hp.b, hp.h, hp.bin, -2.0 * d, hp.depth + 2.0 * d),
      kWallDie));
  w.walls.push_back(walls::make_wall("gate", walls::Plane{{0, 0, 0}, {0, 0, 1}}, kWallBottom));
  particles::InsertRequest req = material_insert_request(
      material,
      particles::BoxRegion{{-0.5 * hp.top, 0.0, hp.h}, {0.5 * hp.top, hp.depth, hp.h + hp.bin}},
      static_cast<std::size_t>(s.particles));
  // Spheres stay inside the region, so none overlaps a periodic image across y = 0 / depth.
  const PhaseCost filled = timed_fill(w, req, rng, s.time_step_safety, material.factors().time);
  hp.limits.lo = {-hp.top - hp.bin, -1e3, -(hp.h + hp.bin) * 4.0 - 1.0};
  hp.limits.hi = {hp.top + hp.bin, 1e3, 2.0 * (hp.h + hp.bin)};
  hp.limits.max_kinetic_energy = sim::kinetic_energy_limit(
      w, w.particles.total_mass() * std::max(norm(w.gravity), 1.0) * (hp.h + hp.bin));
  BedSpec settle_spec;
  settle_spec.max_settle_time = 1.5;
  const PreparedBed built =
      prepare_and_settle(w, material, settle_spec, hp.limits, hp.h + hp.bin, options.seed);
  const double z0 = 0.3 * hp.h, z1 = std::min(0.9 * hp.h, metrics::bed_top(w) - 2.0 * d);
  const double half = 0.5 * (hp.b + 2.0 * z0 * t) - 2.0 * d;
  double phi = 0.6;
  if (half > d && z1 > z0 + d)
    phi = metrics::solid_fraction(w, {-half, 0.0, z0}, {half, hp.depth, z1});
  hp.rho_b = phi * material.simulated_density();
  out.add_phase(filled, {});
  if (built.prepared.steps > 0) out.add_phase(built.prepared, {});
  out.add_phase(built.settled, {"bulk_density", "beverloo_ratio"});
  return hp;
}

struct Discharge {
  Series curve{{"time", "discharged_mass"}, {{0.0, 0.0}}};
  double discharged = 0.0;  ///< (kg)
  double total = 0.0;       ///< the bed's mass (kg)
  bool arched = false;
};

/// Opens the gate (moved far away: no wall is removed, so the bed keeps its contact history) and
/// runs until the hopper is empty, arched or max_time has passed. Discharged particles (centre
/// below z = -2 d) are parked, kinematic, on a lattice under the hopper, so they neither fall
/// for ever nor touch anything.
Discharge discharge(Hopper& hp, const HopperSettings& s, const RunOptions& options,
                    LabOutput& out) {
  sim::World& w = hp.w;
  std::get<walls::Plane>(w.walls[1].shape).point = {0, 0, -1e3};
  w.walls[1].pivot = {0, 0, -1e3};
  Discharge dis;
  dis.total = w.particles.total_mass();
  const double r_max = hp.r_max, d = hp.d;
  const double park_z = -(hp.h + hp.bin) * 2.0;
  const int per_row = std::max(1, static_cast<int>(hp.top / (3.0 * r_max)));
  const int per_col = std::max(1, static_cast<int>(hp.depth / (3.0 * r_max)));
  int parked = 0;
  std::vector<char> gone(w.particles.size(), 0);
  double last_discharge = 0.0;
  const double t0 = w.time;
  const long check = std::max<long>(1, std::lround(0.002 / w.dt));
  auto each = [&](sim::World& world) {
    if (world.step_count % check != 0) return true;
    auto& p = world.particles;
    bool any = false;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (gone[i] || p.x[i].z > -2.0 * d) continue;
      any = true;
      const int k = parked++;
      dis.discharged += p.park(i,
                               {-0.5 * hp.top + 3.0 * r_max * (k % per_row + 0.5),
                                3.0 * r_max * ((k / per_row) % per_col + 0.5),
                                park_z - 3.0 * r_max * (k / (per_row * per_col))},
                               gone);
    }
    const double tt = world.time - t0;
    if (any) {
      last_discharge = tt;
      dis.curve.rows.push_back({tt, dis.discharged});
    }
    if (dis.discharged >= 0.999 * dis.total) return false;
    if (tt - last_discharge > s.arch_time) {
      dis.arched = true;
      return false;
    }
    if (options.progress) options.progress(std::min(1.0, tt / s.max_time));
    return tt < s.max_time;
  };
  hp.limits.lo.z = park_z - 3.0 * r_max * (s.particles / (per_row * per_col) + 2) - 1.0;
  const PhaseClock discharge_clock(w);
  run_checked(w, std::lround(s.max_time / w.dt) + 1, hp.limits, each);
  out.add_phase(discharge_clock.stop(w, "discharge", "hopper empty or arched within max_time",
                                     dis.arched || dis.discharged >= 0.999 * dis.total),
                {"discharge_rate", "beverloo_ratio", "arched", "discharged_fraction"});
  return dis;
}

/// Least-squares slope of the mass-time curve between 15 % and 75 % of the discharged mass
/// (after the start-up, before the hopper runs empty); the mean rate when too few points.
double discharge_rate(const Discharge& dis) {
  const double m_end = dis.discharged;
  LineFit fit;
  for (const auto& row : dis.curve.rows)
    if (row[1] >= 0.15 * m_end && row[1] <= 0.75 * m_end) fit.add(row[0], row[1]);
  if (fit.points() >= 3 && fit.defined()) return fit.slope();
  if (dis.curve.rows.size() >= 2 && dis.curve.rows.back()[0] > 0.0)
    return m_end / dis.curve.rows.back()[0];
  return 0.0;
}

}  // namespace

LabOutput HopperTest::run(const MaterialModel& material, const Settings& values,
                          const RunOptions& options) {
  const auto s = read_settings<HopperSettings>(values, "settings");
  LabOutput out;
  Hopper hp;
  // The one stage: the settled bed before the gate opens.
  Stages stages(options, {"hopper bed"}, out, [&hp](auto& a) { a.field(hp); });
  if (stages.resuming()) {
    hp.w = make_material_world(material, options);
    stages.resume(hp.w);
  } else {
    hp = build_hopper(material, s, options, out);
    write_snapshot(hp.w, options, "hopper_settled", out, hp.top);
    stages.reached(0, hp.w);
  }
  Discharge dis = discharge(hp, s, options, out);
  const double rate = discharge_rate(dis);
  // Beverloo slot form with the hopper's wall factor (header comment).
  const double g = norm(hp.w.gravity);
  const double opening = std::max(0.0, hp.b - kBeverlooK * hp.d);
  const double beverloo = 4.0 * std::sqrt(2.0) / M_PI * kBeverlooC * hp.rho_b * std::sqrt(g) *
                          hp.depth * std::pow(opening, 1.5) * rose_tanaka_factor(hp.theta);
  out.metrics["discharge_rate"] = rate;
  out.metrics["arched"] = dis.arched ? 1.0 : 0.0;
  out.metrics["beverloo_rate"] = beverloo;
  out.metrics["beverloo_ratio"] = beverloo > 0.0 ? rate / beverloo : 0.0;
  out.metrics["discharged_fraction"] = dis.discharged / dis.total;
  out.metrics["bulk_density"] = hp.rho_b;
  out.series["discharge"] = std::move(dis.curve);
  out.cost.close(hp.w);
  return out;
}

}  // namespace demcal::lab
