#pragma once
// A fraction nested in a two-level design: the runs of a multi-fidelity campaign that run at the
// high level as well, so that every high run has its low twin at the same point (nested designs
// for two levels of accuracy: Qian, Tang and Wu 2009, Statistica Sinica 19:287). The design's
// factorial runs are halved one defining word at a time; each word is the one that leaves the
// highest resolution (then the fewest defining words of that length), among the words of up to
// six of the design's base factors (the first k - p). Halving stops before fewer than
// `min_runs` runs or a resolution below III would remain.
#include <vector>

#include "core/doe/design.hpp"

namespace demcal::doe {

/// Rows (0-based, standard order) of the first replicate's factorial runs that form the nested
/// fraction; all of them when no halving keeps `min_runs` runs at resolution III or more.
std::vector<int> nested_fraction(const Design& design, int min_runs);

/// Half the first replicate's factorial runs (rounded up, at least k + 1) for a main-effect
/// model: the regular half of resolution III or more where one exists (nested_fraction), else
/// the half whose main-effect information matrix X'X (intercept and k main effects) has the
/// largest determinant found by exchanging one run at a time from the first half (Fedorov's
/// exchange, Atkinson, Donev and Tobias 2007, Optimum Experimental Designs, ch. 12). A 2^(5-1)
/// of resolution V has no regular half of resolution III (any word added to ABCDE leaves a word
/// of two letters or fewer), but has non-regular halves that estimate every main effect.
std::vector<int> main_effect_half(const Design& design);

}  // namespace demcal::doe
