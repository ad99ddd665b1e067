#pragma once
// The contact-law section of a spec, the same in `demcal contact`, `demcal simulate` and campaigns:
//   normal:     {model: luding, k1: 1.0e4, k2_ratio: 5, kc_ratio: 0.5, phi_f: 0.05, restitution:
//   0.5} cohesion:   {model: van_der_waals, hamaker: 1.0e-19, d_max: 1.0e-6}     (default: none)
//   tangential: {model: history, mu_s: 0.5, kt_ratio: 0.2857}
//   rolling:    {model: cdt, mu_r: 0.1}                                       (default: none)
#include "core/contact/contact_law.hpp"
#include "core/io/yaml_node.hpp"

namespace demcal::io {

contact::ContactLawSpec read_contact_law_spec(const YamlNode& node);
contact::ContactLaw read_contact_law(const YamlNode& node);

}  // namespace demcal::io
