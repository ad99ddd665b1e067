#include "core/doe/nested_fraction.hpp"

#include <algorithm>
#include <optional>

#include "core/doe/alias_structure.hpp"

namespace demcal::doe {
namespace {

/// Rows of the first replicate's factorial runs.
std::vector<int> factorial_rows(const Design& d) {
  std::vector<int> rows;
  for (int r = 0; r < d.runs(); ++r)
    if (d.point_type[std::size_t(r)] == PointType::kFactorial && d.replicate[std::size_t(r)] == 1)
      rows.push_back(r);
  return rows;
}

/// Longest word tried: every word of a design of up to 64 base runs.
constexpr int kMaxWordLength = 6;

/// Words of 1 to kMaxWordLength letters over the first `base` factors.
std::vector<Word> candidate_words(int base) {
  std::vector<Word> words;
  for (Word w = 1; w < (Word{1} << base); ++w)
    if (word_length(w) <= kMaxWordLength) words.push_back(w);
  return words;
}

int column_sign(const Design& d, int row, Word w) {
  int s = 1;
  for (int f = 0; f < d.factors(); ++f)
    if (w & (Word{1} << f)) s *= d.coded(row, f) > 0 ? 1 : -1;
  return s;
}

/// How good a fraction is: higher resolution first (a full factorial best), then fewer
/// defining words of that length.
struct Quality {
  int resolution = 0;
  int shortest_words = 0;
  bool better_than(const Quality& o) const {
    return resolution != o.resolution ? resolution > o.resolution
                                      : shortest_words < o.shortest_words;
  }
};

Quality quality(const Design& d, const std::vector<int>& rows) {
  Eigen::MatrixXd coded(Eigen::Index(rows.size()), d.factors());
  for (std::size_t i = 0; i < rows.size(); ++i) coded.row(Eigen::Index(i)) = d.coded.row(rows[i]);
  const AliasStructure a = analyse_aliasing(coded);
  if (!a.regular) return {};
  if (!a.resolution) return {1 << 20, 0};
  const std::size_t at = std::size_t(*a.resolution - 3);
  return {*a.resolution, at < a.word_length_pattern.size() ? a.word_length_pattern[at] : 0};
}

/// The best half of `rows` by one word; empty when no word splits them.
std::optional<std::vector<int>> best_half(const Design& d, const std::vector<int>& rows,
                                          const std::vector<Word>& words) {
  std::optional<std::vector<int>> best;
  Quality best_quality;
  for (const Word w : words) {
    std::vector<int> half;
    for (const int r : rows)
      if (column_sign(d, r, w) > 0) half.push_back(r);
    if (half.empty() || half.size() == rows.size()) continue;
    const Quality q = quality(d, half);
    if (!best || q.better_than(best_quality)) {
      best = std::move(half);
      best_quality = q;
    }
  }
  if (best && best_quality.resolution < 3) return std::nullopt;
  return best;
}

}  // namespace

std::vector<int> nested_fraction(const Design& design, int min_runs) {
  std::vector<int> rows = factorial_rows(design);
  const int base = design.factors() - static_cast<int>(design.generators.size());
  const auto words = candidate_words(base);
  while (static_cast<int>(rows.size()) / 2 >= min_runs) {
    auto half = best_half(design, rows, words);
    if (!half) break;
    rows = std::move(*half);
  }
  return rows;
}

namespace {

/// log det of X'X for the main-effect model on `rows` (a tiny ridge keeps a singular start
/// comparable: every exchange that makes it regular is an improvement).
double main_effect_log_det(const Design& d, const std::vector<int>& rows) {
  Eigen::MatrixXd x(Eigen::Index(rows.size()), d.factors() + 1);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    x(Eigen::Index(i), 0) = 1.0;
    x.row(Eigen::Index(i)).tail(d.factors()) = d.coded.row(rows[i]);
  }
  const Eigen::MatrixXd info =
      x.transpose() * x + 1e-9 * Eigen::MatrixXd::Identity(x.cols(), x.cols());
  return 2.0 * info.llt().matrixLLT().diagonal().array().log().sum();
}

}  // namespace

std::vector<int> main_effect_half(const Design& design) {
  const std::vector<int> all = factorial_rows(design);
  const std::size_t size = std::max<std::size_t>((all.size() + 1) / 2, design.factors() + 1);
  if (size >= all.size()) return all;
  const std::vector<int> regular = nested_fraction(design, static_cast<int>(size));
  if (regular.size() == size) return regular;
  std::vector<int> in(all.begin(), all.begin() + std::ptrdiff_t(size));
  std::vector<int> out(all.begin() + std::ptrdiff_t(size), all.end());
  double best = main_effect_log_det(design, in);
  // Each pass makes the best single exchange; a strict gain ends the search in finitely many.
  for (bool improved = true; improved;) {
    improved = false;
    std::size_t bi = 0, bo = 0;
    for (std::size_t i = 0; i < in.size(); ++i)
      for (std::size_t o = 0; o < out.size(); ++o) {
        std::swap(in[i], out[o]);
        const double v = main_effect_log_det(design, in);
        std::swap(in[i], out[o]);
        if (v > best + 1e-9) {
          best = v;
          bi = i;
          bo = o;
          improved = true;
        }
      }
    if (improved) std::swap(in[bi], out[bo]);
  }
  std::sort(in.begin(), in.end());
  return in;
}

}  // namespace demcal::doe
