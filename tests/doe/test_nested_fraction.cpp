// The fraction nested in a design that a multi-fidelity campaign runs at the high level: a
// subset of the design's factorial runs, regular, of the smallest size that still estimates every
// main effect, at the best resolution a half of a half can keep.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace demcal::doe
