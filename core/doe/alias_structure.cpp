#include "core/doe/alias_structure.hpp"

#include <algorithm>
#include <cstdint>
#include <set>

#include "core/common/error.hpp"

namespace demcal::doe {

namespace {

/// Bit i set when factor i is at its low level, so that the product of the columns in word
/// w on run r is (-1)^popcount(r & w).
std::vector<Word> two_level_runs(const Eigen::MatrixXd& coded) {
  std::set<Word> runs;
  for (Eigen::Index r = 0; r < coded.rows(); ++r) {
    Word bits = 0;
    bool two_level = true;
    for (Eigen::Index c = 0; c < coded.cols(); ++c) {
      const double v = coded(r, c);
      if (v == -1.0) {
        bits |= Word{1} << c;
      } else if (v != 1.0) {
        two_level = false;
        break;
      }
    }
    if (two_level) runs.insert(bits);
  }
  return {runs.begin(), runs.end()};
}

bool word_less(const SignedWord& a, const SignedWord& b) {
  const int la = word_length(a.word), lb = word_length(b.word);
  if (la != lb) return la < lb;
  return word_name(a.word) < word_name(b.word);
}

}  // namespace

std::vector<SignedWord> AliasStructure::chain_of(Word effect) const {
  std::vector<SignedWord> chain{{effect, 1}};
  for (const auto& w : defining_relation) {
    const Word other = effect ^ w.word;
    if (word_length(other) <= 2) chain.push_back({other, w.sign});
  }
  std::sort(chain.begin() + 1, chain.end(), word_less);
  return chain;
}

AliasStructure analyse_aliasing(const Eigen::MatrixXd& coded) {
  const int k = static_cast<int>(coded.cols());
  if (k < 1 || k > kMaxFactors) {
    throw InputError("design", "alias analysis needs 1 to " + std::to_string(kMaxFactors) +
                                   " factors, got " + std::to_string(k));
  }
  AliasStructure out;
  out.factor_count = k;
  const std::vector<Word> runs = two_level_runs(coded);
  out.distinct_runs = static_cast<int>(runs.size());
  if (runs.empty()) throw InputError("design", "no two-level runs to analyse");

  // Reduced row echelon basis of the directions r ^ r0 over GF(2).
  const Word r0 = runs.front();
  std::vector<Word> basis;  // each with a distinct pivot bit (its lowest set bit)
  for (const Word r : runs) {
    Word d = r ^ r0;
    for (const Word b : basis) {
      if (d & (b & -b)) d ^= b;
    }
    if (d == 0) continue;
    const Word pivot = d & -d;
    for (Word& b : basis) {
      if (b & pivot) b ^= d;
    }
    basis.push_back(d);
  }
  const int rank = static_cast<int>(basis.size());
  if (out.distinct_runs != (1 << rank)) {
    out.regular = false;
    return out;
  }
  // Null space: one vector per free (non-pivot) column f, with the pivot bits of the basis
  // rows that contain f.
  Word pivots = 0;
  for (const Word b : basis) pivots |= b & -b;
  std::vector<Word> null_basis;
  for (int f = 0; f < k; ++f) {
    const Word fb = Word{1} << f;
    if (pivots & fb) continue;
    Word v = fb;
    for (const Word b : basis) {
      if (b & fb) v |= b & -b;
    }
    null_basis.push_back(v);
  }
  const std::size_t p = null_basis.size();
  for (std::uint64_t mask = 1; mask < (std::uint64_t{1} << p); ++mask) {
    Word w = 0;
    for (std::size_t j = 0; j < p; ++j) {
      if (mask & (std::uint64_t{1} << j)) w ^= null_basis[j];
    }
    out.defining_relation.push_back({w, (std::popcount(r0 & w) % 2) ? -1 : 1});
  }
  std::sort(out.defining_relation.begin(), out.defining_relation.end(), word_less);

  out.word_length_pattern.assign(static_cast<std::size_t>(std::max(0, k - 2)), 0);
  for (const auto& w : out.defining_relation) {
    const int len = word_length(w.word);
    if (!out.resolution || len < *out.resolution) out.resolution = len;
    if (len >= 3) ++out.word_length_pattern[static_cast<std::size_t>(len - 3)];
  }

  for (int i = 0; i < k; ++i) {
    const auto chain = out.chain_of(Word{1} << i);
    if (chain.size() > 1) out.main_effect_chains.push_back(chain);
  }
  std::set<Word> seen;
  for (int i = 0; i < k; ++i) {
    for (int j = i + 1; j < k; ++j) {
      const Word pair = (Word{1} << i) | (Word{1} << j);
      if (seen.count(pair)) continue;
      const auto chain = out.chain_of(pair);
      if (chain.size() == 1) {
        out.clear_two_factor.push_back(pair);
        continue;
      }
      bool has_main = false;
      for (const auto& m : chain) {
        seen.insert(m.word);
        has_main = has_main || word_length(m.word) == 1;
      }
      // A chain holding a main effect is reported with the main effects (FrF2's $main).
      if (!has_main) out.two_factor_chains.push_back(chain);
    }
  }
  return out;
}

std::string resolution_name(const std::optional<int>& resolution) {
  if (!resolution) return "full factorial";
  static const char* kRoman[] = {"0",  "I", "II", "III", "IV",   "V",   "VI", "VII", "VIII",
                                 "IX", "X", "XI", "XII", "XIII", "XIV", "XV", "XVI"};
  if (*resolution >= 0 && *resolution <= 16) return kRoman[*resolution];
  return std::to_string(*resolution);
}

}  // namespace demcal::doe
