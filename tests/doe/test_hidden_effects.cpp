// Hidden-effect trials: responses synthesised on random designs from a random sparse truth
// (main effects, one hidden 2FI of random size and place, optional curvature, unit noise),
// seeded. The rates measured here are printed; the bounds asserted are the claims.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/common/rng.hpp"
#include "core/doe/analysis.hpp"
#include "core/doe/design.hpp"
#include "core/doe/minimum_aberration.hpp"

namespace demcal::doe {
namespace {

struct Truth {
  std::vector<std::pair<int, double>> mains;
  Word hidden = 0;
  double hidden_size = 0.0;
  double curvature = 0.0;  ///< coefficient of x_0^2
  double response(const Eigen::RowVectorXd& x, Rng& rng) const {
    double y = 10.0 + rng.normal();
    for (const auto& [i, b] : mains) y += b * x(i);
    double prod = hidden_size;
    for (int i = 0; i < x.size(); ++i) {
      if (hidden & (Word{1} << i)) prod *= x(i);
    }
    return y + prod + curvature * x(0) * x(0);
  }
};

Truth random_truth(int k, Rng& rng) {
  Truth t;
  const int active = 2 + static_cast<int>(rng.below(2));
  while (static_cast<int>(t.mains.size()) < active) {
    const int i = static_cast<int>(rng.below(std::uint64_t(k)));
    bool dup = false;
    for (const auto& m : t.mains) dup = dup || m.first == i;
    if (!dup) t.mains.emplace_back(i, (rng.uniform() < 0.5 ? -1 : 1) * rng.uniform(1.0, 2.0));
  }
  const int a = static_cast<int>(rng.below(std::uint64_t(k)));
  int b = a;
  while (b == a) b = static_cast<int>(rng.below(std::uint64_t(k)));
  t.hidden = (Word{1} << a) | (Word{1} << b);
  t.hidden_size = (rng.uniform() < 0.5 ? -1 : 1) * rng.uniform(1.0, 2.0);
  return t;
}

bool contains(const ModelTerm& term, Word w) {
  for (const auto& m : term.chain) {
    if (m.word == w && !term.squared) return true;
  }
  return false;
}

Eigen::VectorXd simulate(const Design& d, const Truth& truth, Rng& rng) {
  Eigen::VectorXd y(d.runs());
  for (int r = 0; r < d.runs(); ++r) y(r) = truth.response(d.coded.row(r), rng);
  return y;
}

const std::vector<std::pair<int, int>> kDesigns{{12, 32}, {8, 32}, {6, 16}, {7, 32}};

TEST(HiddenEffects, ActiveEffectsFlaggedAndFalsePositivesNearNominal) {
  constexpr int kTrials = 400;
  Rng rng(2024);
  int mains_total = 0, mains_found = 0, hidden_found = 0, null_total = 0, null_flagged = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const auto [k, runs] = kDesigns[rng.below(kDesigns.size())];
    const Design d = minimum_aberration_design(k, runs);
    const Truth truth = random_truth(k, rng);
    const ResponseAnalysis res = analyse_response(d.coded, simulate(d, truth, rng), {});
    for (const auto& e : res.effects) {
      bool is_true = contains(e.term, truth.hidden);
      for (const auto& [i, b] : truth.mains) {
        if (contains(e.term, Word{1} << i)) {
          is_true = true;
          ++mains_total;
          mains_found += e.active ? 1 : 0;
        }
      }
      if (contains(e.term, truth.hidden)) hidden_found += e.active ? 1 : 0;
      if (!is_true) {
        ++null_total;
        null_flagged += e.active ? 1 : 0;
      }
    }
  }
  const double main_rate = double(mains_found) / mains_total;
  const double hidden_rate = double(hidden_found) / kTrials;
  const double fp_rate = double(null_flagged) / null_total;
  std::printf(
      "hidden-effect trials: %d; main effects flagged %.4f; hidden-2FI chain flagged "
      "%.4f; false-positive rate %.4f (nominal alpha 0.05, %d null contrasts)\n",
      kTrials, main_rate, hidden_rate, fp_rate, null_total);
  EXPECT_GE(main_rate, 0.97);
  EXPECT_GE(hidden_rate, 0.90);
  EXPECT_GT(fp_rate, 0.01);
  EXPECT_LT(fp_rate, 0.08);
}

TEST(HiddenEffects, FoldOverAugmentationNamesTheTrueInteraction) {
  constexpr int kTrials = 100;
  Rng rng(77);
  int named = 0, folds_total = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const int k = trial % 2 ? 12 : 8;
    const Design original = minimum_aberration_design(k, 32);
    const Truth truth = random_truth(k, rng);
    Design d = original;
    Eigen::VectorXd y = simulate(d, truth, rng);
    std::vector<SignedWord> candidates;  // 2FIs the flagged chain may still be
    for (int fold = 0; fold < 4; ++fold) {
      const ResponseAnalysis res = analyse_response(d.coded, y, {});
      // The analyst's choice: the largest flagged 2FI term among the remaining candidates.
      const EffectEstimate* pick = nullptr;
      for (const auto& e : res.effects) {
        if (!e.active || e.term.order() != 2) continue;
        bool relevant = candidates.empty();
        for (const auto& c : candidates) relevant = relevant || contains(e.term, c.word);
        if (relevant && (!pick || std::abs(e.effect) > std::abs(pick->effect))) pick = &e;
      }
      if (!pick) break;
      candidates.clear();
      for (const auto& m : pick->term.chain) {
        if (word_length(m.word) == 2) candidates.push_back(m);
      }
      if (candidates.size() == 1) break;
      const Design mirror = fold_over(original, choose_fold_to_split(candidates, k));
      const Eigen::MatrixXd added = mirror.coded.bottomRows(original.runs());
      d.coded.conservativeResize(d.coded.rows() + added.rows(), Eigen::NoChange);
      d.coded.bottomRows(added.rows()) = added;
      y.conservativeResize(y.size() + added.rows());
      for (Eigen::Index r = 0; r < added.rows(); ++r) {
        y(y.size() - added.rows() + r) = truth.response(added.row(r), rng);
      }
      ++folds_total;
    }
    if (candidates.size() == 1 && candidates.front().word == truth.hidden) ++named;
  }
  std::printf(
      "fold-over augmentation: true 2FI named in %d of %d trials, %.2f folds on "
      "average\n",
      named, kTrials, double(folds_total) / kTrials);
  EXPECT_GE(named, 90);
}

TEST(HiddenEffects, CurvatureDetectedWhenPresentAndNotOtherwise) {
  constexpr int kTrials = 200;
  Rng rng(99);
  int detected = 0, false_alarms = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    Design d = minimum_aberration_design(8, 32);
    add_centre_points(d, 6);
    Truth truth = random_truth(8, rng);
    const bool curved = trial % 2 == 0;
    truth.curvature = curved ? (rng.uniform() < 0.5 ? -1 : 1) * rng.uniform(2.5, 3.5) : 0.0;
    const ResponseAnalysis res = analyse_response(d.coded, simulate(d, truth, rng), {});
    EXPECT_TRUE(res.curvature.available);
    if (curved) detected += res.curvature.significant ? 1 : 0;
    if (!curved) false_alarms += res.curvature.significant ? 1 : 0;
  }
  std::printf(
      "curvature: detected %d of %d curved responses, false alarms %d of %d flat ones "
      "(alpha 0.05)\n",
      detected, kTrials / 2, false_alarms, kTrials / 2);
  EXPECT_GE(detected, 95 * kTrials / 200);
  EXPECT_LE(false_alarms, 12 * kTrials / 200);
}

}  // namespace
}  // namespace demcal::doe
