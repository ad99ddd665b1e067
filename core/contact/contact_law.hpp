#pragma once
// The contact law: four slots (normal, cohesion, tangential, rolling), each a closed set of models
// composed at run time. Physics are stateless functions of (parameters, pair input, the model's own
// history span); the order of evaluation is written once, in evaluate() below.
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "core/contact/cohesion/none.hpp"
#include "core/contact/cohesion/van_der_waals.hpp"
#include "core/contact/normal/hertz.hpp"
#include "core/contact/normal/linear.hpp"
#include "core/contact/normal/luding.hpp"
#include "core/contact/pair.hpp"
#include "core/contact/rolling/cdt.hpp"
#include "core/contact/rolling/epsd.hpp"
#include "core/contact/rolling/none.hpp"
#include "core/contact/tangential/history.hpp"

namespace demcal::contact {

using NormalModel = std::variant<normal::Linear, normal::Hertz, normal::Luding>;
using CohesionModel = std::variant<cohesion::None, cohesion::VanDerWaals>;
using TangentialModel = std::variant<tangential::History>;
using RollingModel = std::variant<rolling::None, rolling::Cdt, rolling::Epsd>;

/// A slot as written in a spec: the model's name and its parameters by name.
struct SlotSpec {
  std::string model;
  std::map<std::string, double> params;
  bool operator==(const SlotSpec&) const = default;
};
struct ContactLawSpec {
  SlotSpec normal, cohesion{"none", {}}, tangential, rolling{"none", {}};
  bool operator==(const ContactLawSpec&) const = default;
};

struct ContactLaw {
  NormalModel normal;
  CohesionModel cohesion;
  TangentialModel tangential;
  RollingModel rolling;

  /// Doubles of per-contact history this composition needs.
  int history_size() const;
  /// How far beyond contact (surface gap, m) the law still acts.
  double range() const;
  /// Largest stiffness a contact of effective radius r_eff = 2 R* can reach (N/m), for the
  /// sqrt(m/k) time-step bound.
  double max_stiffness(double r_eff) const;
  /// Largest stiffness a contact can present once its overlap has reached delta_max (N/m): below
  /// max_stiffness() for a normal model whose un-/reloading stiffness grows with the overlap
  /// (Luding); max_stiffness() for the others.
  double reached_stiffness(double r_eff, double delta_max) const;
  /// An upper bound of the energy (J) the law's attraction sets free on a pair of effective radius
  /// r_eff that comes from its range into contact: the cohesion's work up to contact, plus at most
  /// its contact force F times the overlap at which the fresh contact's repulsion carries F (the
  /// depth of the well the attraction pulls the pair into is below F times that overlap). Zero
  /// without a cohesion model.
  double attraction_energy(double r_eff) const;
  /// The overlap (m) at which a fresh contact's repulsion carries the cohesion's contact force
  /// (the van der Waals A_H r_eff / (6 D_min^2), seed 000 eq. 12): where the attraction alone
  /// holds a pair of effective radius r_eff at rest. Zero without a cohesion model.
  double adhesion_overlap(double r_eff) const;
  /// Builds a law from its spec; errors name the field path below `where`.
  static ContactLaw from_spec(const ContactLawSpec& spec, const std::string& where);
};

/// Names of the models of each slot, and their parameter tables, for docs and validation.
struct ParamDoc {
  std::string name, unit, doc;
  double lo, hi, fallback;
};
std::vector<std::string> slot_names();
std::vector<std::string> model_names(const std::string& slot);
std::vector<ParamDoc> model_params(const std::string& slot, const std::string& model);

template <class N, class C, class T, class R>
struct History {
  static constexpr int kNormal = 0;
  static constexpr int kTangential = N::kHistory;
  static constexpr int kRolling = N::kHistory + T::kHistory;
  static constexpr int kSize = N::kHistory + T::kHistory + R::kHistory;
};

/// Evaluates one pair. The order matters: the Coulomb limits of the tangential and rolling slots
/// use the normal force of seed 000 eq. 18 (normal law + adhesive parts added back), so the
/// normal and cohesion slots run first. A pair that does not overlap feels only the cohesion
/// slot (acting beyond contact) and its history is cleared, as a contact that ended.
template <class N, class C, class T, class R>
inline PairOutput evaluate(const N& nm, const C& cm, const T& tm, const R& rm, const PairInput& in,
                           double* history) {
  using H = History<N, C, T, R>;
  PairOutput out;
  const double f_coh = cm.force(in);
  if (in.delta <= 0.0) {
    clear_history<H::kSize>(history);
    out.fn = -f_coh;
    out.force = in.n * f_coh;
    return out;
  }
  const NormalResult nr = nm.force(in, history + H::kNormal);
  out.fn = nr.fn - f_coh;
  out.stiffness = nr.k_step;
  const double f_coulomb = std::max(0.0, out.fn + nr.f_adhesive + f_coh);
  out.ft = tm.force(in, nr, f_coulomb, history + H::kTangential);
  out.rolling_torque = rm.torque(in, nr, f_coulomb, history + H::kRolling);
  out.force = out.ft - in.n * out.fn;
  const Vec3 n_x_ft = cross(in.n, out.ft);
  out.torque_i = n_x_ft * in.r_i + out.rolling_torque;
  out.torque_j = n_x_ft * in.r_j - out.rolling_torque;
  return out;
}

/// Calls f(normal, cohesion, tangential, rolling) with the concrete model types, so hot loops
/// are compiled for the models in use (one std::visit per call, not per pair).
template <class F>
decltype(auto) visit(const ContactLaw& law, F&& f) {
  return std::visit(std::forward<F>(f), law.normal, law.cohesion, law.tangential, law.rolling);
}

/// Evaluates one pair with one visit of the law's slots: for single contacts and setup code;
/// the per-step loops use the templated form above.
PairOutput evaluate(const ContactLaw& law, const PairInput& in, double* history);

}  // namespace demcal::contact
