#include "core/doe/minimum_aberration.hpp"

#include <algorithm>
#include <map>
#include <utility>

#include "core/common/error.hpp"
#include "core/doe/alias_structure.hpp"

namespace demcal::doe {

namespace {

// FrF2 catalogue catlg entries, copied from the FrF2 oracle,
// tests/data/doe-oracle/catlg_ranking.txt (FrF2 2.3.4): {runs, factors} -> {entry, generating
// columns}.
const std::map<std::pair<int, int>, std::pair<const char*, const char*>>& catalogue() {
  static const std::map<std::pair<int, int>, std::pair<const char*, const char*>> entries{
      {{32, 12}, {"12-7.1", "ABC ABD ACD BCD ABE ACE ADE"}},
      {{32, 8}, {"8-3.1", "ABC ABD ACDE"}},
  };
  return entries;
}

int log2_runs(int runs) {
  if (runs < 4 || runs > (1 << 20) || (runs & (runs - 1)) != 0) {
    throw InputError("runs",
                     "a two-level fraction needs a power of two runs, got " + std::to_string(runs));
  }
  return std::countr_zero(static_cast<unsigned>(runs));
}

void check_size(int k, int runs) {
  const int m = log2_runs(runs);
  if (k < 2 || k > kMaxFactors) {
    throw InputError("factors", "number of factors must be 2.." + std::to_string(kMaxFactors) +
                                    ", got " + std::to_string(k));
  }
  if (k < m) {
    throw InputError("runs", std::to_string(runs) + " runs exceed the " + std::to_string(1 << k) +
                                 " of a full 2^" + std::to_string(k) +
                                 " factorial; use replicates instead");
  }
  if (k > runs - 1) {
    throw InputError("factors", std::to_string(k) + " factors cannot be estimated in " +
                                    std::to_string(runs) + " runs (at most " +
                                    std::to_string(runs - 1) + ")");
  }
}

/// Branch and bound over sets of generator columns. The words of a partial choice are a
/// subset of the final words, so its pattern bounds the final one from below in every
/// component; once it compares worse than the best complete design (or equal with words
/// still to add, which can only make it worse) the branch is cut.
class Search {
 public:
  Search(int k, int m, std::uint64_t budget) : k_(k), m_(m), p_(k - m), budget_(budget) {
    for (Word w = 1; w < (Word{1} << m); ++w) {
      if (word_length(w) >= 2) candidates_.push_back(w);
    }
    // Long generators first: they give long words and so a good first bound.
    std::stable_sort(candidates_.begin(), candidates_.end(),
                     [](Word a, Word b) { return word_length(a) > word_length(b); });
    counts_.assign(static_cast<std::size_t>(k + 1), 0);
    group_.push_back(0);
  }

  GeneratorChoice run() {
    seed_with_greedy();
    // Permuting base factors maps any design onto one whose first (longest) generator is the
    // first candidate of its length, so only those open the search.
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      if (c > 0 && word_length(candidates_[c]) == word_length(candidates_[c - 1])) continue;
      descend(c, 0);
    }
    GeneratorChoice out;
    out.generators = best_;
    out.word_length_pattern = pattern(best_counts_);
    out.clear_two_factor = best_clear_;
    out.source = "search";
    out.proven = !exhausted_;
    out.nodes = nodes_;
    return out;
  }

 private:
  /// A first bound from a greedy choice (each added generator the one that keeps the
  /// pattern smallest): without it a truncated search of a large case can end in the
  /// first subtree it happens to open.
  void seed_with_greedy() {
    std::vector<bool> used(candidates_.size(), false);
    for (int depth = 0; depth < p_; ++depth) {
      std::size_t pick = candidates_.size();
      std::vector<int> pick_counts;
      for (std::size_t c = 0; c < candidates_.size(); ++c) {
        if (used[c]) continue;
        push(c, depth);
        if (pick == candidates_.size() ||
            compare_word_length_patterns(pattern(counts_), pattern(pick_counts)) < 0) {
          pick = c;
          pick_counts = counts_;
        }
        pop();
      }
      used[pick] = true;
      push(pick, depth);
    }
    best_ = chosen_;
    best_counts_ = counts_;
    best_clear_ = clear_count();
    for (int depth = 0; depth < p_; ++depth) pop();
  }

  void push(std::size_t c, int depth) {
    const Word gen = candidates_[c] | (Word{1} << (m_ + depth));
    const std::size_t n = group_.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Word w = group_[i] ^ gen;
      group_.push_back(w);
      ++counts_[std::size_t(word_length(w))];
    }
    chosen_.push_back(candidates_[c]);
  }

  void pop() {
    const std::size_t n = group_.size() / 2;
    for (std::size_t i = n; i < group_.size(); ++i) --counts_[std::size_t(word_length(group_[i]))];
    group_.resize(n);
    chosen_.pop_back();
  }

  std::vector<int> pattern(const std::vector<int>& counts) const {
    return {counts.begin() + 3, counts.end()};
  }

  int clear_count() const {
    Eigen::MatrixXd coded = Eigen::MatrixXd::Zero(1 << m_, k_);
    for (int r = 0; r < (1 << m_); ++r) {
      for (int i = 0; i < m_; ++i) coded(r, i) = (r >> i) & 1 ? 1.0 : -1.0;
      for (int j = 0; j < p_; ++j) {
        double v = 1.0;
        for (int i = 0; i < m_; ++i) {
          if (chosen_[std::size_t(j)] & (Word{1} << i)) v *= coded(r, i);
        }
        coded(r, m_ + j) = v;
      }
    }
    return static_cast<int>(analyse_aliasing(coded).clear_two_factor.size());
  }

  void descend(std::size_t c, int depth) {
    if (++nodes_ > budget_) {
      exhausted_ = true;
      return;
    }
    push(c, depth);
    const bool leaf = depth + 1 == p_;
    const int cmp =
        best_.empty() ? -1 : compare_word_length_patterns(pattern(counts_), pattern(best_counts_));
    if (leaf) {
      if (cmp < 0) {
        best_ = chosen_;
        best_counts_ = counts_;
        best_clear_ = clear_count();
      } else if (cmp == 0) {
        if (const int clear = clear_count(); clear > best_clear_) {
          best_ = chosen_;
          best_clear_ = clear;
        }
      }
    } else if (cmp < 0) {
      for (std::size_t next = c + 1; next + (p_ - depth - 2) < candidates_.size(); ++next) {
        descend(next, depth + 1);
        if (exhausted_) break;
      }
    }
    pop();
  }

  int k_, m_, p_;
  std::uint64_t budget_;
  std::uint64_t nodes_ = 0;
  bool exhausted_ = false;
  std::vector<Word> candidates_;
  std::vector<Word> group_;
  std::vector<int> counts_;
  std::vector<Word> chosen_;
  std::vector<Word> best_;
  std::vector<int> best_counts_;
  int best_clear_ = -1;
};

}  // namespace

int compare_word_length_patterns(const std::vector<int>& a, const std::vector<int>& b) {
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const int x = i < a.size() ? a[i] : 0;
    const int y = i < b.size() ? b[i] : 0;
    if (x != y) return x < y ? -1 : 1;
  }
  return 0;
}

GeneratorChoice search_minimum_aberration(int factor_count, int runs, std::uint64_t node_budget) {
  check_size(factor_count, runs);
  const int m = log2_runs(runs);
  if (factor_count == m) {
    GeneratorChoice full;
    full.word_length_pattern.assign(std::size_t(std::max(0, factor_count - 2)), 0);
    full.clear_two_factor = factor_count * (factor_count - 1) / 2;
    full.source = "full factorial";
    return full;
  }
  return Search(factor_count, m, node_budget).run();
}

GeneratorChoice minimum_aberration_generators(int factor_count, int runs,
                                              std::uint64_t node_budget) {
  check_size(factor_count, runs);
  const auto it = catalogue().find({runs, factor_count});
  if (it == catalogue().end()) return search_minimum_aberration(factor_count, runs, node_budget);
  const Design d = fractional_factorial(factor_count, it->second.second);
  const AliasStructure a = analyse_aliasing(d.coded);
  GeneratorChoice out;
  out.generators = d.generators;
  out.word_length_pattern = a.word_length_pattern;
  out.clear_two_factor = static_cast<int>(a.clear_two_factor.size());
  out.source = std::string("catalogue FrF2 catlg ") + it->second.first;
  return out;
}

Design minimum_aberration_design(int factor_count, int runs) {
  const GeneratorChoice choice = minimum_aberration_generators(factor_count, runs);
  if (choice.generators.empty()) return full_factorial(factor_count);
  std::string text;
  for (const Word g : choice.generators) text += word_name(g) + " ";
  Design d = fractional_factorial(factor_count, text);
  const int p = static_cast<int>(choice.generators.size());
  d.description = "2^(" + std::to_string(factor_count) + "-" + std::to_string(p) +
                  ") minimum aberration (" + choice.source +
                  (choice.proven ? "" : "; search budget reached, best found, not proven") +
                  "), generators " + generators_text(d);
  return d;
}

}  // namespace demcal::doe
