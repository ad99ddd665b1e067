#pragma once
// A design in coded units: one row per run in standard order, with the randomised run order
// kept alongside so that the analysis can always go back to the standard (Yates) order.
#include <Eigen/Dense>
#include <cstdint>
#include <string>
#include <vector>

#include "core/doe/word.hpp"

namespace demcal::doe {

enum class PointType { kFactorial, kCentre, kAxial, kSpaceFilling };
const char* to_string(PointType type);

struct Design {
  /// What the design is, e.g. "2^(12-7) minimum aberration (catalogue 12-7.1)".
  std::string description;
  std::vector<std::string> factor_names;
  /// Coded levels, rows in standard order: +-1 factorial, 0 centre, +-alpha axial.
  Eigen::MatrixXd coded;
  std::vector<PointType> point_type;
  /// Replicate number (1-based) of each row.
  std::vector<int> replicate;
  /// Block of each row (1-based): 2 marks the mirror half of a fold-over.
  std::vector<int> block;
  /// run_order[r] = the position (1-based) at which row r is run.
  std::vector<int> run_order;
  /// For a 2^(k-p): the base word of each added factor, e.g. F=ABC; empty otherwise.
  std::vector<Word> generators;

  int runs() const { return static_cast<int>(coded.rows()); }
  int factors() const { return static_cast<int>(coded.cols()); }
  /// Rows in the order they are to be run.
  std::vector<int> rows_in_run_order() const;
};

/// "F=ABC G=ABD": one generator per added factor, letters of the base factors only.
std::string generators_text(const Design& design);

/// Full 2^k factorial in standard order (A changes fastest, low level first).
Design full_factorial(int factor_count);

/// 2^(k-p) from generators, one word over the first k-p (base) factors per added factor,
/// given as "F=ABC G=ABD H=ACDE" or "ABC ABD ACDE"; a leading '-' flips the sign.
Design fractional_factorial(int factor_count, const std::string& generators);

/// Parses generators for a design with `factor_count` factors into signed base words.
std::vector<SignedWord> parse_generators(int factor_count, const std::string& text);

/// Appends `count` centre points (coded 0) to the design.
void add_centre_points(Design& design, int count);

/// Repeats every run `count` times in total (replicate numbers 1..count).
void replicate_runs(Design& design, int count);

/// Seeded random run order (Fisher-Yates with demcal::Rng); the rows stay in standard order.
void randomise_run_order(Design& design, std::uint64_t seed);

/// Fold-over: the factorial runs again with the signs of the factors in `fold` reversed,
/// as block 2 (Montgomery 2017, sec. 8.6). fold = all factors is the full fold-over.
Design fold_over(const Design& design, Word fold);

/// Factors to fold on so that the members of an alias chain fall into two groups of sizes as
/// equal as possible: after folding on S, members P and Q stay aliased only when
/// P xor Q has an even number of letters in S. Repeating the choice on the group that holds
/// the effect names the interaction in about log2(chain size) fold-overs. Throws InputError
/// when no fold on one or two factors splits the chain.
Word choose_fold_to_split(const std::vector<SignedWord>& chain, int factor_count);

enum class CompositeKind { kFaceCentred, kRotatable };
/// Central composite design on a full 2^k factorial: 2k axial points at alpha = 1
/// (face-centred) or alpha = (2^k)^(1/4) (rotatable, Box and Hunter 1957), plus centres.
Design central_composite(int factor_count, CompositeKind kind, int centre_points);

/// Maximin Latin hypercube of `runs` points in [-1, 1]^k: cell midpoints, the best of several
/// seeded random hypercubes improved by pairwise swaps within columns (Morris and Mitchell 1995).
Design latin_hypercube(int factor_count, int runs, std::uint64_t seed);

/// Smallest distance between two rows of the coded matrix (the maximin criterion).
double min_pairwise_distance(const Eigen::MatrixXd& points);

}  // namespace demcal::doe
