#include "core/sim/step.hpp"

#include <omp.h>

#include <algorithm>

#include "core/integrate/rigid_body.hpp"
#include "core/integrate/velocity_verlet.hpp"
#include "core/sim/forces.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::sim {
namespace {

/// The first half kick and the drift (rigid clumps kick, drift and turn as bodies and place their
/// member spheres), in one parallel region; returns whether some particle moved more than half
/// the skin since the last neighbour-list build.
bool kick_drift(World& w) {
  auto& p = w.particles;
  const bool clumps = p.clumps.size() > 0;
  const double half_skin = 0.5 * w.effective_skin();
  double worst = 0.0;
#pragma omp parallel num_threads(w.active_threads()) reduction(max : worst)
  {
    const auto [lo, hi] = w.owned_range(omp_get_thread_num());
    integrate::kick_drift(p, w.dt, lo, hi);
    if (clumps) integrate::clump_kick_drift(p, w.clump_frames, w.domain, w.gravity, w.dt);
    for (int i = lo; i < hi; ++i) worst = std::max(worst, w.list.displacement2(i, p.x[i]));
  }
  return worst > half_skin * half_skin;
}

}  // namespace

void step(World& w) {
  if (!w.prepared() || w.list.row_start.size() != w.particles.size() + 1 ||
      w.wall_history.size() != w.walls.size()) {
    // A new or changed world: build its state and its forces (prepare() computes them), so the
    // first kick below uses the forces of the initial configuration (as LIGGGHTS' setup does).
    w.prepare();
    // The new state's contacts may need a shorter step than the one set.
    if (w.adaptive_safety > 0.0) w.dt = next_time_step(w, false);
  }
  if (!w.owners_fit()) w.balance_owners();
  const double half = 0.5 * w.dt;
  auto& p = w.particles;
  const bool clumps = p.clumps.size() > 0;
  if (clumps && w.clump_frames.q.size() != p.clumps.size()) w.clump_frames.reset(p);

  // 1. Walls move with their prescribed or controlled velocities (nothing in them depends on
  //    the particles' drift).
  for (auto& wall : w.walls) walls::advance(wall, w.dt);

  // 2. First half kick with the forces of the last step, then drift (velocity Verlet).
  // 3. Neighbour list: rebuilt only once some particle moved more than half the skin; the
  //    history of pairs still in range is carried to the new list.
  if (kick_drift(w)) w.rebuild_list();

  // 4. Forces: gravity, particle-particle and particle-wall contacts (which also give each wall
  //    its force and torque); 5. in the same region, the second half kick with the new forces
  //    (clumps: with the sums over their members, once every member's force is final).
  compute_forces(w, [&](int lo, int hi) {
    integrate::kick(p, half, lo, hi);
    if (clumps) {
#pragma omp barrier
      integrate::clump_kick(p, w.clump_frames, w.gravity, half);
    }
  });

  w.time += w.dt;
  ++w.step_count;
  if (w.adaptive_safety > 0.0) w.dt = next_time_step(w, w.step_count % World::kRetuneSteps == 0);
}

void run(World& w, std::int64_t steps) {
  for (std::int64_t s = 0; s < steps; ++s) step(w);
}

}  // namespace demcal::sim
