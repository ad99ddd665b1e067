#pragma once
// The simulated system: particles, walls, the contact laws per pair type, and the state the
// step function carries from one step to the next (neighbour list, per-contact history).
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/common/domain.hpp"
#include "core/contact/contact_law.hpp"
#include "core/integrate/rigid_body.hpp"
#include "core/neighbour/verlet_list.hpp"
#include "core/particles/insertion.hpp"
#include "core/particles/particle_store.hpp"
#include "core/walls/wall.hpp"

namespace demcal::sim {

class World {
 public:
  particles::ParticleStore particles;
  std::vector<walls::Wall> walls;
  Domain domain;
  Vec3 gravity{0.0, 0.0, -9.81};
  double dt = 0.0;  ///< time step (s)
  /// > 0: the step follows the stiffness of the contacts in use (sim::next_time_step): after
  /// every force evaluation dt shrinks at once to adaptive_safety x sqrt(m*/k) of the stiffest
  /// contact (sim::kStableFraction x for a Hertz contact), every kRetuneSteps steps it may grow
  /// by kStepGrowth, never beyond adaptive_safety x the bound of a fresh contact
  /// (sim::fresh_contact_time_step); 0: dt stays as set.
  double adaptive_safety = 0.0;
  static constexpr int kRetuneSteps = 100;
  static constexpr double kStepGrowth = 1.1;
  /// The largest k / m* over the contacts of the last force evaluation (1/s^2; 0 without any):
  /// k the normal slope the contact can follow (contact::NormalResult::k_step), m* the mass it
  /// moves (the reduced mass of a pair, the particle's at a wall; for clump members, with the
  /// bodies' effective masses, sim::contact_mass).
  double contact_rate2 = 0.0;
  /// The same for the contacts whose normal model sets the step's accuracy by a bound of its own
  /// (contact::normal::stiffness_sets_accuracy: Hertz), which the step only keeps stable.
  double contact_stable_rate2 = 0.0;
  /// 1 / sim::contact_mass of each particle when there are clumps (set by prepare()), else null:
  /// the force kernel then takes 1 / m* of the pair.
  const double* contact_inverse_mass() const {
    return clump_inverse_mass_.empty() ? nullptr : clump_inverse_mass_.data();
  }
  double skin = 0.0;  ///< Verlet skin (m); 0 = 10 % of the smallest particle radius
  int threads = 1;    ///< OpenMP threads at most; see active_threads()
  /// The fewest particles a thread is given: a smaller system runs on fewer threads than asked.
  /// Below a few thousand particles a step is too short to pay for the barriers between threads
  /// (docs/engine.md, "Threads"); tests of the threaded paths set it to 1.
  int particles_per_thread = kParticlesPerThread;
  static constexpr int kParticlesPerThread = 1000;
  /// The threads a step runs on: `threads`, or fewer so that each has particles_per_thread.
  /// Results are bitwise identical for a given number of active threads.
  int active_threads() const { return active_threads_for(particles.size()); }
  /// The threads a step of `count` particles would run on.
  int active_threads_for(std::size_t count) const {
    const auto by_size = count / static_cast<std::size_t>(std::max(1, particles_per_thread));
    return static_cast<int>(
        std::clamp<std::size_t>(by_size, 1, static_cast<std::size_t>(std::max(1, threads))));
  }
  double time = 0.0;
  std::int64_t step_count = 0;

  /// The particles [lo, hi) thread `tid` of the active threads owns, in every parallel loop of a
  /// step: contiguous ranges of about equal work, set at each neighbour-list build
  /// (balance_owners).
  std::pair<int, int> owned_range(int tid) const {
    return {owner_bounds_[tid], owner_bounds_[tid + 1]};
  }
  /// Splits the particles into active_threads() contiguous ranges of about equal work: a particle
  /// costs kOwnerRowCost, plus 1 per pair of its neighbour-list row and kOwnerContactCost per pair
  /// of its row within reach (its owner evaluates them; a later owner also adds the forces
  /// deferred to it). A function of the list alone, so a run and its resumption from a
  /// checkpoint split alike. One thread owns every particle.
  void balance_owners();
  /// Whether the owners' ranges are of the current particles and thread count.
  bool owners_fit() const {
    return owner_bounds_.size() == static_cast<std::size_t>(active_threads()) + 1 &&
           owner_bounds_.back() == static_cast<int>(particles.size());
  }
  static constexpr int kOwnerRowCost = 2;
  static constexpr int kOwnerContactCost = 8;

  /// Contact laws. Particle-particle laws by (material i, material j), symmetric; particle-wall
  /// laws by (wall material, particle material). All particle-particle laws share one composition
  /// of models (their parameters differ), and so do all laws of one wall material.
  void set_pair_law(int material_i, int material_j, const contact::ContactLaw& law);
  void set_wall_law(int wall_material, int particle_material, const contact::ContactLaw& law);
  /// Replaces a particle-particle law during a run. A law of the same composition (other
  /// parameters, e.g. another cohesion range) keeps the contact history: the neighbour list is
  /// rebuilt at once for the new reach (pairs still listed keep their history); the new law acts
  /// from the next force evaluation (the next first half kick uses the forces of the last step,
  /// as after any step). Another composition needs fresh history: as set_pair_law.
  void change_pair_law(int material_i, int material_j, const contact::ContactLaw& law);
  /// Replaces a particle-wall law during a run, as change_pair_law: a law of the same
  /// composition keeps the wall contacts' history and acts from the next force evaluation.
  void change_wall_law(int wall_material, int particle_material, const contact::ContactLaw& law);
  const contact::ContactLaw& pair_law(int material_i, int material_j) const;
  const contact::ContactLaw& wall_law(int wall_material, int particle_material) const;
  int materials() const { return n_materials_; }

  /// Checks the laws, the time step against the stability limit, the particle-particle laws'
  /// range against the particles (check_contact_range), builds the neighbour list and computes
  /// the forces of the current configuration (contact history starts afresh).
  /// Called by step() when needed; call it again after adding or removing particles or walls.
  void prepare();
  bool prepared() const { return prepared_; }
  /// Removes flagged particles (e.g. a bed cut to height); contact history is dropped.
  void remove_particles(const std::vector<char>& flags);

  /// The whole state a run carries from one step to the next, for a checkpoint: particles and
  /// clumps, walls, domain, gravity, time step, time and step count, the neighbour list with the
  /// contact history, the walls' histories and lists, and the clumps' frames. Not in it: the
  /// contact laws and the thread settings, which the resuming run sets up as the saving run did
  /// (restore_state refuses laws of another shape). Restored into a world set up so, a run goes
  /// on to the same bits as from the saved moment, on the same number of threads.
  std::string save_state() const;
  /// Replaces this world's state by a saved one; throws InputError naming "checkpoint" for a
  /// record that is damaged or was made with other laws, and leaves the world unchanged then.
  void restore_state(std::string_view state);

  /// The largest interaction reach beyond contact over all laws (cohesion range), m.
  double interaction_range() const;
  /// Builds the neighbour list for the current positions (wrapped into periodic boxes), carrying
  /// the history of the pairs still in reach.
  void rebuild_list();

  // State carried between steps, used by the step function and by metrics.
  neighbour::VerletList list;
  std::vector<double> pair_history;               ///< history_stride() doubles per listed pair
  std::vector<std::vector<double>> wall_history;  ///< per wall: particles * wall_stride
  /// Per wall, the particles that may touch it (walls/reach.hpp); the force kernel visits only
  /// these. Listed again at every neighbour-list build and whenever the wall's surface has moved
  /// by half the skin since. Since a listing every particle has moved less than the skin (half
  /// the skin since the list build, before and after it) and the wall less than half of it, so a
  /// particle not listed with a margin of 1.5 skins is still out of reach.
  struct WallReach {
    std::vector<int> near;  ///< particle indices, ascending
    walls::Shape shape;     ///< the wall's shape when listed
    double range = -1.0;    ///< the wall laws' reach beyond contact when listed (m)
    double extent = 0.0;    ///< the largest distance of a particle from the shape's reference (m)
    bool valid = false;
    /// A mesh's triangles each listed particle may touch, with the same margin: near[k]'s are
    /// triangles[triangle_start[k] .. triangle_start[k + 1]), ascending (walls::mesh_candidates).
    /// Not part of a saved state: a restored mesh wall is listed again.
    std::vector<int> triangle_start, triangles;
  };
  std::vector<WallReach> wall_reach;
  /// Lists again the particles of every wall whose list is out of date (forces.cpp calls it
  /// before each force evaluation); clears the history of a particle a wall no longer lists.
  void refresh_wall_reach();
  /// A pair force on a particle owned by another thread, added after the pair loop.
  struct DeferredForce {
    int particle;
    Vec3 force, torque;
  };
  std::vector<std::vector<DeferredForce>> deferred;  ///< per thread
  /// The clumps' rotations, arms and wrenches one half step hands to the next (reset by prepare).
  integrate::ClumpFrames clump_frames;
  int pair_stride() const { return pair_stride_; }
  int wall_stride(std::size_t wall) const { return wall_strides_[wall]; }
  double effective_skin() const { return skin_; }
  /// The body of each particle for the neighbour list, or null when there are no clumps.
  const std::int32_t* clump_bodies() const {
    return particles.clumps.size() ? particles.body.data() : nullptr;
  }

 private:
  void grow_law_tables(int n);
  /// The inverse contact masses of the clump members (contact_inverse_mass), for the particles
  /// as they are.
  void set_contact_masses();
  /// Why the arrays of a restored state do not fit together (empty: they do).
  std::string state_mismatch() const;
  /// The state save_state writes and restore_state reads, handed to `a.field` in record order
  /// (ByteWriter with a const World, ByteReader with a mutable one; world_state.cpp).
  template <class A, class W>
  static void state_fields(A& a, W& w);
  std::vector<contact::ContactLaw> pair_laws_;               // n_materials_^2
  std::vector<std::vector<contact::ContactLaw>> wall_laws_;  // [wall material][particle material]
  std::vector<bool> pair_set_;
  std::vector<std::vector<bool>> wall_set_;
  int n_materials_ = 0;
  int pair_stride_ = 0;
  std::vector<int> wall_strides_;
  std::vector<double> clump_inverse_mass_;
  std::vector<int> owner_bounds_{0, 0};  ///< thread t owns [owner_bounds_[t], owner_bounds_[t + 1])
  double skin_ = 0.0;
  bool prepared_ = false;
};

/// Random sequential insertion into the world's store (particles::insert_random), stored in cell
/// order when the grown bed will run on more than one thread (docs/engine.md, "Particle order"),
/// as drawn otherwise.
void insert_random(World& world, particles::InsertRequest request, Rng& rng);

}  // namespace demcal::sim
