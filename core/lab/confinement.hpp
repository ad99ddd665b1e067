#pragma once
// The confined compression protocol (seed 000 §2.7.2): a die bed loaded by the piston to
// max_stress, `cycles` times unloaded to min_stress and reloaded, then unloaded to final_stress.
// Two tests run it: confined_compression, which measures the cycles, and tensile, which starts
// from the bed the protocol conditioned (seed 000 §2.7.3: "loading the pre-compressed powder as
// well as the piston at its last position from the confined compression test"). A run keeps the
// conditioned bed in the stage cache (core/lab/stage_cache.hpp) under the identity of everything
// that acted on it, and a tensile run of the same material, settings and seed takes it from
// there instead of conditioning its own.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/lab/piston.hpp"
#include "core/lab/stage_cache.hpp"
#include "core/lab/stages.hpp"
#include "core/model/confined_compression_settings.hpp"

namespace demcal::lab {

/// What the servo phases have measured so far, in simulated units: the states the cycles'
/// stiffnesses are computed from (seed 000 eq. 31-33) and their running sums.
struct Cycles {
  double h1 = 0.0;                                 ///< the first loaded height (m)
  double loaded_stress = 0.0, loaded_z = 0.0;      ///< the last loaded state
  double unloaded_stress = 0.0, unloaded_z = 0.0;  ///< the last unloaded state
  double k_load = 0.0, k_unload = 0.0;             ///< sums over the cycles (MPa, real)
  double e_conf = 0.0;                             ///< eq. 19 on the last loop (MPa, real)
  double final_z = 0.0;                            ///< piston after the final unload (m)
};

/// The protocol's state: the bed with its piston, the cycles measured, and the curves.
struct Confinement {
  PistonBed bed;
  Cycles done;
  Series stress_strain{{"time_s", "height_m", "stress_kPa", "phase"}, {}};
  Series cycles{{"cycle", "h_loaded_m", "h_unloaded_m", "k_load_MPa", "k_unload_MPa"}, {}};
  /// Whether every phase that conditioned the bed reached its target.
  bool reached = true;
};

template <class A, RecordOf<Confinement> C>
void record_fields(A& a, C& c) {
  a.field(c.bed);
  a.field(c.done);
  a.field(c.stress_strain);
  a.field(c.cycles);
  a.field(c.reached);
}

/// The checkpoint stages of the protocol: the bed, then every servo phase in the order they run
/// (load 1, unload 1, load 2, ..., final unload), so that phase p ends stage p + 1.
std::vector<std::string> confinement_stages(int cycles);

/// The bed request of the protocol: stiff piston and bottom (the material's wall law with its
/// normal stiffness times wall_stiffness_factor, seed 000 §2.7.2), the rest of the die as the
/// material's wall law.
PistonBedRequest confinement_request(const MaterialModel& material,
                                     const ConfinedCompressionSettings& s);

/// The identity the conditioned bed is kept under: the protocol's version, the material, every
/// setting of the protocol, the seed and the threads.
std::string conditioned_bed_identity(const MaterialModel& material,
                                     const ConfinedCompressionSettings& s,
                                     const RunOptions& options);

/// Runs the protocol's servo phases from stage `next` (start_piston_test's answer) on, calling
/// `reached` with each stage as it is reached, and keeps the conditioned bed in the options'
/// stage cache when every phase reached its target.
/// `depending(p)` names the metrics of `out` that phase p (load 1 = 0) feeds; `progress_share`
/// is the share of the run's progress the protocol takes.
void run_confinement(Confinement& c, const std::function<void(std::size_t stage)>& reached,
                     std::size_t next, const MaterialModel& material,
                     const ConfinedCompressionSettings& s, const RunOptions& options,
                     LabOutput& out,
                     const std::function<std::vector<std::string>(std::size_t)>& depending,
                     double progress_share);

/// The conditioned bed of the stage cache for these settings, if a run kept it (every phase of
/// that run reached its target).
std::optional<PistonBed> cached_conditioned_bed(const MaterialModel& material,
                                                const ConfinedCompressionSettings& s,
                                                const RunOptions& options);

}  // namespace demcal::lab
