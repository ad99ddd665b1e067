// Determinism (DESIGN "Determinism"): the same scene and thread count give bitwise
// identical states; and with one thread the Verlet skin does not change a single bit, on a dense
// sheared bed with friction and rolling resistance whose contacts outlive many list rebuilds —
// which holds only if the per-contact history is carried across every rebuild (pairs outside
// reach contribute nothing and rows are sorted, so the force sums are the same).
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "core/io/scene_yaml.hpp"
#include "core/metrics/bulk.hpp"
#include "core/sim/step.hpp"

namespace demcal {
namespace {

/// 180 spheres poured into a 12 x 12 mm box, periodic in x and y, onto a floor.
const std::string kPeriodicPour = R"(seed: 77
time_step: 2.0e-5
gravity: [0, 0, -9.81]
domain: {lo: [0, 0, -0.01], hi: [0.012, 0.012, 0.05], periodic: [true, true, false]}
density: 2500
contact_law:
  normal: {model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 0.5}
  tangential: {model: history, mu_s: 0.5, kt_ratio: 1.0, gamma_t_ratio: 1.0}
  rolling: {model: epsd, mu_r: 0.1}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
particles:
  random:
    region: {box: {lo: [0, 0, 0], hi: [0.012, 0.012, 0.015]}}
    count: 180
    sizes: {lognormal: {median_radius: 0.0008, sigma_g: 1.2, truncate_k: 2}}
phases: []
)";

/// A closed box whose floor slides in x at 5 cm/s under a settling bed: friction, rolling
/// resistance, contacts that persist while the bed is sheared.
const std::string kShearedBed = R"(seed: 5
time_step: 2.0e-5
gravity: [0, 0, -9.81]
density: 2500
contact_law:
  normal: {model: linear, kn: 1000, damping_ratio: 0.3}
  tangential: {model: history, mu_s: 0.5, kt_ratio: 0.4}
  rolling: {model: epsd, mu_r: 0.1, kr_ratio: 0.5}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, velocity: [0.05, 0, 0]}
  - {name: x0, plane: {point: [0, 0, 0], normal: [1, 0, 0]}}
  - {name: x1, plane: {point: [0.012, 0, 0], normal: [-1, 0, 0]}}
  - {name: y0, plane: {point: [0, 0, 0], normal: [0, 1, 0]}}
  - {name: y1, plane: {point: [0, 0.012, 0], normal: [0, -1, 0]}}
particles:
  random:
    region: {box: {lo: [0, 0, 0], hi: [0.012, 0.012, 0.03]}}
    count: 200
    sizes: {monodisperse: {radius: 0.001}}
phases: []
)";

sim::World load(const std::string& yaml, int threads, double skin = 0.0) {
  auto scene = io::read_scene(io::YamlNode::load_string(yaml, "scene.yaml"));
  scene.world.threads = threads;
  scene.world.particles_per_thread = 1;  // the 180-particle pour runs on every thread asked for
  if (skin > 0.0) scene.world.skin = skin;
  return std::move(scene.world);
}

/// Number of particles whose position, velocity or angular velocity differ in any bit.
std::size_t bit_differences(const sim::World& a, const sim::World& b) {
  EXPECT_EQ(a.particles.size(), b.particles.size());
  std::size_t diff = 0;
  for (std::size_t i = 0; i < a.particles.size(); ++i) {
    const bool same = std::memcmp(&a.particles.x[i], &b.particles.x[i], sizeof(Vec3)) == 0 &&
                      std::memcmp(&a.particles.v[i], &b.particles.v[i], sizeof(Vec3)) == 0 &&
                      std::memcmp(&a.particles.omega[i], &b.particles.omega[i], sizeof(Vec3)) == 0;
    diff += !same;
  }
  return diff;
}

TEST(SimDeterminism, SameThreadCountGivesBitwiseIdenticalRuns) {
  for (int threads : {2, 1}) {
    sim::World a = load(kPeriodicPour, threads), b = load(kPeriodicPour, threads);
    ASSERT_EQ(a.active_threads(), threads);
    sim::run(a, 4000);
    sim::run(b, 4000);
    EXPECT_EQ(bit_differences(a, b), 0u) << threads << " threads";
    EXPECT_EQ(std::memcmp(&a.walls[0].force, &b.walls[0].force, sizeof(Vec3)), 0);
    // The run is not trivial: the spheres have landed and touch each other and the floor.
    EXPECT_GT(metrics::coordination_number(a), 1.0) << threads << " threads";
    EXPECT_LT(a.walls[0].force.z, 0.0);
    EXPECT_GT(a.list.builds(), 5u);
  }
}

TEST(SimThreads, SmallSystemsRunOnFewerThreadsThanAsked) {
  sim::World w = load(kPeriodicPour, 2);
  w.particles_per_thread = sim::World::kParticlesPerThread;
  EXPECT_EQ(w.active_threads(), 1) << "180 particles";
  w.particles_per_thread = 50;
  EXPECT_EQ(w.active_threads(), 2);
  w.threads = 8;
  EXPECT_EQ(w.active_threads(), 3) << "180 particles at 50 per thread";
  w.particles_per_thread = 0;
  EXPECT_EQ(w.active_threads(), 8) << "no grain: every thread asked for";
  w.threads = 0;
  EXPECT_EQ(w.active_threads(), 1);
}

TEST(SimThreads, OwnersShareTheContactsNotTheCount) {
  // 400 spheres: the first 200 touch their neighbours in a 10 x 20 square layer, the last 200
  // lie far apart. Two threads split the work, so the first owns fewer than half the spheres.
  sim::World w;
  w.gravity = {};
  w.dt = 1e-6;
  w.threads = 2;
  w.particles_per_thread = 1;
  w.set_pair_law(
      0, 0,
      contact::ContactLaw::from_spec(
          {{"linear", {{"kn", 1000.0}}}, {"none", {}}, {"history", {{"mu_s", 0.5}}}, {"none", {}}},
          "law"));
  const double r = 0.001;
  for (int i = 0; i < 200; ++i)
    w.particles.add_sphere({1.99 * r * (i % 10), 1.99 * r * (i / 10), 0}, r, 2500, 0);
  for (int i = 0; i < 200; ++i) w.particles.add_sphere({0.1 + 0.01 * i, 0, 0}, r, 2500, 0);
  sim::run(w, 1);
  ASSERT_EQ(w.active_threads(), 2);
  const auto [lo0, hi0] = w.owned_range(0);
  const auto [lo1, hi1] = w.owned_range(1);
  EXPECT_EQ(lo0, 0);
  EXPECT_EQ(hi0, lo1);
  EXPECT_EQ(hi1, 400);
  EXPECT_LT(hi0, 200) << "the touching layer holds the work";
  EXPECT_GT(hi0, 100);
  // One thread owns every sphere.
  w.threads = 1;
  sim::run(w, 1);
  EXPECT_EQ(w.owned_range(0), std::make_pair(0, 400));
}

TEST(SimDeterminism, SkinDoesNotChangeOneBitBecauseHistorySurvivesRebuilds) {
  const double r = 0.001;
  sim::World small = load(kShearedBed, 1, 0.05 * r), large = load(kShearedBed, 1, 0.6 * r);
  std::size_t contacts_sum = 0;
  for (int chunk = 0; chunk < 10; ++chunk) {
    sim::run(small, 800);
    sim::run(large, 800);
    ASSERT_EQ(bit_differences(small, large), 0u) << "after " << small.step_count << " steps";
    contacts_sum += metrics::contact_count(small);
  }
  std::printf(
      "sheared bed: %zu list builds with skin 0.05 r, %zu with 0.6 r; coordination %.2f; "
      "floor moved %.4f m\n",
      small.list.builds(), large.list.builds(), metrics::coordination_number(small),
      small.walls[0].displacement.x);
  // The small skin forces many rebuilds while contacts persist; the large one far fewer.
  EXPECT_GT(small.list.builds(), 200u);
  EXPECT_GT(small.list.builds(), 3 * large.list.builds());
  EXPECT_GT(metrics::coordination_number(small), 3.0);
  EXPECT_GT(contacts_sum, 1000u);
  // Friction and rolling history are in play: some contact holds a tangential spring.
  double max_spring = 0.0;
  for (double h : small.pair_history) max_spring = std::max(max_spring, std::abs(h));
  EXPECT_GT(max_spring, 0.0);
}

/// Runs `steps` on from a world's saved state restored into a fresh world of the same scene, and
/// on from the world itself: both must end in the same bits.
void expect_resumed_run_identical(sim::World& a, sim::World fresh, int steps) {
  fresh.restore_state(a.save_state());
  EXPECT_EQ(fresh.step_count, a.step_count);
  sim::run(a, steps);
  sim::run(fresh, steps);
  EXPECT_EQ(bit_differences(a, fresh), 0u);
  EXPECT_EQ(a.step_count, fresh.step_count);
  EXPECT_EQ(std::memcmp(&a.time, &fresh.time, sizeof(double)), 0);
  EXPECT_EQ(a.list.builds(), fresh.list.builds());
  for (std::size_t k = 0; k < a.walls.size(); ++k) {
    EXPECT_EQ(std::memcmp(&a.walls[k].force, &fresh.walls[k].force, sizeof(Vec3)), 0) << k;
    EXPECT_EQ(std::memcmp(&a.walls[k].displacement, &fresh.walls[k].displacement, sizeof(Vec3)), 0)
        << k;
  }
}

TEST(SimCheckpoint, ARestoredStateRunsOnToTheSameBits) {
  // Moving walls, friction and rolling springs that outlive list rebuilds: the histories, the
  // walls' lists and the list's positions of the last build all carry into the next steps.
  sim::World sheared = load(kShearedBed, 1);
  sim::run(sheared, 4000);
  ASSERT_GT(metrics::coordination_number(sheared), 2.0);
  expect_resumed_run_identical(sheared, load(kShearedBed, 1), 4000);
  // Periodic axes, on two threads.
  sim::World pour = load(kPeriodicPour, 2);
  sim::run(pour, 2000);
  expect_resumed_run_identical(pour, load(kPeriodicPour, 2), 2000);
}

TEST(SimCheckpoint, ADamagedRecordOrOtherLawsAreRefusedAndTheWorldIsKept) {
  sim::World w = load(kShearedBed, 1);
  sim::run(w, 500);
  const std::string state = w.save_state();
  sim::World target = load(kShearedBed, 1);
  const std::string before = target.save_state();
  auto refusal = [&](std::string_view record) {
    try {
      target.restore_state(record);
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "checkpoint");
      return std::string(e.message());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal(std::string_view(state).substr(0, state.size() / 2)).find("truncated"),
            std::string::npos);
  EXPECT_NE(refusal(state + "x").find("left over"), std::string::npos);
  EXPECT_NE(refusal("not a state at all, not at all").find("truncated"), std::string::npos);
  EXPECT_EQ(target.save_state(), before) << "a refused record changed the world";
  sim::World other = load(kPeriodicPour, 1);  // history of another size (EPSD, no spring ratio)
  other.set_pair_law(
      0, 0,
      contact::ContactLaw::from_spec(
          {{"linear", {{"kn", 1000.0}}}, {"none", {}}, {"history", {{"mu_s", 0.5}}}, {"none", {}}},
          "law"));
  EXPECT_NE(
      [&] {
        try {
          other.restore_state(state);
        } catch (const InputError& e) {
          return std::string(e.message());
        }
        return std::string("accepted");
      }()
          .find("other contact laws"),
      std::string::npos);
}

}  // namespace
}  // namespace demcal
