#pragma once
// Minimum-aberration 2^(k-p) generators (Fries and Hunter 1980): among all regular fractions
// the one whose word-length pattern (A_3, A_4, ...) is smallest in lexicographic order; ties
// are broken by the larger number of clear 2FIs (FrF2's MaxC2 criterion, Groemping 2014).
// Two FrF2 catalogue entries are stored verbatim (those of tests/data/doe-oracle/);
// everything else comes from an exhaustive branch-and-bound search whose result carries
// whether it completed (proven minimum aberration) or hit its node budget.
#include <cstdint>
#include <string>
#include <vector>

#include "core/doe/design.hpp"

namespace demcal::doe {

struct GeneratorChoice {
  std::vector<Word> generators;  ///< one base word per added factor
  std::vector<int> word_length_pattern;
  int clear_two_factor = 0;
  /// "catalogue FrF2 catlg 12-7.1" or "search".
  std::string source;
  /// True when the search enumerated every candidate (or the entry is from the catalogue).
  bool proven = true;
  std::uint64_t nodes = 0;
};

/// Default node budget of the search: the 32-run cases of the oracle complete in about 0.1 s;
/// the largest cases (15 factors in 64 or 128 runs) stop after a few seconds, unproven.
inline constexpr std::uint64_t kDefaultSearchNodes = 4'000'000;

/// Searches without consulting the catalogue (used to check the catalogue).
GeneratorChoice search_minimum_aberration(int factor_count, int runs,
                                          std::uint64_t node_budget = kDefaultSearchNodes);

/// Catalogue entry when there is one, else the search.
GeneratorChoice minimum_aberration_generators(int factor_count, int runs,
                                              std::uint64_t node_budget = kDefaultSearchNodes);

/// The design: full factorial when runs = 2^k, otherwise the minimum-aberration fraction.
Design minimum_aberration_design(int factor_count, int runs);

/// Lexicographic comparison of word-length patterns (shorter words weigh first).
int compare_word_length_patterns(const std::vector<int>& a, const std::vector<int>& b);

}  // namespace demcal::doe
