// The fraction nested in a design that a multi-fidelity campaign runs at the high level: a
// subset of the design's factorial runs, regular, of the smallest size that still estimates every
// main effect, at the best resolution a half of a half can keep.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/doe/alias_structure.hpp"
#include "core/doe/minimum_aberration.hpp"
#include "core/doe/nested_fraction.hpp"

namespace demcal::doe {
namespace {

AliasStructure aliasing_of(const Design& d, const std::vector<int>& rows) {
  Eigen::MatrixXd coded(Eigen::Index(rows.size()), d.factors());
  for (std::size_t i = 0; i < rows.size(); ++i) coded.row(Eigen::Index(i)) = d.coded.row(rows[i]);
  return analyse_aliasing(coded);
}

TEST(NestedFraction, HalvesTheLactoseCalibrationDesignToAResolutionThreeHalf) {
  // Seed 000 Table 8's size: 2^(8-3), resolution IV; 16 runs still estimate 8 main effects.
  // The minimum-aberration 2^(8-3) has defining words of length 5, and the 2^(8-4) of
  // resolution IV has words of lengths 4 and 8 only, so no half of it is of resolution IV:
  // the best nested half is of resolution III.
  Design d = minimum_aberration_design(8, 32);
  add_centre_points(d, 1);
  const auto rows = nested_fraction(d, 9);
  ASSERT_EQ(rows.size(), 16u);
  const std::set<int> distinct(rows.begin(), rows.end());
  EXPECT_EQ(distinct.size(), 16u);
  for (const int r : rows) EXPECT_EQ(d.point_type[std::size_t(r)], PointType::kFactorial);
  const auto a = aliasing_of(d, rows);
  EXPECT_TRUE(a.regular);
  ASSERT_TRUE(a.resolution);
  EXPECT_EQ(*a.resolution, 3);
  ASSERT_GE(a.word_length_pattern.size(), 1u);
  // Against every half by one base word: none has fewer words of length 3.
  const int base = 5;
  for (Word w = 1; w < (Word{1} << base); ++w) {
    std::vector<int> half;
    for (int r = 0; r < 32; ++r) {
      int s = 1;
      for (int f = 0; f < base; ++f)
        if (w & (Word{1} << f)) s *= d.coded(r, f) > 0 ? 1 : -1;
      if (s > 0) half.push_back(r);
    }
    const auto b = aliasing_of(d, half);
    if (b.resolution && *b.resolution == 3) {
      EXPECT_GE(b.word_length_pattern[0], a.word_length_pattern[0]) << word_name(w);
    }
  }
}

TEST(NestedFraction, AFullFactorialOfThreeFactorsGivesItsHalfOfResolutionThree) {
  const Design d = full_factorial(3);
  const auto rows = nested_fraction(d, 4);
  ASSERT_EQ(rows.size(), 4u);
  const auto a = aliasing_of(d, rows);
  ASSERT_TRUE(a.resolution);
  EXPECT_EQ(*a.resolution, 3);  // I = ABC, the best half
}

TEST(NestedFraction, ADesignWithNoSmallerFractionGivesAllItsFactorialRuns) {
  Design d = fractional_factorial(3, "C=AB");
  add_centre_points(d, 2);
  replicate_runs(d, 2);
  const auto rows = nested_fraction(d, 4);
  EXPECT_EQ(rows, (std::vector<int>{0, 1, 2, 3}));  // the first replicate's factorial runs
}

/// log det of X'X of the main-effect model (intercept and k main effects) on `rows`.
double log_det(const Design& d, const std::vector<int>& rows) {
  Eigen::MatrixXd x(Eigen::Index(rows.size()), d.factors() + 1);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    x(Eigen::Index(i), 0) = 1.0;
    x.row(Eigen::Index(i)).tail(d.factors()) = d.coded.row(rows[i]);
  }
  return std::log((x.transpose() * x).determinant());
}

TEST(NestedFraction, AResolutionFiveHalfFractionOfFiveFactorsHasOnlyANonRegularHalf) {
  Design d = fractional_factorial(5, "E=ABCD");
  add_centre_points(d, 1);
  // No regular half keeps resolution III: the nested fraction is the whole design.
  EXPECT_EQ(nested_fraction(d, 6).size(), 16u);
  const auto half = main_effect_half(d);
  ASSERT_EQ(half.size(), 8u);
  EXPECT_EQ(std::set<int>(half.begin(), half.end()).size(), 8u);
  for (const int r : half) EXPECT_LT(r, 16) << "the centre run is no factorial run";
  // Every main effect estimable, and no half of the 16 runs does better (all 12,870 tried).
  const double found = log_det(d, half);
  ASSERT_TRUE(std::isfinite(found));
  double best = -1e300;
  for (int mask = 0; mask < (1 << 16); ++mask) {
    if (__builtin_popcount(unsigned(mask)) != 8) continue;
    std::vector<int> rows;
    for (int r = 0; r < 16; ++r)
      if (mask & (1 << r)) rows.push_back(r);
    const double v = log_det(d, rows);
    if (std::isfinite(v)) best = std::max(best, v);
  }
  EXPECT_NEAR(found, best, 1e-9);
}

TEST(NestedFraction, TheMainEffectHalfIsTheRegularHalfWhereOneExists) {
  EXPECT_EQ(main_effect_half(full_factorial(3)), nested_fraction(full_factorial(3), 4));
  const Design lactose = fractional_factorial(8, "F=ABC G=ABD H=ACDE");
  EXPECT_EQ(main_effect_half(lactose), nested_fraction(lactose, 9));
  EXPECT_EQ(main_effect_half(lactose).size(), 16u);
}

}  // namespace
}  // namespace demcal::doe
