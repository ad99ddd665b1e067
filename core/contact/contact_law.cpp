#include "core/contact/contact_law.hpp"

#include <algorithm>

namespace demcal::contact {
namespace {

template <class Variant, std::size_t I = 0>
Variant make_model(const SlotSpec& spec, const std::string& where) {
  if constexpr (I == std::variant_size_v<Variant>) {
    std::string known;
    [&]<std::size_t... Is>(std::index_sequence<Is...>) {
      ((known += (Is ? ", " : "") + std::string(std::variant_alternative_t<Is, Variant>::kName)),
       ...);
    }
    (std::make_index_sequence<std::variant_size_v<Variant>>{});
    throw InputError(where + ".model", "unknown model '" + spec.model + "' (known: " + known + ")");
  } else {
    using M = std::variant_alternative_t<I, Variant>;
    if (spec.model == M::kName) return params_from_map<M>(spec.params, where);
    return make_model<Variant, I + 1>(spec, where);
  }
}

template <class Variant>
std::vector<std::string> names_of() {
  std::vector<std::string> out;
  [&]<std::size_t... Is>(std::index_sequence<Is...>) {
    (out.emplace_back(std::variant_alternative_t<Is, Variant>::kName), ...);
  }
  (std::make_index_sequence<std::variant_size_v<Variant>>{});
  return out;
}

/// Appends model M's parameter table to `out` if `model` names it. (A function of its own, not a
/// lambda inside the fold below: clang 14's front end crashes on that nesting.)
template <class M>
void append_params_if_named(const std::string& model, std::vector<ParamDoc>& out, bool& found) {
  if (model != M::kName) return;
  found = true;
  for (const auto& p : M::table())
    out.push_back(
        {std::string(p.name), std::string(p.unit), std::string(p.doc), p.lo, p.hi, p.fallback});
}

template <class Variant>
std::vector<ParamDoc> params_of(const std::string& model) {
  std::vector<ParamDoc> out;
  bool found = false;
  [&]<std::size_t... Is>(std::index_sequence<Is...>) {
    (append_params_if_named<std::variant_alternative_t<Is, Variant>>(model, out, found), ...);
  }
  (std::make_index_sequence<std::variant_size_v<Variant>>{});
  if (!found) throw InputError("model", "unknown model '" + model + "'");
  return out;
}

template <class F>
decltype(auto) with_slot(const std::string& slot, F&& f) {
  if (slot == "normal") return f(NormalModel{});
  if (slot == "cohesion") return f(CohesionModel{});
  if (slot == "tangential") return f(TangentialModel{});
  if (slot == "rolling") return f(RollingModel{});
  throw InputError(slot, "unknown contact-law slot (known: normal, cohesion, tangential, rolling)");
}

}  // namespace

int ContactLaw::history_size() const {
  return visit(*this,
               []<class N, class C, class T, class R>(const N&, const C&, const T&, const R&) {
                 return History<N, C, T, R>::kSize;
               });
}

double ContactLaw::range() const {
  return std::visit([](const auto& c) { return c.range(); }, cohesion);
}

double ContactLaw::max_stiffness(double r_eff) const {
  return std::visit([&](const auto& n) { return n.max_stiffness(r_eff); }, normal);
}

double ContactLaw::reached_stiffness(double r_eff, double delta_max) const {
  return std::visit(
      [&](const auto& n) {
        if constexpr (requires { n.reached_stiffness(r_eff, delta_max); })
          return n.reached_stiffness(r_eff, delta_max);
        else
          return n.max_stiffness(r_eff);
      },
      normal);
}

double ContactLaw::attraction_energy(double r_eff) const {
  const double work = std::visit([&](const auto& c) { return c.approach_work(r_eff); }, cohesion);
  const double f = std::visit([&](const auto& c) { return c.contact_force(r_eff); }, cohesion);
  return work + f * adhesion_overlap(r_eff);
}

double ContactLaw::adhesion_overlap(double r_eff) const {
  return std::visit(
      [&](const auto& n, const auto& c) {
        const double f = c.contact_force(r_eff);
        return f > 0.0 ? n.overlap_at(f, r_eff) : 0.0;
      },
      normal, cohesion);
}

ContactLaw ContactLaw::from_spec(const ContactLawSpec& spec, const std::string& where) {
  return {make_model<NormalModel>(spec.normal, where + ".normal"),
          make_model<CohesionModel>(spec.cohesion, where + ".cohesion"),
          make_model<TangentialModel>(spec.tangential, where + ".tangential"),
          make_model<RollingModel>(spec.rolling, where + ".rolling")};
}

std::vector<std::string> slot_names() {
  return {"normal", "cohesion", "tangential", "rolling"};
}

std::vector<std::string> model_names(const std::string& slot) {
  return with_slot(slot, []<class V>(const V&) { return names_of<V>(); });
}

std::vector<ParamDoc> model_params(const std::string& slot, const std::string& model) {
  return with_slot(slot, [&]<class V>(const V&) { return params_of<V>(model); });
}

PairOutput evaluate(const ContactLaw& law, const PairInput& in, double* history) {
  return visit(law, [&](const auto& n, const auto& c, const auto& t, const auto& r) {
    return evaluate(n, c, t, r, in, history);
  });
}

}  // namespace demcal::contact
