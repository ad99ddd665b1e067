#include "rpc/effects_convert.hpp"

#include <algorithm>
#include <cmath>

namespace demcal::rpc {

v1::MetricEffects effects_message(const std::string& response, const doe::ResponseAnalysis& a) {
  v1::MetricEffects m;
  m.set_metric(response);
  m.set_runs_used(a.balance.runs_used);
  m.set_runs_total(a.balance.runs_total);
  std::vector<const doe::EffectEstimate*> by_size;
  for (const auto& e : a.effects) by_size.push_back(&e);
  std::stable_sort(by_size.begin(), by_size.end(),
                   [](auto x, auto y) { return std::abs(x->effect) > std::abs(y->effect); });
  for (const auto* e : by_size) {
    auto* o = m.add_effects();
    o->set_chain(e->term.name());
    o->set_effect(e->effect);
    o->set_active_me(e->active);
    o->set_active_sme(e->active_simultaneous);
    o->set_in_model(e->in_model);
  }
  if (a.lenth) {
    m.set_pse(a.lenth->pse);
    m.set_me(a.lenth->me);
    m.set_sme(a.lenth->sme);
    m.set_lenth_df(a.lenth->degrees_of_freedom);
    m.set_lenth_terms(a.lenth->contrasts);
  }
  m.set_noise_sd(a.noise.sd);
  m.set_noise_df(a.noise.degrees_of_freedom);
  m.set_noise_source(a.noise.source);
  m.set_intercept(a.fit.intercept);
  for (std::size_t i = 0; i < a.fit.terms.size(); ++i) {
    auto* c = m.add_coefficients();
    c->set_chain(a.fit.terms[i].name());
    c->set_coefficient(a.fit.coefficients(Eigen::Index(i)));
    c->set_standard_error(a.fit.standard_errors.size() ? a.fit.standard_errors(Eigen::Index(i))
                                                       : std::nan(""));
  }
  m.set_r_squared(a.fit.r_squared);
  m.set_curvature_available(a.curvature.available);
  m.set_curvature_p(a.curvature.p_value);
  m.set_curvature_significant(a.curvature.significant);
  m.set_curvature_difference(a.curvature.difference);
  m.set_curvature_t(a.curvature.t);
  m.set_curvature_df(a.curvature.degrees_of_freedom);
  m.set_curvature_error(a.curvature.error_source);
  for (const auto& n : a.notes) m.add_notes(n);
  return m;
}

}  // namespace demcal::rpc
