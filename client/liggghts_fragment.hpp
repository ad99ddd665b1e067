#pragma once
// The calibrated material as a LIGGGHTS 3.8 input fragment (`demcal export ID --format
// liggghts`, docs/report.md): two atom types (1 = particles with the particle law, 2 = the
// walls' material with the wall law), `fix property/global` for every parameter of the
// models, the `pair_style gran` line and the same model for `fix wall/gran` in a variable.
// Every line carries a comment naming the demcal parameter and its unit. What LIGGGHTS 3.8
// cannot express (van der Waals beyond contact, damping on approach only, ...) is said in a
// comment and returned as a warning.
#include <map>
#include <string>
#include <vector>

#include "demcal/v1/campaign.pb.h"

namespace demcal::cli {

struct LiggghtsFragment {
  std::string text;
  std::vector<std::string> warnings;  ///< one line each: what is not exported exactly
};

/// `material` with `parameters` (path -> natural value: the spec's fixed values, then the
/// calibrated set) applied. `title` heads the fragment's comment. Throws InputError for a
/// parameter path that names no model parameter.
LiggghtsFragment liggghts_fragment(v1::Material material,
                                   const std::map<std::string, double>& parameters,
                                   const std::string& title);

}  // namespace demcal::cli
