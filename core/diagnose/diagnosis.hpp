#pragma once
// Diagnosis of a calibration that does not fit all measurements, made systematic (seed 000 §3.3
// and §4: the calibrated LH220 model missed the tensile strength by a factor of 16 and the
// yield-locus slope by 38 %; the thesis blamed particle shape, Tables 10-15). From a finished
// screening or calibration design and the measurements it reports:
//   - every measured metric's reachable envelope over the factor box against its measurement
//     (Tables 10 and 13) and the residuals at the best calibration, verified by simulation
//     (Tables 12 and 15);
//   - which metrics pull against each other: the best fit of one alone, and how far it puts
//     the others compared with the joint best fit;
//   - candidate causes, each tested by simulation with a small augmented design:
//       shape        rigid rods (shape.aspect_ratio) instead of spheres;
//       rolling      a rolling-resistance model (CDT, mu_r) where the model has none;
//       size_distribution  a log-normal size distribution (its width sigma_g) where the
//                    material has one size;
//       preparation  a cohesive bed built from clusters (seed 000 §2.7.1 method 1; its
//                    agitation time) where the material's beds are poured;
//       coarse_graining  particles of the powder's real median radius at the same Bond number
//                    (its cohesion rescaled) where the material's particles are larger;
//       fixed:<p>    a parameter held fixed, varied over [v / span, v * span];
//       consolidation  the held-out test's bed consolidated to the powder's measured solid
//                    fraction instead of at the design's stress (no model change: its gain is on
//                    the held-out metrics);
//       curvature    non-linearity: axial runs, main effects and squares;
//       interaction  a two-factor interaction aliased in the design: the fold-over;
//     each extended model is fitted, calibrated and its proposed set verified by simulation,
//     the verified run joining its data for up to `rounds` rounds;
//   - the named cause (the candidate whose verified error is lowest, if it cuts the baseline's
//     verified error by the stated margin) and the gain, on the calibrated metrics and on
//     metrics held out of the calibration; and the named cause of the held-out misfit (the
//     candidate whose verified held-out error is lowest, if it cuts the baseline's by the margin
//     without a worse calibrated error).
// The diagnosis is a pure function of the stored results: advance() says which runs it still
// needs and reports what can be said so far, so the coordinator can persist it as jobs.
#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/doe/factor.hpp"
#include "core/particles/size_distribution.hpp"

namespace demcal::diagnose {

inline constexpr double kPending = std::numeric_limits<double>::quiet_NaN();
/// size_distribution: the narrowest log-normal width it runs (sigma_g = 1 is one size).
inline constexpr double kSigmaGLow = particles::kNarrowestLogNormal;
/// preparation: the shortest agitation it runs, as a fraction of the longest (an agitation
/// time of 0 is pouring; the preparation reads 0 as "the default").
inline constexpr double kAgitationLowFraction = 1e-3;

/// coarse_graining: a Hamaker constant at the same granular Bond number when every radius is
/// multiplied by `radius_ratio`. The Bond number is the van der Waals force at contact over the
/// weight (seed 000 eq. 12-13, two spheres of radius r: r_eff = r):
///   Bo = (A_H r / (6 D_min^2)) / ((4/3) pi r^3 rho g) = A_H / (8 pi D_min^2 rho g r^2),
/// so with D_min, D_max and the density kept (a molecular distance and the solid's density do
/// not change with the particle size) it stays the same when A_H ~ r^2. docs/diagnosis.md
/// measured it so (LH220's median radius 6.5 um against the example's 100 um: A_H 5e-18 J ->
/// 2.1e-20 J). Seed 000's own scaling (eq. 24-30) keeps the same Bond number between the
/// simulated and the real particle: A_H ~ SF and D_min ~ SF with r ~ SF, rho ~ SF^-3.
double bond_number_hamaker(double hamaker, double radius_ratio);

struct Factor {
  std::string path;  ///< material parameter path
  doe::Factor factor;
};

struct Measurement {
  std::string response;  ///< test.metric
  double value = 0.0;
  double weight = 1.0;
  std::optional<double> uncertainty;
  bool holdout = false;  ///< kept out of every calibration, reported before/after
};

struct Options {
  std::vector<std::string> candidates;  ///< ids to test; empty = every applicable one
  double aspect_ratio_max = 3.0;        ///< shape: rods from 1 (a sphere) to this
  double rolling_max = 0.3;             ///< rolling: mu_r from 0 (none) to this
  double sigma_g_max = 1.5;             ///< size_distribution: sigma_g from 1 (one size) to this
  double fixed_span = 2.0;              ///< fixed:<p>: from v / span to v * span
  double margin = 0.3;  ///< a named cause cuts the verified RMS error by at least this fraction
  /// ... and, where replicates give both errors a standard error, by more than this many
  /// standard errors of the difference: a cut within the seeds' noise names nothing.
  double noise_z = 2.0;
  int starts = 16;
  std::uint64_t seed = 1;
  /// Ridge toward the design centre in every calibration (calib::CalibrationOptions): 1e-4
  /// moves a fit by less than a 1 % error allows and settles the valleys of fits with more
  /// factors than metrics where the fitted models are best supported.
  double centre_weight = 1e-4;
  /// A candidate's calibration is verified, the verified run joins its data, the models are
  /// refitted and it is calibrated again: at most `rounds` times, fewer once the verified RMS
  /// error is at most `converged`.
  int rounds = 3;
  double converged = 0.01;
  /// Every verification (the baseline's and each candidate's round) is simulated with this many
  /// lab seeds (offsets 0..replicates - 1) and its metrics averaged: the noise of a verified
  /// error falls as 1 / sqrt(replicates), at that many times the verification runs.
  int replicates = 1;
  /// The model extensions repeat only half the base factorial runs, chosen for a main-effect
  /// model (`Problem::nested_rows`), not all of them.
  bool nested = false;
  /// consolidation: the lowest stress it conditions the held-out test's bed at, as a fraction of
  /// the design's; it runs that one and their geometric middle.
  double consolidation_min = 0.1;
};

/// consolidation: the held-out measurements are all of one test instance that consolidates its
/// bed before it measures (a tensile test's compact), and the solid fraction such a
/// consolidation leaves is measured (a confined compression's final solid fraction).
struct Conditioning {
  std::string held_out;  ///< the held-out test instance
  std::string stress;    ///< its setting of the consolidation stress
  std::string density;   ///< the measured response of the consolidated solid fraction
  /// The settings its runs scale with the consolidation stress, per instance they run (the
  /// held-out one and the density's): setting -> value in the design's runs.
  std::map<std::string, std::map<std::string, double>> scaled = {};
};

/// The campaign as the diagnosis sees it.
struct Problem {
  std::vector<Factor> factors;
  Eigen::MatrixXd design;  ///< coded base design, standard order
  std::vector<std::string> responses;
  Eigen::MatrixXd results;  ///< base design results, rows x responses, NaN = missing
  std::vector<Measurement> measurements;
  std::string shape_kind = "sphere";       ///< the material's particle shape
  std::string rolling_model = "none";      ///< its particle-particle rolling model
  std::string size_kind = "monodisperse";  ///< its size distribution: monodisperse | other
  std::string cohesion_model = "none";     ///< its particle-particle cohesion model
  std::string preparation = "pour";        ///< how its beds are built (material.preparation)
  /// A lab test of the campaign can build its bed from clusters (the preparation candidate's
  /// runs change those tests' beds only).
  bool preparable = true;
  /// preparation: the longest agitation time it runs (s, simulated): the preparation's own
  /// default, 3 largest diameters at the speed sqrt(g d).
  double agitation_time_max = 0.0;
  /// coarse_graining: the material's median radius as its model states it at the design centre
  /// (sizes times sizes.scale, m; 0: no one median, as for discrete classes), the powder's measured
  /// median radius (material.real_median_radius, m; 0: not stated), the size scale the base runs
  /// use, and the cohesive parameters the Bond number holds (path -> value at that radius, J).
  double median_radius = 0.0;
  double real_median_radius = 0.0;
  double size_scale = 1.0;
  std::map<std::string, double> bond_scaled;
  std::map<std::string, double> fixed;  ///< parameters held fixed (path -> value)
  std::map<std::string, std::pair<double, double>> valid;  ///< valid range of each path
  /// Rows (0-based) of `design`: half its factorial runs, chosen for a main-effect model
  /// (doe::main_effect_half); used when `options.nested`.
  std::vector<int> nested_rows;
  std::optional<Conditioning> conditioning;  ///< where consolidation applies
  Options options;
};

/// A run the diagnosis needs: the group it belongs to, its row (1-based) and the material it
/// needs (switches of model, then parameter values in natural units).
struct RunRequest {
  std::string group;  ///< "baseline", "<candidate>" or "<candidate>/verify"
  int row = 1;
  std::map<std::string, std::string>
      switches;  ///< "shape" -> "rod", "particle_law.rolling" -> "cdt", "sizes" -> "lognormal",
                 ///< "preparation" -> "clusters"
  std::map<std::string, double> parameters;
  int replicate = 0;  ///< a replicated verification's lab-seed offset, 0..replicates - 1
  /// The test instances it runs (empty: every one) and the settings it runs them with where they
  /// differ from the design's (instance -> setting -> value).
  std::vector<std::string> tests = {};
  std::map<std::string, std::map<std::string, double>> settings = {};
};

/// Finished runs of a group: row -> response -> value (NaN = the run failed).
using GroupResults = std::map<int, std::map<std::string, double>>;

struct MetricRow {
  std::string response;
  double target = 0.0;
  bool holdout = false;
  double envelope_min = 0.0, envelope_max = 0.0;  ///< over the base factor box
  bool reachable = true;
  std::string statement;
  double curvature_p = kPending;     ///< centre-point curvature test, when the design has centres
  double predicted = 0.0;            ///< at the baseline calibration
  double simulated = kPending;       ///< verified at the baseline calibration
  double relative_error = kPending;  ///< (simulated - target) / |target|
};

struct Conflict {
  std::string fitted, other;
  double other_error_alone = 0.0;  ///< relative error of `other` when `fitted` alone is fitted
  double other_error_joint = 0.0;  ///< ... at the joint best fit
  std::string statement;
};

struct CandidateOutcome {
  std::string id, cause;
  std::string state;  ///< pending | designed | verified | failed
  /// It changes how a test conditions its bed (consolidation), not the model: its calibrated
  /// metrics are the baseline's, its verified_rms is pending, and it is judged on the held-out.
  bool conditioning = false;
  int runs = 0;                            ///< simulations of its augmented design
  std::vector<Factor> factors;             ///< the extended factor box
  std::map<std::string, double> proposed;  ///< its calibrated set (natural)
  /// Parameters its runs set from the proposed set rather than take from it (coarse_graining:
  /// the cohesion at the proposed radius, bond_number_hamaker); empty for the others.
  std::map<std::string, double> rescaled;
  bool reaches_all = false;  ///< every calibrated target inside its envelopes
  int rounds = 0;            ///< verification rounds done
  /// The verified round with the lowest calibrated error; proposed, predicted_rms,
  /// verified_rms, simulated, holdout_rms and reaches_all are that round's (0: none verified,
  /// proposed and predicted_rms are the round being verified).
  int best_round = 0;
  double predicted_rms = kPending, verified_rms = kPending;
  /// The standard error of verified_rms from its replicates (Options::replicates >= 2; else
  /// pending): the standard deviation of the replicates' own RMS errors over sqrt(replicates).
  double verified_rms_se = kPending;
  /// Relative RMS misprediction of its augmented runs by the base model: what the base design
  /// did not see (ranks the remedies: an aliased interaction shows in the fold-over runs,
  /// curvature in the axial runs).
  double design_misprediction = kPending;
  std::map<std::string, double> simulated;  ///< verified metrics
  double holdout_rms = kPending;
  double holdout_rms_se = kPending;  ///< as verified_rms_se, on the held-out metrics
  /// 1 - holdout_rms / the baseline's: the verified gain on the held-out metrics.
  double holdout_gain = kPending;
  bool explains = false;
  /// Cuts the baseline's held-out error by the margin beyond the seeds' noise, with a calibrated
  /// error no worse than the baseline's (a conditioning's is the baseline's).
  bool explains_holdout = false;
  /// Cuts the baseline's verified error by the margin, but by no more than `noise_z` standard
  /// errors of the difference: not told from the seeds' noise, so it does not explain.
  bool within_noise = false;
  std::string evidence;
};

/// What a candidate explains, in the words every view shows: "both" (the calibrated and the
/// held-out misfit), "yes" (the calibrated), "held out", or "no".
std::string explains_label(const CandidateOutcome& c);

struct Report {
  std::string state;  ///< waiting | running | done
  std::vector<MetricRow> metrics;
  std::map<std::string, double> baseline_proposed;
  double baseline_predicted_rms = kPending, baseline_verified_rms = kPending;
  double baseline_verified_rms_se = kPending;  ///< as CandidateOutcome::verified_rms_se
  double baseline_holdout_rms = kPending;
  double baseline_holdout_rms_se = kPending;
  std::vector<Conflict> conflicts;
  std::vector<CandidateOutcome> candidates;  ///< ranked once verified (best first)
  std::string named_cause;                   ///< candidate id, empty when none is named
  /// Other candidates that explain the misfit with a verified error within the margin of the
  /// named cause's (below its error / (1 - margin), or both below `converged`): the data do not
  /// tell them apart from it.
  std::vector<std::string> rivals;
  /// The named cause of the held-out misfit: the candidate that explains it with the lowest
  /// verified held-out error; empty when none does.
  std::string holdout_cause;
  std::string conclusion;  ///< plain words
};

struct Step {
  std::vector<RunRequest> requests;  ///< every run needed so far (stored ones included)
  Report report;
};

/// What can be said from the finished runs, and which runs are still needed. Throws InputError
/// when the problem cannot be diagnosed (no calibrated measurement, unknown candidate id).
Step advance(const Problem& problem, const std::map<std::string, GroupResults>& groups);

}  // namespace demcal::diagnose
