#pragma once
// The aliasing of a regular two-level design, read from its runs rather than from its
// generators, so that the same code serves catalogue designs, user generators and fold-overs.
// A regular fraction is an affine subspace of GF(2)^k; its defining words are the
// orthogonal complement of the subspace's direction (Mee 2009, "A Comprehensive Guide to
// Factorial Two-Level Experimentation", ch. 5). Definitions follow FrF2 (Groemping 2014):
// a 2FI is clear when it is aliased with no main effect and no other 2FI.
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "core/doe/word.hpp"

namespace demcal::doe {

struct AliasStructure {
  int factor_count = 0;
  int distinct_runs = 0;
  /// False when the two-level runs do not form a regular fraction (then nothing below is set).
  bool regular = true;
  /// Defining relation I = w1 = w2 = ..., words sorted by length then letters.
  std::vector<SignedWord> defining_relation;
  /// A_3, A_4, ..., A_k: the number of defining words of each length.
  std::vector<int> word_length_pattern;
  /// Shortest defining word; empty for a full factorial.
  std::optional<int> resolution;
  /// 2FIs aliased with other 2FIs or main effects, each chain sorted, first member sign +1.
  std::vector<std::vector<SignedWord>> two_factor_chains;
  /// Main effects aliased with 2FIs (resolution III): each chain starts with the main effect.
  std::vector<std::vector<SignedWord>> main_effect_chains;
  /// 2FIs aliased with no main effect and no other 2FI.
  std::vector<Word> clear_two_factor;

  int two_factor_count() const { return factor_count * (factor_count - 1) / 2; }
  /// The main effects and 2FIs aliased with `effect` (itself first), as a chain.
  std::vector<SignedWord> chain_of(Word effect) const;
};

/// Aliasing of the two-level runs of `coded` (rows with any entry other than +-1, such as
/// centre or axial points, are ignored; repeated runs count once).
AliasStructure analyse_aliasing(const Eigen::MatrixXd& coded);

/// "IV" for 4; "full factorial" when there is no defining word.
std::string resolution_name(const std::optional<int>& resolution);

}  // namespace demcal::doe
