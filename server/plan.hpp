#pragma once
// The validated campaign as one domain value, the plan: its test instances (settings at each
// fidelity level, material models), fixed values, factors and ties, design, responses and
// targets, fidelity axis, and calibration and diagnosis options. Built once from the spec at
// Submit (plan_campaign, the only reader of the spec's fields), stored in campaigns.design_json,
// and read back by every RPC that needs the campaign (Calibrate, Diagnose, GetEffects, Export):
// none of them reads the spec again. The jobs of a campaign are built from it here.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/calib/sequential.hpp"
#include "core/diagnose/diagnosis.hpp"
#include "core/doe/design.hpp"
#include "core/doe/factor.hpp"
#include "core/model/catalog.hpp"
#include "core/model/material.hpp"
#include "demcal/v1/campaign.pb.h"
#include "server/store.hpp"

namespace demcal::server {

/// One test instance: a lab test under a name of its own (its responses are "<name>.<metric>").
struct PlannedInstance {
  std::string name, test;
  lab::Settings settings_low;   ///< its settings as given, or at the low fidelity level
  lab::Settings settings_high;  ///< at the high fidelity level (= settings_low without one)
  lab::MaterialModel material;  ///< the campaign's, with the instance's own wall law
  std::uint64_t seed = 1;       ///< the simulation seed of its first design row
  int threads = 0;              ///< 0 = the worker's --threads
  /// The instance whose job of a row this one's is leased after (a tensile test after the
  /// confined compression whose conditioned bed it starts from); empty: none.
  std::string waits_for;
};

struct PlannedFactor {
  std::string path;
  doe::Factor factor;             ///< factor.name = the label shown in tables
  std::vector<std::string> tied;  ///< paths set to the factor's value in every run
};

struct Target {
  std::string response;  ///< test.metric
  double value = 0.0, weight = 1.0;
  std::optional<double> uncertainty;
  std::string source;
  bool holdout = false;  ///< kept out of calibrations (reported by the diagnosis)
};

/// The fidelity axis of a multi-fidelity campaign: the design runs at `low`, the rows
/// `high_rows` (1-based standard order) at `high` as well.
struct FidelityPlan {
  std::string path;  ///< settings.<name> or a material parameter path
  double low = 0.0, high = 0.0;
  std::vector<int> high_rows;
};

struct CampaignPlan {
  lab::MaterialModel material;          ///< the campaign's, without its fixed values
  std::map<std::string, double> fixed;  ///< parameter path -> value, in every run
  std::vector<PlannedInstance> instances;
  std::vector<PlannedFactor> factors;
  doe::Design design;
  /// Repeated points share their seed (Design.Seeds PINNED) instead of each row its own.
  bool pinned_seeds = false;
  std::vector<std::string> responses;  ///< instance.metric, instances in spec order
  std::vector<Target> targets;
  std::optional<FidelityPlan> fidelity;
  calib::SequentialOptions calibration;
  /// The calibration verifies as many points per batch as workers ran the campaign (no batch
  /// size in the spec).
  bool batch_per_worker = true;
  diagnose::Options diagnosis;
};

/// The instances' names, in spec order.
std::vector<std::string> instance_names(const CampaignPlan& plan);

/// Validates a spec and plans it, with the jobs of its design; InputError names the field
/// ("spec.factors[2].high"). Factor paths must exist in the material's parameter table
/// (lab::parameters) with bounds inside the valid range; tests, settings and measured metrics
/// must exist in the catalogue; every job is admitted as a worker would admit it.
CampaignPlan plan_campaign(const v1::CampaignSpec& spec, std::vector<NewJob>& jobs);

/// The plan as stored in campaigns.design_json, and back. A campaign stored before the plan held
/// the whole campaign (its design_json has no "form") is read with its stored spec: the plan of
/// `row`, its instances waiting for none (PlannedInstance::waits_for is set at Submit).
std::string plan_to_json(const CampaignPlan& plan);
CampaignPlan stored_plan(const CampaignRow& row);

/// The parameters a run sets on its material at the given factor values (path -> natural): the
/// fixed values, a fidelity parameter's level, the factors' and each factor's tied paths.
std::map<std::string, double> run_parameters(const CampaignPlan& plan,
                                             const std::map<std::string, double>& factors,
                                             bool high);

/// One planned simulation: an instance at a parameter set, a fidelity level and a seed, as row
/// `std_order` of job kind `kind`.
struct PlannedRun {
  std::size_t instance = 0;  ///< into CampaignPlan::instances
  int std_order = 0, run_order = 0;
  std::string kind;
  std::map<std::string, double> parameters;  ///< run_parameters
  bool high = false;
  std::uint64_t seed = 1;
  lab::Settings settings = {};  ///< settings it runs with where they differ from its instance's
};

/// The settings a run simulates its instance with: the instance's at the run's fidelity level,
/// the run's own in their place.
lab::Settings run_settings(const CampaignPlan& plan, const PlannedRun& run);

/// One run per design row and instance, the plan's design laid over `box` (the campaign's
/// factors or a calibration stage's narrowed box), at the low fidelity level (`high`: the high).
/// Seeds: see Design.Seeds in the proto; a later stage adds `stage_offset` to keep its runs'
/// seeds apart from the first. With `rows` (1-based standard order), only those rows.
std::vector<PlannedRun> design_runs(const CampaignPlan& plan, const std::vector<PlannedFactor>& box,
                                    const std::string& kind, int stage_offset, bool high,
                                    const std::vector<int>* rows = nullptr);

/// One run per instance at one parameter set (run_parameters of `factors`), as row `std_order`,
/// with the instance's seed + `seed_offset`.
std::vector<PlannedRun> runs_at(const CampaignPlan& plan,
                                const std::map<std::string, double>& factors, bool high,
                                int std_order, const std::string& kind, std::uint64_t seed_offset);

/// The jobs that simulate the runs, each instance's material under the diagnosis's model
/// `switches` (lab::with_switches; none: as planned).
std::vector<NewJob> jobs_of(const CampaignPlan& plan, const std::vector<PlannedRun>& runs,
                            const std::map<std::string, std::string>& switches = {});

/// How near (relative, in every parameter) a proposed point is to a journal run's to be that
/// run: far above the last digits in which two builds' calibrations land apart, far below any
/// change a simulation could show.
inline constexpr double kHeldPointTolerance = 1e-6;

/// Jobs at points an optimizer proposed (verification rounds, stage designs, a diagnosis's
/// runs) whose run the store does not hold: a job whose point is within kHeldPointTolerance of
/// a journal run of the same lab test and seed, and whose run key at that run's point is that
/// run's (so the same material, settings and protocol), takes that point. A journal written by
/// another build, whose calibration proposes its points a hair away, so serves a campaign planned
/// again from it instead of every later point being simulated anew.
void take_held_points(Store& store, std::vector<NewJob>& jobs);

/// Every rule a worker checks before it simulates, on runs planned after Submit (plan_campaign
/// admits its own); InputError naming the instance's settings and the row.
void admit_runs(const CampaignPlan& plan, const std::vector<PlannedRun>& runs);

}  // namespace demcal::server
