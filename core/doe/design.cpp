#include "core/doe/design.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <sstream>

#include "core/common/error.hpp"
#include "core/common/rng.hpp"

namespace demcal::doe {

const char* to_string(PointType type) {
  switch (type) {
    case PointType::kFactorial:
      return "factorial";
    case PointType::kCentre:
      return "centre";
    case PointType::kAxial:
      return "axial";
    case PointType::kSpaceFilling:
      return "space_filling";
  }
  return "unknown";
}

namespace {

std::vector<std::string> letter_names(int k) {
  std::vector<std::string> names;
  for (int i = 0; i < k; ++i) names.emplace_back(1, factor_letter(i));
  return names;
}

Design empty_design(int k, int rows, PointType type) {
  Design d;
  d.factor_names = letter_names(k);
  d.coded = Eigen::MatrixXd::Zero(rows, k);
  d.point_type.assign(static_cast<std::size_t>(rows), type);
  d.replicate.assign(static_cast<std::size_t>(rows), 1);
  d.block.assign(static_cast<std::size_t>(rows), 1);
  d.run_order.resize(static_cast<std::size_t>(rows));
  std::iota(d.run_order.begin(), d.run_order.end(), 1);
  return d;
}

void append_rows(Design& d, const Eigen::MatrixXd& rows, PointType type, int replicate, int block) {
  const Eigen::Index old = d.coded.rows();
  d.coded.conservativeResize(old + rows.rows(), Eigen::NoChange);
  d.coded.bottomRows(rows.rows()) = rows;
  for (Eigen::Index r = 0; r < rows.rows(); ++r) {
    d.point_type.push_back(type);
    d.replicate.push_back(replicate);
    d.block.push_back(block);
    d.run_order.push_back(static_cast<int>(old + r + 1));
  }
}

void check_factor_count(int k, const std::string& where) {
  if (k < 1 || k > kMaxFactors) {
    throw InputError(where, "number of factors must be 1.." + std::to_string(kMaxFactors) +
                                ", got " + std::to_string(k));
  }
}

}  // namespace

std::vector<int> Design::rows_in_run_order() const {
  std::vector<int> rows(run_order.size());
  for (std::size_t r = 0; r < run_order.size(); ++r) {
    rows[static_cast<std::size_t>(run_order[r] - 1)] = static_cast<int>(r);
  }
  return rows;
}

std::string generators_text(const Design& design) {
  const int base = design.factors() - static_cast<int>(design.generators.size());
  std::string text;
  for (std::size_t j = 0; j < design.generators.size(); ++j) {
    if (j > 0) text += ' ';
    text += factor_letter(base + static_cast<int>(j));
    text += '=';
    text += word_name(design.generators[j]);
  }
  return text;
}

Design full_factorial(int factor_count) {
  check_factor_count(factor_count, "factors");
  if (factor_count > 20) throw InputError("factors", "a full factorial of more than 20 factors");
  const int n = 1 << factor_count;
  Design d = empty_design(factor_count, n, PointType::kFactorial);
  // Yates standard order: factor i alternates every 2^i runs, low level first.
  for (int r = 0; r < n; ++r) {
    for (int i = 0; i < factor_count; ++i) d.coded(r, i) = (r >> i) & 1 ? 1.0 : -1.0;
  }
  d.description = "full factorial 2^" + std::to_string(factor_count);
  return d;
}

std::vector<SignedWord> parse_generators(int factor_count, const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  const int base = factor_count - static_cast<int>(tokens.size());
  if (base < 1) {
    throw InputError("generators", std::to_string(tokens.size()) + " generators for " +
                                       std::to_string(factor_count) + " factors");
  }
  std::vector<SignedWord> out;
  for (std::size_t j = 0; j < tokens.size(); ++j) {
    std::string t = tokens[j];
    const char expected = factor_letter(base + static_cast<int>(j));
    if (const auto eq = t.find('='); eq != std::string::npos) {
      const std::string lhs = t.substr(0, eq);
      if (lhs.size() != 1 || factor_index(lhs[0]) != base + static_cast<int>(j)) {
        throw InputError("generators", "'" + t + "': generator " + std::to_string(j + 1) +
                                           " must define factor " + expected);
      }
      t = t.substr(eq + 1);
    }
    int sign = 1;
    if (!t.empty() && (t[0] == '-' || t[0] == '+')) {
      sign = t[0] == '-' ? -1 : 1;
      t = t.substr(1);
    }
    const Word w = parse_word(t, "generators");
    if (w >> base) {
      throw InputError("generators", "'" + tokens[j] + "' uses a factor beyond the " +
                                         std::to_string(base) + " base factors " +
                                         word_name((Word{1} << base) - 1));
    }
    if (word_length(w) < 2) {
      throw InputError("generators", "'" + tokens[j] + "' aliases factor " + expected +
                                         " with a main effect; a generator needs 2+ letters");
    }
    out.push_back({w, sign});
  }
  return out;
}

Design fractional_factorial(int factor_count, const std::string& generators) {
  check_factor_count(factor_count, "factors");
  const auto gens = parse_generators(factor_count, generators);
  const int base = factor_count - static_cast<int>(gens.size());
  for (std::size_t a = 0; a < gens.size(); ++a) {
    for (std::size_t b = a + 1; b < gens.size(); ++b) {
      if (gens[a].word == gens[b].word) {
        throw InputError("generators", "factors " + std::string(1, factor_letter(base + int(a))) +
                                           " and " + std::string(1, factor_letter(base + int(b))) +
                                           " have the same generator " + word_name(gens[a].word));
      }
    }
  }
  const Design bf = full_factorial(base);
  Design d = empty_design(factor_count, bf.runs(), PointType::kFactorial);
  d.coded.leftCols(base) = bf.coded;
  for (std::size_t j = 0; j < gens.size(); ++j) {
    d.generators.push_back(gens[j].word);
    for (int r = 0; r < d.runs(); ++r) {
      double v = gens[j].sign;
      for (int i = 0; i < base; ++i) {
        if (gens[j].word & (Word{1} << i)) v *= bf.coded(r, i);
      }
      d.coded(r, base + static_cast<Eigen::Index>(j)) = v;
    }
  }
  d.description = "2^(" + std::to_string(factor_count) + "-" + std::to_string(gens.size()) +
                  ") fractional factorial, generators " + generators_text(d);
  return d;
}

void add_centre_points(Design& design, int count) {
  if (count < 0) throw InputError("center", "number of centre points must be >= 0");
  append_rows(design, Eigen::MatrixXd::Zero(count, design.factors()), PointType::kCentre, 1, 1);
}

void replicate_runs(Design& design, int count) {
  if (count < 1) throw InputError("replicates", "number of replicates must be >= 1");
  const Design one = design;
  for (int rep = 2; rep <= count; ++rep) {
    const Eigen::Index old = design.coded.rows();
    append_rows(design, one.coded, PointType::kFactorial, rep, 1);
    for (int r = 0; r < one.runs(); ++r) {
      design.point_type[static_cast<std::size_t>(old + r)] = one.point_type[std::size_t(r)];
      design.block[static_cast<std::size_t>(old + r)] = one.block[std::size_t(r)];
    }
  }
}

void randomise_run_order(Design& design, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<int> order(static_cast<std::size_t>(design.runs()));
  std::iota(order.begin(), order.end(), 1);
  for (std::size_t i = order.size(); i > 1; --i) {
    std::swap(order[i - 1], order[rng.below(i)]);
  }
  design.run_order = order;
}

Design fold_over(const Design& design, Word fold) {
  const Word all = (Word{1} << design.factors()) - 1;
  if (fold == 0 || (fold & ~all)) {
    throw InputError("fold", "fold-over factors '" + word_name(fold) +
                                 "' must be a non-empty subset of " + word_name(all));
  }
  Design d = design;
  std::vector<Eigen::Index> factorial;
  for (Eigen::Index r = 0; r < design.coded.rows(); ++r) {
    if (design.point_type[std::size_t(r)] == PointType::kFactorial) factorial.push_back(r);
  }
  Eigen::MatrixXd mirror(static_cast<Eigen::Index>(factorial.size()), design.factors());
  for (std::size_t r = 0; r < factorial.size(); ++r) {
    mirror.row(Eigen::Index(r)) = design.coded.row(factorial[r]);
    for (int i = 0; i < design.factors(); ++i) {
      if (fold & (Word{1} << i)) mirror(Eigen::Index(r), i) = -mirror(Eigen::Index(r), i);
    }
  }
  append_rows(d, mirror, PointType::kFactorial, 1, 2);
  d.generators.clear();
  d.description = design.description + ", folded over on " +
                  (fold == all ? std::string("all factors") : word_name(fold));
  return d;
}

Word choose_fold_to_split(const std::vector<SignedWord>& chain, int factor_count) {
  Word best = 0;
  std::size_t best_score = chain.size();
  const auto consider = [&](Word s) {
    std::size_t odd = 0;
    for (const auto& m : chain) odd += std::popcount(m.word & s) % 2;
    if (odd == 0 || odd == chain.size()) return;
    const std::size_t score =
        odd > chain.size() - odd ? 2 * odd - chain.size() : chain.size() - 2 * odd;
    if (score < best_score) {
      best_score = score;
      best = s;
    }
  };
  for (int i = 0; i < factor_count; ++i) consider(Word{1} << i);
  for (int i = 0; i < factor_count; ++i) {
    for (int j = i + 1; j < factor_count; ++j) consider((Word{1} << i) | (Word{1} << j));
  }
  if (best == 0) {
    throw InputError("chain", "no fold on one or two factors splits " + chain_name(chain));
  }
  return best;
}

Design central_composite(int factor_count, CompositeKind kind, int centre_points) {
  check_factor_count(factor_count, "factors");
  if (factor_count > 10) throw InputError("factors", "a central composite of more than 10 factors");
  Design d = full_factorial(factor_count);
  const double alpha =
      kind == CompositeKind::kFaceCentred ? 1.0 : std::pow(static_cast<double>(d.runs()), 0.25);
  Eigen::MatrixXd axial = Eigen::MatrixXd::Zero(2 * factor_count, factor_count);
  for (int i = 0; i < factor_count; ++i) {
    axial(2 * i, i) = -alpha;
    axial(2 * i + 1, i) = alpha;
  }
  append_rows(d, axial, PointType::kAxial, 1, 1);
  add_centre_points(d, centre_points);
  d.description = std::string(kind == CompositeKind::kFaceCentred ? "face-centred" : "rotatable") +
                  " central composite, alpha = " + std::to_string(alpha);
  return d;
}

double min_pairwise_distance(const Eigen::MatrixXd& points) {
  double best = std::numeric_limits<double>::infinity();
  for (Eigen::Index a = 0; a < points.rows(); ++a) {
    for (Eigen::Index b = a + 1; b < points.rows(); ++b) {
      best = std::min(best, (points.row(a) - points.row(b)).norm());
    }
  }
  return best;
}

Design latin_hypercube(int factor_count, int runs, std::uint64_t seed) {
  check_factor_count(factor_count, "factors");
  if (runs < 2) throw InputError("runs", "a Latin hypercube needs at least 2 runs");
  Rng rng(seed);
  const auto level = [runs](int cell) { return -1.0 + (2.0 * cell + 1.0) / runs; };
  const auto random_cube = [&] {
    Eigen::MatrixXd x(runs, factor_count);
    for (int c = 0; c < factor_count; ++c) {
      std::vector<int> perm(static_cast<std::size_t>(runs));
      std::iota(perm.begin(), perm.end(), 0);
      for (std::size_t i = perm.size(); i > 1; --i) std::swap(perm[i - 1], perm[rng.below(i)]);
      for (int r = 0; r < runs; ++r) x(r, c) = level(perm[std::size_t(r)]);
    }
    return x;
  };
  Eigen::MatrixXd best = random_cube();
  double best_d = min_pairwise_distance(best);
  for (int t = 1; t < 20; ++t) {
    Eigen::MatrixXd x = random_cube();
    if (const double dist = min_pairwise_distance(x); dist > best_d) {
      best = x;
      best_d = dist;
    }
  }
  // Swapping two entries of a column keeps the Latin property; keep a swap when it raises
  // the smallest distance.
  for (int it = 0; it < std::min(200 * runs, 4000); ++it) {
    const auto c = static_cast<Eigen::Index>(rng.below(std::uint64_t(factor_count)));
    const auto a = static_cast<Eigen::Index>(rng.below(std::uint64_t(runs)));
    const auto b = static_cast<Eigen::Index>(rng.below(std::uint64_t(runs)));
    if (a == b) continue;
    std::swap(best(a, c), best(b, c));
    if (const double dist = min_pairwise_distance(best); dist > best_d) {
      best_d = dist;
    } else {
      std::swap(best(a, c), best(b, c));
    }
  }
  Design d = empty_design(factor_count, runs, PointType::kSpaceFilling);
  d.coded = best;
  d.description =
      "maximin Latin hypercube, " + std::to_string(runs) + " runs, seed " + std::to_string(seed);
  return d;
}

}  // namespace demcal::doe
