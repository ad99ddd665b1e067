// The sequential calibration against a hidden truth: a synthetic simulator with curvature the
// two-level models cannot see and seeded noise. The loop must end within the measurement's
// uncertainty plus noise, and say so; with an unreachable target and a job budget it must stop
// at the budget and name the metric that is off and by how much.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/calib/sequential.hpp"
#include "core/common/error.hpp"
#include "core/common/rng.hpp"
#include "core/doe/analysis.hpp"
#include "core/doe/design.hpp"

namespace demcal::calib {
namespace {

const std::vector<doe::Factor> kBox{{"mu_s", 0.1, 0.5, doe::Scale::kLinear},
                                    {"e", 0.2, 0.6, doe::Scale::kLinear},
                                    {"Y", 1e6, 1e8, doe::Scale::kLog}};

/// The hidden truth in the campaign box's coded units: curved (squares) and interacting.
Eigen::VectorXd truth(const Eigen::VectorXd& natural) {
  Eigen::VectorXd x(3);
  for (int i = 0; i < 3; ++i) x(i) = kBox[std::size_t(i)].to_coded(natural(i));
  Eigen::VectorXd y(2);
  y(0) = 0.55 + 0.08 * x(0) - 0.04 * x(1) + 0.06 * x(0) * x(0) + 0.03 * x(0) * x(1);
  y(1) = 10.0 + 3.0 * x(2) + 2.0 * x(0) + 2.5 * x(2) * x(2) - 1.0 * x(0) * x(2);
  return y;
}

const Eigen::Vector2d kNoise{0.002, 0.05};

/// The synthetic simulator: the truth plus seeded normal noise.
struct Simulator {
  Rng rng;
  Eigen::VectorXd operator()(const Eigen::VectorXd& natural) {
    Eigen::VectorXd y = truth(natural);
    for (int m = 0; m < 2; ++m) y(m) += kNoise(m) * rng.normal();
    return y;
  }
};

StageRuns simulate_stage(const std::vector<doe::Factor>& box, const doe::Design& d,
                         Simulator& sim) {
  StageRuns st{box, d.coded, Eigen::MatrixXd(d.runs(), 2)};
  for (int r = 0; r < d.runs(); ++r) {
    Eigen::VectorXd nat(3);
    for (int i = 0; i < 3; ++i) nat(i) = box[std::size_t(i)].to_natural(d.coded(r, i));
    st.responses.row(r) = sim(nat).transpose();
  }
  return st;
}

struct LoopOutcome {
  SequentialState state;
  SequentialDecision last;
};

/// Drives next_step to the end as the coordinator does, simulating what it asks for.
LoopOutcome run_loop(const Eigen::Vector2d& target, const Eigen::Vector2d& uncertainty,
                     const SequentialOptions& options, std::uint64_t seed = 2024) {
  Simulator sim{Rng(seed)};
  doe::Design design = doe::full_factorial(3);
  doe::add_centre_points(design, 3);
  LoopOutcome out;
  SequentialState& s = out.state;
  s.factors = kBox;
  s.stages.push_back(simulate_stage(kBox, design, sim));
  for (int m = 0; m < 2; ++m) {
    // The noise the coordinator reports: pure error of the centre points.
    const doe::ResponseAnalysis a =
        doe::analyse_response(design.coded, s.stages[0].responses.col(m), {});
    EXPECT_TRUE(a.noise.available());
    s.targets.push_back({"m" + std::to_string(m), target(m), 1.0, uncertainty(m), a.noise.sd});
  }
  for (int step = 0; step < 40; ++step) {
    out.last = next_step(s, options);
    if (out.last.step == NextStep::kDone) break;
    if (out.last.step == NextStep::kVerify) {
      const int batch = s.rounds.empty() ? 1 : s.rounds.back().batch + 1;
      for (std::size_t b = 0; b < out.last.batch.size(); ++b) {
        s.rounds.push_back({out.last.stage,
                            out.last.batch[b],
                            out.last.batch_predicted[b],
                            sim(out.last.batch[b]),
                            batch,
                            {}});
        s.jobs_used += 1;
      }
    } else {
      s.stages.push_back(simulate_stage(out.last.next_box, design, sim));
      s.jobs_used += design.runs();
    }
  }
  return out;
}

TEST(Sequential, HiddenTruthEndsWithinUncertaintyAfterMoreThanOneRound) {
  // Three hidden parameter sets, each with its own noise seed.
  const double hidden_sets[3][3] = {{0.38, 0.31, 3e7}, {0.22, 0.5, 4e6}, {0.45, 0.25, 6e7}};
  int missed_first = 0;
  for (int h = 0; h < 3; ++h) {
    Eigen::VectorXd hidden(3);
    hidden << hidden_sets[h][0], hidden_sets[h][1], hidden_sets[h][2];
    const Eigen::VectorXd y = truth(hidden);
    const Eigen::Vector2d target(y(0), y(1)), uncertainty(0.004, 0.12);
    const LoopOutcome o = run_loop(target, uncertainty, {}, 2024 + h);
    ASSERT_EQ(o.last.step, NextStep::kDone) << o.last.conclusion;
    std::printf("hidden set %d: %s; first round %s\n", h, o.last.conclusion.c_str(),
                score_point(o.state.targets, *o.state.rounds.front().simulated).within
                    ? "within"
                    : "not within");
    EXPECT_TRUE(o.last.within) << h << ": " << o.last.conclusion;
    EXPECT_EQ(o.last.conclusion.rfind("within uncertainty after ", 0), 0u) << o.last.conclusion;
    EXPECT_EQ(o.last.accepted_round, static_cast<int>(o.state.rounds.size()) - 1);
    ASSERT_FALSE(o.state.rounds.empty());
    missed_first += score_point(o.state.targets, *o.state.rounds.front().simulated).within ? 0 : 1;
    // The last simulated point is within tolerance by the noise-free truth as well, give or
    // take the noise it was judged with.
    const Eigen::VectorXd at = truth(o.state.rounds.back().natural);
    for (int m = 0; m < 2; ++m) {
      const double tol = std::hypot(uncertainty(m), o.state.targets[std::size_t(m)].noise_sd);
      EXPECT_LE(std::abs(at(m) - target(m)), tol + 3.0 * kNoise(m)) << h << " metric " << m;
    }
  }
  // The first proposal of the two-level models misses the curved truth: the loop mattered.
  EXPECT_GE(missed_first, 2);
}

TEST(Sequential, GaussianProcessBatchesEndWithinUncertaintyOnTheSameHiddenTruths) {
  // The same three hidden sets, seeds and first design; GP surrogates over all runs, batches of
  // two points by expected improvement, up to 10 batches, no stages.
  const double hidden_sets[3][3] = {{0.38, 0.31, 3e7}, {0.22, 0.5, 4e6}, {0.45, 0.25, 6e7}};
  SequentialOptions opt;
  opt.surrogate = Surrogate::kGaussianProcess;
  opt.batch = 2;
  opt.rounds = 10;
  for (int h = 0; h < 3; ++h) {
    Eigen::VectorXd hidden(3);
    hidden << hidden_sets[h][0], hidden_sets[h][1], hidden_sets[h][2];
    const Eigen::VectorXd y = truth(hidden);
    const LoopOutcome o =
        run_loop(Eigen::Vector2d(y(0), y(1)), Eigen::Vector2d(0.004, 0.12), opt, 2024 + h);
    std::printf("gp hidden set %d: %s\n", h, o.last.conclusion.c_str());
    EXPECT_TRUE(o.last.within) << h << ": " << o.last.conclusion;
    EXPECT_EQ(o.state.stages.size(), 1u);
    EXPECT_EQ(o.state.jobs_used % 2, 0);  // whole batches
  }
}

TEST(Sequential, UnreachableTargetStopsAtTheJobBudgetAndNamesTheMetric) {
  SequentialOptions opt;
  opt.max_jobs = 14;  // one stage of 11 runs does not fit after 3 rounds: rounds only
  const LoopOutcome o = run_loop(Eigen::Vector2d(0.56, 30.0), Eigen::Vector2d(0.004, 0.12), opt);
  EXPECT_FALSE(o.last.within);
  EXPECT_LE(o.state.jobs_used, opt.max_jobs);
  EXPECT_EQ(o.state.stages.size(), 1u);
  EXPECT_EQ(o.state.rounds.size(), 3u);
  EXPECT_NE(o.last.conclusion.find("not within uncertainty after 3 round(s) (3 simulations)"),
            std::string::npos)
      << o.last.conclusion;
  EXPECT_NE(o.last.conclusion.find("m1 simulated"), std::string::npos) << o.last.conclusion;
  EXPECT_NE(o.last.conclusion.find("x its tolerance"), std::string::npos) << o.last.conclusion;
  // The set it ends with is the verified round closest to the targets, the one it names.
  ASSERT_GE(o.last.best_round, 0);
  const auto worst = [&](const VerifiedRound& r) {
    double w = 0.0;
    for (std::size_t m = 0; m < o.state.targets.size(); ++m)
      w = std::max(w, std::abs((*r.simulated)(Eigen::Index(m)) - o.state.targets[m].target) /
                          tolerance(o.state.targets[m]));
    return w;
  };
  for (const auto& r : o.state.rounds)
    EXPECT_LE(worst(o.state.rounds[std::size_t(o.last.best_round)]), worst(r));
}

/// A campaign's design on the synthetic simulator with targets at `hidden`, and one verified
/// round there whose simulated values are the noise-free truth: within tolerance.
SequentialState state_with_a_round_at(const Eigen::VectorXd& hidden) {
  Simulator sim{Rng(7)};
  doe::Design design = doe::full_factorial(3);
  doe::add_centre_points(design, 3);
  SequentialState s;
  s.factors = kBox;
  s.stages.push_back(simulate_stage(kBox, design, sim));
  const Eigen::VectorXd y = truth(hidden);
  for (int m = 0; m < 2; ++m)
    s.targets.push_back({"m" + std::to_string(m), y(m), 1.0, 0.01 * std::abs(y(m)), kNoise(m)});
  s.rounds.push_back({1, hidden, y, y, 1, {}});
  s.jobs_used = 1;
  return s;
}

TEST(Sequential, ARoundWithinOnlyByAFlaggedValueIsNotAccepted) {
  const Eigen::Vector3d hidden(0.38, 0.31, 3e7);
  SequentialState s = state_with_a_round_at(hidden);
  ASSERT_TRUE(score_point(s.targets, *s.rounds[0].simulated).within);
  SequentialOptions options;
  options.stages = 1;
  options.rounds = 1;
  // Unflagged, the round is the calibrated set.
  SequentialDecision d = next_step(s, options);
  EXPECT_TRUE(d.within) << d.conclusion;
  EXPECT_EQ(d.accepted_round, 0);
  // The same values with m0's flagged (a phase it is computed from missed its target): the
  // round is not accepted, and with the rounds spent the calibration ends not within, saying why.
  s.rounds[0].flagged = {true, false};
  d = next_step(s, options);
  EXPECT_FALSE(d.within) << d.conclusion;
  EXPECT_EQ(d.step, NextStep::kDone);
  EXPECT_EQ(d.accepted_round, -1);
  EXPECT_EQ(d.conclusion.rfind("not within uncertainty after 1 round(s)", 0), 0u) << d.conclusion;
  EXPECT_NE(d.conclusion.find("round 1 is within tolerance, but its simulated m0 flagged (a phase "
                              "did not reach its target): not accepted"),
            std::string::npos)
      << d.conclusion;
  // With rounds left it verifies again, under either surrogate, and says why.
  for (const Surrogate surrogate : {Surrogate::kPolynomial, Surrogate::kGaussianProcess}) {
    options.surrogate = surrogate;
    options.rounds = 3;
    d = next_step(s, options);
    EXPECT_FALSE(d.within) << d.conclusion;
    EXPECT_EQ(d.step, NextStep::kVerify) << d.conclusion;
    EXPECT_NE(d.conclusion.find("round 1 is within tolerance, but its simulated m0 flagged"),
              std::string::npos)
        << d.conclusion;
    // A second round within and unflagged is accepted, and the first stays refused.
    s.rounds.push_back({1, hidden, truth(hidden), truth(hidden), 2, {}});
    const SequentialDecision second = next_step(s, options);
    EXPECT_TRUE(second.within) << second.conclusion;
    EXPECT_EQ(second.accepted_round, 1);
    s.rounds.pop_back();
  }
}

TEST(Sequential, OptionsOutOfRangeNameTheField) {
  SequentialOptions o;
  o.rounds = 0;
  try {
    o.validate("spec.calibration");
    ADD_FAILURE() << "rounds 0 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("spec.calibration.rounds"), std::string::npos);
  }
  o = {};
  o.narrow = std::nan("");
  EXPECT_THROW(o.validate("c"), InputError);
  o = {};
  o.narrow = 1.0;
  EXPECT_THROW(o.validate("c"), InputError);
}

TEST(Sequential, NarrowedBoxStaysInsideAndKeepsLogScale) {
  Eigen::VectorXd corner(3);
  corner << 0.5, 0.2, 1e8;
  const auto box = narrowed_box(kBox, corner, 0.3);
  EXPECT_NEAR(box[0].high, 0.5, 1e-12);
  EXPECT_NEAR(box[0].low, 0.5 - 0.3 * 0.4, 1e-12);
  EXPECT_NEAR(box[1].low, 0.2, 1e-12);
  EXPECT_NEAR(box[2].high, 1e8, 1e-3);
  EXPECT_NEAR(std::log10(box[2].high / box[2].low), 0.3 * 2.0, 1e-12);
  EXPECT_EQ(box[2].scale, doe::Scale::kLog);
}

}  // namespace
}  // namespace demcal::calib
