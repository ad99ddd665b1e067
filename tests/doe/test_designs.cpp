// Designs against the FrF2 oracle in tests/data/doe-oracle/ (FrF2 2.3.4 output).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/common/error.hpp"
#include "core/doe/alias_structure.hpp"
#include "core/doe/design.hpp"
#include "core/doe/minimum_aberration.hpp"

namespace demcal::doe {
namespace {

const std::string kOracle = std::string(DEMCAL_SOURCE_DIR) + "/tests/data/doe-oracle/";

/// An oracle file, open; a missing one is an error naming its path (the test fails, no crash).
std::ifstream open_oracle(const std::string& file) {
  std::ifstream in(kOracle + file);
  if (!in) throw std::runtime_error("cannot read the FrF2 oracle file " + kOracle + file);
  return in;
}

Eigen::MatrixXd read_oracle_matrix(const std::string& file) {
  std::ifstream in = open_oracle(file);
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<double> row;
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  Eigen::MatrixXd m(static_cast<Eigen::Index>(rows.size()),
                    static_cast<Eigen::Index>(rows.front().size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < rows[r].size(); ++c)
      m(Eigen::Index(r), Eigen::Index(c)) = rows[r][c];
  }
  return m;
}

std::vector<std::string> chain_names(const AliasStructure& a) {
  std::vector<std::string> names;
  for (const auto& chain : a.two_factor_chains) {
    std::string name;
    for (std::size_t i = 0; i < chain.size(); ++i)
      name += (i ? "=" : "") + word_name(chain[i].word);
    names.push_back(name);
  }
  return names;
}

std::vector<std::string> defining_words(const AliasStructure& a) {
  std::vector<std::string> out;
  for (const auto& w : a.defining_relation) out.push_back(word_name(w));
  return out;
}

/// The 2FI chains of one section of foldover_checks.txt. FrF2 adds the fold as a block
/// factor named F and shifts the later letters up by one; map them back (G->F, ..., N->M)
/// so the chains can be compared with those of the folded design without a block factor.
std::vector<std::string> oracle_fold_chains(const std::string& section) {
  std::ifstream in = open_oracle("foldover_checks.txt");
  std::string line;
  bool inside = false, fi2 = false;
  std::vector<std::string> chains;
  while (std::getline(in, line)) {
    if (line.rfind("== ", 0) == 0) {
      if (inside) break;
      inside = line.find(section) != std::string::npos;
      continue;
    }
    if (!inside) continue;
    if (line.find("$fi2") != std::string::npos) fi2 = true;
    if (!fi2) continue;
    for (std::size_t q = line.find('"'); q != std::string::npos; q = line.find('"', q + 1)) {
      const std::size_t e = line.find('"', q + 1);
      std::string chain = line.substr(q + 1, e - q - 1);
      q = e;
      std::vector<std::string> members;
      std::stringstream ss(chain);
      for (std::string m; std::getline(ss, m, '=');) {
        EXPECT_EQ(m.find('F'), std::string::npos) << "fold block in chain " << chain;
        for (char& c : m) c = c > 'F' ? factor_letter(factor_index(c) - 1) : c;
        std::sort(m.begin(), m.end());
        members.push_back(m);
      }
      std::sort(members.begin(), members.end());
      std::string name;
      for (const auto& m : members) name += (name.empty() ? "" : "=") + m;
      chains.push_back(name);
    }
  }
  std::sort(chains.begin(), chains.end());
  EXPECT_FALSE(chains.empty()) << section;
  return chains;
}

TEST(Oracle, Frf2_32_12_MatchesCatalogueEntry12_7_1) {
  const Design d = minimum_aberration_design(12, 32);
  EXPECT_EQ(generators_text(d), "F=ABC G=ABD H=ACD J=BCD K=ABE L=ACE M=ADE");
  EXPECT_TRUE(d.coded.isApprox(read_oracle_matrix("frf2_32run_12fac_design_standard_order.csv")));
  const AliasStructure a = analyse_aliasing(d.coded);
  EXPECT_EQ(a.resolution, 4);
  EXPECT_EQ(a.word_length_pattern, (std::vector<int>{0, 38, 0, 52, 0, 33, 0, 4, 0, 0}));
  EXPECT_EQ(a.defining_relation.size(), 127u);
  EXPECT_EQ(defining_words(a).front(), "ABCF");
  EXPECT_EQ(defining_words(a).back(), "BCDEFGHKLM");
  EXPECT_TRUE(a.main_effect_chains.empty());
  EXPECT_EQ(a.clear_two_factor.size(), 0u);
  EXPECT_EQ(chain_names(a), (std::vector<std::string>{
                                "AB=CF=DG=EK=HJ", "AC=BF=DH=EL=GJ", "AD=BG=CH=EM=FJ", "AE=BK=CL=DM",
                                "AF=BC=DJ=GH=KL", "AG=BD=CJ=FH=KM", "AH=BJ=CD=FG=LM", "AJ=BH=CG=DF",
                                "AK=BE=FL=GM", "AL=CE=FK=HM", "AM=DE=GK=HL", "BL=CK=EF=JM",
                                "BM=DK=EG=JL", "CM=DL=EH=JK", "EJ=FM=GL=HK"}));
}

TEST(Oracle, Frf2_32_12_WithCentrePointMatchesNcenter1File) {
  Design d = minimum_aberration_design(12, 32);
  add_centre_points(d, 1);
  EXPECT_TRUE(d.coded.isApprox(read_oracle_matrix("frf2_32run_12fac_ncenter1.csv")));
  EXPECT_EQ(d.point_type.back(), PointType::kCentre);
}

TEST(Oracle, Frf2_32_8_MatchesCatalogueEntry8_3_1) {
  const Design d = minimum_aberration_design(8, 32);
  EXPECT_EQ(generators_text(d), "F=ABC G=ABD H=ACDE");
  EXPECT_TRUE(d.coded.isApprox(read_oracle_matrix("frf2_32run_8fac_design_standard_order.csv")));
  const AliasStructure a = analyse_aliasing(d.coded);
  EXPECT_EQ(a.resolution, 4);
  EXPECT_EQ(a.word_length_pattern, (std::vector<int>{0, 3, 4, 0, 0, 0}));
  EXPECT_EQ(defining_words(a),
            (std::vector<std::string>{"ABCF", "ABDG", "CDFG", "ACDEH", "AEFGH", "BCEGH", "BDEFH"}));
  EXPECT_EQ(a.clear_two_factor.size(), 13u);
  EXPECT_EQ(chain_names(a), (std::vector<std::string>{"AB=CF=DG", "AC=BF", "AD=BG", "AF=BC",
                                                      "AG=BD", "CD=FG", "CG=DF"}));
  // All 2FIs of E and of H are clear (catlg_ranking.txt).
  int with_e_or_h = 0;
  for (const Word w : a.clear_two_factor) with_e_or_h += (w & 0b10010000) ? 1 : 0;
  EXPECT_EQ(with_e_or_h, 13);
}

TEST(Oracle, NistTwoToTheEightMinusThreeIsEquivalent) {
  const Design d = fractional_factorial(8, "F=ABC G=ABD H=BCDE");
  EXPECT_TRUE(d.coded.isApprox(read_oracle_matrix("alt_nist_8_3_design_standard_order.csv")));
  const AliasStructure a = analyse_aliasing(d.coded);
  EXPECT_EQ(a.resolution, 4);
  EXPECT_EQ(a.word_length_pattern, (std::vector<int>{0, 3, 4, 0, 0, 0}));
  EXPECT_EQ(defining_words(a),
            (std::vector<std::string>{"ABCF", "ABDG", "CDFG", "ACEGH", "ADEFH", "BCDEH", "BEFGH"}));
  EXPECT_EQ(a.clear_two_factor.size(), 13u);
  EXPECT_EQ(chain_names(a), (std::vector<std::string>{"AB=CF=DG", "AC=BF", "AD=BG", "AF=BC",
                                                      "AG=BD", "CD=FG", "CG=DF"}));
}

TEST(Oracle, LexicographicGeneratorsAreRecognisedAsWorse) {
  const AliasStructure naive = analyse_aliasing(fractional_factorial(8, "F=ABC G=ABD H=ABE").coded);
  EXPECT_EQ(naive.word_length_pattern, (std::vector<int>{0, 6, 0, 0, 0, 1}));
  EXPECT_EQ(naive.two_factor_chains.size(), 13u);
  EXPECT_EQ(naive.clear_two_factor.size(), 0u);
  EXPECT_EQ(chain_names(naive).front(), "AB=CF=DG=EH");
  const GeneratorChoice best = minimum_aberration_generators(8, 32);
  EXPECT_GT(compare_word_length_patterns(naive.word_length_pattern, best.word_length_pattern), 0);
  EXPECT_EQ(best.clear_two_factor, 13);
}

TEST(Search, ReproducesTheCatalogueOptimumWithoutIt) {
  for (const auto& [k, wlp] : std::vector<std::pair<int, std::vector<int>>>{
           {12, {0, 38, 0, 52, 0, 33, 0, 4, 0, 0}}, {8, {0, 3, 4, 0, 0, 0}}}) {
    const GeneratorChoice found = search_minimum_aberration(k, 32);
    EXPECT_TRUE(found.proven) << k;
    EXPECT_EQ(found.word_length_pattern, wlp) << k;
    const int clear = k == 8 ? 13 : 0;
    EXPECT_EQ(found.clear_two_factor, clear) << k;
  }
}

TEST(Search, SmallCasesHaveTheTextbookResolution) {
  // Montgomery (2017) Table 8.14: 2^(4-1)_IV, 2^(5-1)_V, 2^(7-4)_III, 2^(6-2)_IV, 2^(8-4)_IV.
  const std::vector<std::tuple<int, int, int>> cases{{4, 8, 4},  {5, 16, 5},  {7, 8, 3}, {6, 16, 4},
                                                     {8, 16, 4}, {15, 16, 3}, {7, 64, 7}};
  for (const auto& [k, runs, res] : cases) {
    const GeneratorChoice g = search_minimum_aberration(k, runs);
    const Design d = minimum_aberration_design(k, runs);
    EXPECT_TRUE(g.proven) << k << " " << runs;
    EXPECT_EQ(analyse_aliasing(d.coded).resolution, res) << k << " " << runs;
  }
}

TEST(FoldOver, FullFoldOverOfTheTwelveFactorDesignAddsNoNewRuns) {
  const Design d = minimum_aberration_design(12, 32);
  const Design folded = fold_over(d, (Word{1} << 12) - 1);
  EXPECT_EQ(folded.runs(), 64);
  const AliasStructure a = analyse_aliasing(folded.coded);
  EXPECT_EQ(a.distinct_runs, 32);
  EXPECT_EQ(chain_names(a), chain_names(analyse_aliasing(d.coded)));
}

TEST(FoldOver, FoldingOnOneFactorClearsItsTwoFactorInteractions) {
  const Design d = minimum_aberration_design(12, 32);
  const AliasStructure a = analyse_aliasing(fold_over(d, Word{1}).coded);
  EXPECT_EQ(a.distinct_runs, 64);
  EXPECT_EQ(chain_names(a), oracle_fold_chains("FrF2(32,12) foldover on factor A only"));
  for (int j = 1; j < 12; ++j) {
    const Word pair = Word{1} | (Word{1} << j);
    EXPECT_NE(std::find(a.clear_two_factor.begin(), a.clear_two_factor.end(), pair),
              a.clear_two_factor.end())
        << word_name(pair);
  }
}

TEST(FoldOver, EightFactorFoldOversMatchTheOracle) {
  const Design d = minimum_aberration_design(8, 32);
  const AliasStructure full = analyse_aliasing(fold_over(d, 0xFF).coded);
  EXPECT_EQ(chain_names(full), oracle_fold_chains("FrF2(32,8) full foldover"));
  EXPECT_EQ(chain_names(full), chain_names(analyse_aliasing(d.coded)));
  // The full fold-over removes the odd (length-5) words and keeps the length-4 ones.
  EXPECT_EQ(full.word_length_pattern, (std::vector<int>{0, 3, 0, 0, 0, 0}));
  const AliasStructure on_a = analyse_aliasing(fold_over(d, 0x01).coded);
  EXPECT_EQ(chain_names(on_a), oracle_fold_chains("FrF2(32,8) foldover on factor A only"));
  EXPECT_EQ(on_a.clear_two_factor.size(), 22u);
}

}  // namespace
}  // namespace demcal::doe
