// rotating_drum (seed 001 §3.2.2-3.2.3). The drum's axis is z and gravity is -y, so the cross
// section is the x-y plane and the "photograph" is the projection of the particles along z.
// The drum (inner cylinder) and both end plates rotate rigidly about the axis; their contact law
// is the material's wall law (the granule-boundary law of seed 001 Table 3).
//
// The drum is given in real units (D x W in mm, the fill degree); the particle count follows
// from it and the simulated size distribution, so coarse-graining (seed 001 eq. 15) changes
// D / d and the count, never the drum: the scale effect of seed 001 App. B and the boundary effect
// of Dury et al. 1998 (seed 001 ref. [46]) are both a function of D / d, which is reported.
//
// Phases: insert in the drum, settle at rest, rotate at `rpm` until the bed has turned to its
// angle, then keep turning for angle_time while images are taken: dynamic_angle_of_repose is the
// mean of the surface-fit angles. Then the area method: the speeds in ascending order, each for
// area_time; csa_occupied_<rpm> (seed 001 eq. 20) is the mean occupied area of the images of the
// second half of each speed. A bed whose particles all lie in a ring at the wall (none within
// half a radius of the axis) and cover at least 90 % of the wall's circumference is centrifuging:
// centrifuging_<rpm> = 1.
#include "core/lab/rotating_drum.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/line_fit.hpp"
#include "core/common/rng.hpp"
#include "core/lab/bed.hpp"
#include "core/lab/stages.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::lab {
namespace {

/// The drum is the real apparatus in real units (only its particles are coarse-grained): its
/// protocol's seconds are simulated seconds (settle(), fill_region()).
constexpr double kRealApparatus = 1.0;

constexpr double kSeedDrumDiameter = 0.100;  // seed 001 §3.2.2

bool centrifuging(const sim::World& w, double radius) {
  constexpr int kSectors = 36;
  std::array<bool, kSectors> covered{};
  const double d = 2.0 * *std::max_element(w.particles.radius.begin(), w.particles.radius.end());
  for (std::size_t i = 0; i < w.particles.size(); ++i) {
    const Vec3& x = w.particles.x[i];
    const double rho = std::hypot(x.x, x.y);
    if (rho < 0.5 * radius) return false;
    if (rho > radius - 2.0 * d) {
      const double phi = std::atan2(x.y, x.x) + M_PI;
      covered[std::min(kSectors - 1, static_cast<int>(phi / (2.0 * M_PI) * kSectors))] = true;
    }
  }
  return static_cast<double>(std::count(covered.begin(), covered.end(), true)) >= 0.9 * kSectors;
}

/// The drum (an inner cylinder about z) and its two end plates, all pivoting about the axis so
/// that they turn as one body; each carries the material's wall law.
void add_drum_walls(sim::World& w, double radius, double depth) {
  w.walls.push_back(walls::make_wall(
      "drum", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, radius, 0.0, depth}, kWallDie));
  w.walls.push_back(walls::make_wall("back", walls::Plane{{0, 0, 0}, {0, 0, 1}}, kWallBottom));
  w.walls.push_back(
      walls::make_wall("front", walls::Plane{{0, 0, depth}, {0, 0, -1}}, kWallPiston));
  for (auto& wall : w.walls) wall.pivot = {0, 0, 0};
}

}  // namespace

DrumImage project_drum(const std::vector<Vec3>& x, const std::vector<double>& radius,
                       double drum_radius, double pixel) {
  DrumImage img;
  img.radius = drum_radius;
  img.pixel = pixel;
  img.n = static_cast<int>(std::ceil(2.0 * drum_radius / pixel));
  img.black.assign(static_cast<std::size_t>(img.n) * img.n, 0);
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double r = radius[k];
    const int i0 = std::max(0, static_cast<int>((x[k].x - r + drum_radius) / pixel));
    const int i1 = std::min(img.n - 1, static_cast<int>((x[k].x + r + drum_radius) / pixel));
    const int j0 = std::max(0, static_cast<int>((x[k].y - r + drum_radius) / pixel));
    const int j1 = std::min(img.n - 1, static_cast<int>((x[k].y + r + drum_radius) / pixel));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double px = -drum_radius + (i + 0.5) * pixel - x[k].x;
        const double py = -drum_radius + (j + 0.5) * pixel - x[k].y;
        if (px * px + py * py <= r * r) img.black[static_cast<std::size_t>(j) * img.n + i] = 1;
      }
  }
  return img;
}

double DrumImage::occupied_percent() const {
  // eq. 20: CSA_oc = 100 black area / CSA_drum, both counted in pixels of the drum circle.
  long drum = 0, occupied = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double px = -radius + (i + 0.5) * pixel, py = -radius + (j + 0.5) * pixel;
      if (px * px + py * py > radius * radius) continue;
      ++drum;
      occupied += at(i, j);
    }
  return drum ? 100.0 * static_cast<double>(occupied) / static_cast<double>(drum) : 0.0;
}

std::vector<std::pair<double, double>> DrumImage::surface() const {
  std::vector<std::pair<double, double>> points;
  for (int i = 0; i < n; ++i)
    for (int j = n - 1; j >= 2; --j)
      if (at(i, j) && at(i, j - 1) && at(i, j - 2)) {
        points.emplace_back(-radius + (i + 0.5) * pixel, -radius + (j + 0.5) * pixel);
        break;
      }
  return points;
}

double DrumImage::surface_angle() const {
  const auto points = surface();
  if (points.size() < 4) return 0.0;
  // The surface spans the chord between the two points where it meets the wall; fit its middle
  // half, away from the toe and the shoulder.
  const double lo = points.front().first, hi = points.back().first;
  const double a = lo + 0.25 * (hi - lo), b = lo + 0.75 * (hi - lo);
  LineFit fit;
  for (const auto& [x, y] : points)
    if (x >= a && x <= b) fit.add(x, y);
  if (fit.points() < 3 || !fit.defined()) return 0.0;
  return std::atan(std::abs(fit.slope())) * 180.0 / M_PI;
}

LabOutput RotatingDrumTest::run(const MaterialModel& material, const Settings& values,
                                const RunOptions& options) {
  const auto s = read_settings<RotatingDrumSettings>(values, "settings");
  const auto sizes = material.simulated_sizes();
  const double r_max = particles::max_radius(sizes);
  const DrumBed bed = drum_bed(s, sizes, "settings");
  const double radius = bed.radius, depth = bed.length;

  LabOutput out;
  sim::HealthLimits limits;
  Series angle_series{{"time", "angle_deg", "csa_occupied_percent"}, {}};
  Series profile{{"x_m", "y_m"}, {}};  // the free surface of the last image
  Series area{{"rpm", "rpm_simulated", "csa_occupied_percent", "centrifuging"}, {}};
  // The stages: the settled bed, the angle measured, then each speed of the area method done.
  std::vector<std::string> names{"drum bed", "angle"};
  for (const int rpm : kDrumSpeeds) names.push_back("area " + std::to_string(rpm) + " rpm");
  const double frame = 0.05;  // s between images
  long frame_steps = 0;       // fixed once the bed has settled, in steps of that time step
  Stages stages(options, std::move(names), out, [&](auto& a) {
    a.field(limits);
    a.field(frame_steps);
    a.field(angle_series);
    a.field(profile);
    a.field(area);
  });
  sim::World w = make_material_world(material, options);
  std::size_t next = stages.resume(w);
  if (next == 0) {
    w.gravity = {0, -9.81, 0};
    Rng rng(options.seed);
    add_drum_walls(w, radius, depth);
    particles::InsertRequest req = material_insert_request(
        material, particles::CylinderRegion{{0, 0, 0}, radius, 0.0, depth}, bed.particles);
    out.add_phase(timed_fill(w, req, rng, s.time_step_safety, kRealApparatus), {});
    limits.lo = {-1.5 * radius, -1.5 * radius, -radius};
    limits.hi = {1.5 * radius, 1.5 * radius, depth + radius};
    limits.max_kinetic_energy =
        sim::kinetic_energy_limit(w, w.particles.total_mass() * 9.81 * 2.0 * radius);
    BedSpec settle_spec;
    settle_spec.max_settle_time = 1.0;
    out.add_phase(settle(w, settle_spec, limits, kRealApparatus), {});
    stages.reached(0, w);
    next = 1;
  }

  // Froude scaling: Fr = w^2 R / g of the seed's drum at the seed's rpm.
  const double speed_factor =
      s.speed_scale *
      (s.froude_scaling > 0.5 ? std::sqrt(kSeedDrumDiameter / (2.0 * radius)) : 1.0);
  auto set_speed = [&](double rpm) {
    const double omega = rpm * speed_factor * 2.0 * M_PI / 60.0;
    limits.max_kinetic_energy = sim::kinetic_energy_limit(
        w, w.particles.total_mass() * (9.81 * 2.0 * radius + omega * omega * radius * radius));
    for (auto& wall : w.walls) wall.omega = {0, 0, omega};
    return omega;
  };
  const double pixel = 0.25 * r_max;
  auto image = [&] { return project_drum(w.particles.x, w.particles.radius, radius, pixel); };

  if (next == 1) frame_steps = std::max<long>(1, std::lround(frame / w.dt));
  auto run_for = [&](double seconds, const std::function<void()>& on_frame) {
    const long frames = std::max<long>(1, std::lround(seconds / frame));
    for (long f = 0; f < frames; ++f) {
      run_checked(w, frame_steps, limits);
      if (on_frame) on_frame();
    }
  };

  // At `rpm`: first turn the bed up to its angle (60 deg of drum rotation, 3 s at most), then
  // measure.
  if (next == 1) {
    const double w_angle = set_speed(s.rpm);
    const PhaseClock angle_clock(w);
    run_for(std::min(60.0 * M_PI / 180.0 / w_angle, 3.0), {});
    double angle_sum = 0.0;
    int angle_n = 0;
    run_for(s.angle_time, [&] {
      const DrumImage img = image();
      const double a = img.surface_angle();
      angle_series.rows.push_back({w.time, a, img.occupied_percent()});
      profile.rows.clear();
      for (const auto& [x, y] : img.surface()) profile.rows.push_back({x, y});
      if (angle_series.rows.size() * 2 > static_cast<std::size_t>(s.angle_time / frame)) {
        angle_sum += a;
        ++angle_n;
      }
    });
    out.metrics["dynamic_angle_of_repose"] = angle_n ? angle_sum / angle_n : 0.0;
    out.add_phase(
        angle_clock.stop(w, drum_rpm_label(s.rpm) + " rpm", "angle_time of turning", true), {});
    if (options.progress) options.progress(0.4);
    write_snapshot(w, options, "drum_angle", out, radius);
    stages.reached(1, w);
    next = 2;
  }

  for (std::size_t k = next - 2; k < kDrumSpeeds.size(); ++k) {
    const int rpm = kDrumSpeeds[k];
    const double omega = set_speed(rpm);
    const PhaseClock rpm_clock(w);
    double sum = 0.0;
    int n = 0, frames = 0;
    const int total = std::max(1, static_cast<int>(std::lround(s.area_time / frame)));
    bool centri = true;
    run_for(s.area_time, [&] {
      if (++frames * 2 <= total && total > 1) return;
      sum += image().occupied_percent();
      ++n;
      centri = centri && centrifuging(w, radius);
    });
    out.add_phase(rpm_clock.stop(w, std::to_string(rpm) + " rpm", "area_time of turning", true),
                  {});
    const double csa = n ? sum / n : 0.0;
    out.metrics["csa_occupied_" + std::to_string(rpm)] = csa;
    out.metrics["centrifuging_" + std::to_string(rpm)] = centri ? 1.0 : 0.0;
    area.rows.push_back({double(rpm), omega * 60.0 / (2.0 * M_PI), csa, centri ? 1.0 : 0.0});
    if (options.progress)
      options.progress(0.4 +
                       0.6 * static_cast<double>(k + 1) / static_cast<double>(kDrumSpeeds.size()));
    stages.reached(k + 2, w);
  }
  out.metrics["drum_diameter"] = 2.0 * radius;
  out.metrics["drum_diameter_ratio"] = bed.diameter_ratio;
  out.metrics["particles"] = static_cast<double>(w.particles.units());
  out.series["angle"] = std::move(angle_series);
  out.series["surface_profile"] = std::move(profile);
  out.series["area_method"] = std::move(area);
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
