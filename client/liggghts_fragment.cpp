#include "client/liggghts_fragment.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>

#include "core/common/error.hpp"
#include "core/contact/contact_law.hpp"

namespace demcal::cli {
namespace {

/// One slot with every parameter: the spec's value, else the model's default.
struct Slot {
  std::string model;
  std::map<std::string, double> params;
  double at(const std::string& name) const { return params.at(name); }
};

struct Law {
  Slot normal, cohesion, tangential, rolling;
  std::string name;  ///< particle_law | wall_law
};

Slot complete(const std::string& slot, const v1::ContactSlot& s,
              const std::string& fallback_model) {
  Slot out{s.model().empty() ? fallback_model : s.model(), {}};
  for (const auto& p : contact::model_params(slot, out.model)) {
    const auto it = s.params().find(p.name);
    // A required parameter left out stays NaN (Luding's k1 from Y); the coordinator validated
    // the spec, and the fragment names what it cannot export.
    out.params[p.name] = it != s.params().end() ? it->second : p.fallback;
  }
  return out;
}

Law complete(const v1::ContactLaw& law, const std::string& name) {
  return {complete("normal", law.normal(), ""), complete("cohesion", law.cohesion(), "none"),
          complete("tangential", law.tangential(), "history"),
          complete("rolling", law.rolling(), "none"), name};
}

/// Sets "particle_law.normal.youngs_modulus" (and density, size_scale) on the proto material.
void apply(v1::Material& m, const std::string& path, double value) {
  if (path == "density") return m.set_density(value);
  if (path == "size_scale") return m.set_size_scale(value);
  const auto a = path.find('.'), b = path.find('.', a + 1);
  const std::string law = path.substr(0, a);
  if (a == std::string::npos || b == std::string::npos ||
      (law != "particle_law" && law != "wall_law"))
    throw InputError(path, "not a contact-law parameter the LIGGGHTS export knows");
  v1::ContactLaw* l = law == "particle_law" ? m.mutable_particle_law() : m.mutable_wall_law();
  const std::string slot = path.substr(a + 1, b - a - 1), param = path.substr(b + 1);
  v1::ContactSlot* s = slot == "normal"       ? l->mutable_normal()
                       : slot == "cohesion"   ? l->mutable_cohesion()
                       : slot == "tangential" ? l->mutable_tangential()
                       : slot == "rolling"    ? l->mutable_rolling()
                                              : nullptr;
  if (!s) throw InputError(path, "unknown slot '" + slot + "'");
  (*s->mutable_params())[param] = value;
}

/// The radius the size-dependent LIGGGHTS properties are computed for: the monodisperse
/// radius, the mass-weighted mean of discrete classes, the median of a log-normal.
double typical_radius(const v1::Material& m) {
  const double scale = m.size_scale() > 0 ? m.size_scale() : 1.0;
  const auto& s = m.sizes();
  if (s.has_discrete() && s.discrete().radii_size() > 0) {
    double sum = 0, weight = 0;
    for (int i = 0; i < s.discrete().radii_size(); ++i) {
      const double w = i < s.discrete().mass_fractions_size() ? s.discrete().mass_fractions(i) : 1;
      sum += w * s.discrete().radii(i);
      weight += w;
    }
    return scale * sum / weight;
  }
  if (s.has_lognormal()) return scale * s.lognormal().median_radius();
  return scale * s.monodisperse().radius();
}

std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(10) << v;
  return s.str();
}

/// The fragment's text: commands with their comment aligned, and the warnings.
class Writer {
 public:
  void comment(const std::string& text) { out_ << "# " << text << "\n"; }
  void command(const std::string& cmd, const std::string& what) {
    out_ << std::left << std::setw(std::max<int>(72, int(cmd.size()) + 1)) << cmd << "# " << what
         << "\n";
  }
  /// Not exported exactly: said in the fragment and returned as a warning.
  void unsupported(const std::string& text) {
    out_ << "# NOT EXPORTED EXACTLY: " << text << "\n";
    warnings_.push_back(text);
  }
  /// A peratomtypepair property: (1,1) particle-particle, (1,2) = (2,1) = (2,2) particle-wall.
  void pair(const std::string& fix, const std::string& property, double pp, double pw,
            const std::string& what) {
    command("fix " + fix + " all property/global " + property + " peratomtypepair 2 " + num(pp) +
                " " + num(pw) + " " + num(pw) + " " + num(pw),
            what);
  }
  void type(const std::string& fix, const std::string& property, double t1, double t2,
            const std::string& what) {
    command("fix " + fix + " all property/global " + property + " peratomtype " + num(t1) + " " +
                num(t2),
            what);
  }
  LiggghtsFragment done() { return {out_.str(), warnings_}; }

 private:
  std::ostringstream out_;
  std::vector<std::string> warnings_;
};

std::string liggghts_normal(const std::string& model) {
  if (model == "linear") return "hooke/stiffness";
  return model;  // hertz, luding
}

/// Young's modulus of atom type 2 that makes LIGGGHTS' mixed Y* of a particle-wall pair,
/// 1 / ((1 - nu1^2)/Y1 + (1 - nu2^2)/Y2), equal demcal's wall law Y_w / (2 (1 - nu_w^2)).
double wall_youngs_modulus(double y1, double nu1, double yw, double nuw) {
  const double y_star_wall = yw / (2.0 * (1.0 - nuw * nuw));
  const double rest = 1.0 / y_star_wall - (1.0 - nu1 * nu1) / y1;
  return rest > 0 ? (1.0 - nuw * nuw) / rest : NAN;
}

void hertz_properties(Writer& w, const Law& p, const Law& wl) {
  const double y1 = p.normal.at("youngs_modulus"), nu1 = p.normal.at("poisson_ratio");
  const double yw = wl.normal.at("youngs_modulus"), nuw = wl.normal.at("poisson_ratio");
  double y2 = wall_youngs_modulus(y1, nu1, yw, nuw);
  if (!std::isfinite(y2)) {
    w.unsupported("the wall law's Y* = " + num(yw / (2 * (1 - nuw * nuw))) +
                  " Pa exceeds what LIGGGHTS' mixing rule reaches with the particles' Y; type 2 "
                  "gets the wall law's Y as it is");
    y2 = yw;
  }
  // LIGGGHTS refuses Young's moduli outside [5e6, 1e9] Pa in SI units unless told.
  const double lo = std::min(y1, y2), hi = std::max(y1, y2);
  if (lo < 5e6)
    w.command("soft_particles yes",
              "LIGGGHTS: allow youngsModulus < 5e6 Pa (here " + num(lo) + ")");
  if (hi > 1e9)
    w.command("hard_particles yes",
              "LIGGGHTS: allow youngsModulus > 1e9 Pa (here " + num(hi) + ")");
  w.type("demcal_Y", "youngsModulus", y1, y2,
         "Pa: particle_law.normal.youngs_modulus; type 2 so that the mixed Y* equals "
         "wall_law.normal's");
  w.type("demcal_nu", "poissonsRatio", nu1, nuw,
         "-: particle_law.normal.poisson_ratio, wall_law.normal.poisson_ratio");
  w.pair("demcal_e", "coefficientRestitution", p.normal.at("restitution"),
         wl.normal.at("restitution"), "-: particle_law / wall_law .normal.restitution");
}

/// LIGGGHTS' hooke/stiffness damps with gamman per effective mass; demcal's linear law with
/// the fraction of critical damping: gamman = 2 xi sqrt(kn / m*), exact for the typical radius.
double gamman(const Slot& normal, double m_star) {
  return 2.0 * normal.at("damping_ratio") * std::sqrt(normal.at("kn") / m_star);
}

void linear_properties(Writer& w, const Law& p, const Law& wl, double radius, double density) {
  const double mass = density * 4.0 / 3.0 * M_PI * radius * radius * radius;
  const double gpp = gamman(p.normal, mass / 2.0), gpw = gamman(wl.normal, mass);
  w.pair("demcal_kn", "kn", p.normal.at("kn"), wl.normal.at("kn"),
         "N/m: particle_law / wall_law .normal.kn");
  w.pair("demcal_kt", "kt", p.tangential.at("kt_ratio") * p.normal.at("kn"),
         wl.tangential.at("kt_ratio") * wl.normal.at("kn"),
         "N/m: .tangential.kt_ratio x .normal.kn");
  w.pair("demcal_gn", "gamman", gpp, gpw,
         "1/s: 2 .normal.damping_ratio sqrt(kn/m*), m* of two spheres (wall: one) of radius " +
             num(radius) + " m");
  w.pair("demcal_gt", "gammat", p.tangential.at("gamma_t_ratio") * gpp,
         wl.tangential.at("gamma_t_ratio") * gpw, "1/s: .tangential.gamma_t_ratio x gamman");
  for (const Law* l : {&p, &wl})
    if (l->normal.at("damp_approach_only") != 0)
      w.unsupported(l->name +
                    ".normal.damp_approach_only = 1: LIGGGHTS hooke/stiffness damps "
                    "throughout the contact, so its restitution is lower than demcal's");
}

void luding_properties(Writer& w, const Law& p, const Law& wl) {
  for (const Law* l : {&p, &wl})
    if (std::isnan(l->normal.at("k1")))
      w.unsupported(l->name +
                    ".normal.k1 from youngs_modulus (eq. 3) depends on the pair's "
                    "radius; LIGGGHTS needs LoadingStiffness: set k1");
  w.pair("demcal_k1", "LoadingStiffness", p.normal.at("k1"), wl.normal.at("k1"), "N/m: .normal.k1");
  w.pair("demcal_k2", "UnloadingStiffness", p.normal.at("k2_ratio"), wl.normal.at("k2_ratio"),
         "-: .normal.k2_ratio (k2/k1)");
  w.pair("demcal_kc", "coefficientAdhesionStiffness", p.normal.at("kc_ratio"),
         wl.normal.at("kc_ratio"), "-: .normal.kc_ratio (kc/k1)");
  w.pair("demcal_phif", "coefficientPlasticityDepth", p.normal.at("phi_f"), wl.normal.at("phi_f"),
         "-: .normal.phi_f");
  w.pair("demcal_e", "coefficientRestitution", p.normal.at("restitution"),
         wl.normal.at("restitution"), "-: .normal.restitution");
  w.pair("demcal_f0", "pullOffForce", 0.0, 0.0, "N: none in demcal (Luding's f0 = 0)");
}

void tangential_properties(Writer& w, const Law& p, const Law& wl) {
  w.pair("demcal_mu", "coefficientFriction", p.tangential.at("mu_s"), wl.tangential.at("mu_s"),
         "-: particle_law / wall_law .tangential.mu_s");
  for (const Law* l : {&p, &wl}) {
    if (l->tangential.at("mu_d_ratio") != 1.0)
      w.unsupported(l->name + ".tangential.mu_d_ratio = " + num(l->tangential.at("mu_d_ratio")) +
                    ": LIGGGHTS' tangential history has one friction coefficient (mu_s used)");
    if (l->normal.model == "hertz" && std::abs(l->tangential.at("kt_ratio") - 1.0) > 1e-12)
      w.unsupported(
          l->name + ".tangential.kt_ratio = " + num(l->tangential.at("kt_ratio")) +
          ": LIGGGHTS hertz uses kt = 8 G* sqrt(R* delta), which is demcal's kt_ratio = 1");
    if (l->normal.model != "linear" && l->tangential.at("gamma_t_ratio") != 0.0)
      w.unsupported(l->name +
                    ".tangential.gamma_t_ratio = " + num(l->tangential.at("gamma_t_ratio")) +
                    ": LIGGGHTS' tangential damping follows its own law");
  }
}

void rolling_properties(Writer& w, const Law& p, const Law& wl) {
  const bool any = p.rolling.model != "none" || wl.rolling.model != "none";
  if (!any) return;
  const auto mu = [](const Law& l) {
    return l.rolling.model == "none" ? 0.0 : l.rolling.at("mu_r");
  };
  w.pair("demcal_mur", "coefficientRollingFriction", mu(p), mu(wl),
         "-: particle_law / wall_law .rolling.mu_r");
  if (p.rolling.model != wl.rolling.model)
    w.unsupported("rolling: particle law '" + p.rolling.model + "', wall law '" + wl.rolling.model +
                  "'; the fragment uses the particle law's model for both");
  for (const Law* l : {&p, &wl})
    if (l->rolling.model == "epsd")
      w.unsupported(l->name +
                    ".rolling epsd: LIGGGHTS' epsd2 sets its rolling stiffness as "
                    "2.25 kn mu_r^2 R*^2, demcal's as kr_ratio (" +
                    num(l->rolling.at("kr_ratio")) + ") x k_ref");
}

void cohesion_notes(Writer& w, const Law& l) {
  if (l.cohesion.model == "none") return;
  w.unsupported(l.name + ".cohesion van_der_waals (Hamaker " + num(l.cohesion.at("hamaker")) +
                " J, D_min " + num(l.cohesion.at("d_min")) + " m, D_max " +
                num(l.cohesion.at("d_max")) +
                " m) acts beyond contact: LIGGGHTS 3.8 has no such model (cohesion sjkr acts "
                "only in contact); the fragment has no cohesion");
}

/// "model hertz tangential history [rolling_friction cdt]".
std::string model_words(const Law& l, const std::string& rolling) {
  std::string s = "model " + liggghts_normal(l.normal.model) + " tangential history";
  if (rolling != "none")
    s += " rolling_friction " + (rolling == "epsd" ? std::string("epsd2") : rolling);
  return s;
}

/// The model's options ("limitForce on tangential_damping off"): they follow the model words
/// in pair_style, but the wall geometry in fix wall/gran.
std::string model_options(const Law& l) {
  std::string s;
  if (l.normal.model != "luding" && l.normal.at("clip_attraction") != 0) s += "limitForce on";
  if (l.normal.model == "hertz" && l.tangential.at("gamma_t_ratio") == 0.0)
    s += std::string(s.empty() ? "" : " ") + "tangential_damping off";
  return s;
}

}  // namespace

LiggghtsFragment liggghts_fragment(v1::Material material,
                                   const std::map<std::string, double>& parameters,
                                   const std::string& title) {
  for (const auto& [path, value] : parameters) apply(material, path, value);
  const bool own_wall_law = material.has_wall_law();
  if (!own_wall_law) *material.mutable_wall_law() = material.particle_law();
  const Law p = complete(material.particle_law(), "particle_law");
  const Law wl = complete(material.wall_law(), "wall_law");
  const double radius = typical_radius(material);

  Writer w;
  w.comment(title);
  w.comment("LIGGGHTS 3.8 input fragment written by `demcal export --format liggghts`; units si.");
  w.comment("Include it after `create_box 2 ...` (atom type 1: particles, type 2: the walls'");
  w.comment("material); walls: fix ID all wall/gran ${demcal_wall_model} <geometry> type 2");
  w.comment("${demcal_wall_options} (docs/report.md).");
  if (p.normal.model != wl.normal.model)
    w.unsupported("particle law '" + p.normal.model + "' and wall law '" + wl.normal.model +
                  "' differ: each has its own model line but share the property tables");
  std::set<std::string> models = {p.normal.model, wl.normal.model};
  if (models.count("hertz")) hertz_properties(w, p, wl);
  if (models.count("linear")) linear_properties(w, p, wl, radius, material.density());
  if (models.count("luding")) luding_properties(w, p, wl);
  tangential_properties(w, p, wl);
  rolling_properties(w, p, wl);
  cohesion_notes(w, p);
  if (own_wall_law) cohesion_notes(w, wl);
  if (material.scaling().law() != "" && material.scaling().law() != "none")
    w.unsupported("scaling law " + material.scaling().law() +
                  ": the parameters above are demcal's scaled ones for the scaled particles");
  w.command("variable demcal_density equal " + num(material.density()),
            "kg/m^3: material.density (set density of the particles)");
  w.command("variable demcal_radius equal " + num(radius),
            "m: typical particle radius of material.sizes (size-dependent values are for it)");
  w.command("variable demcal_wall_model string \"" + model_words(wl, p.rolling.model) + "\"",
            "wall_law: fix wall/gran ${demcal_wall_model} <geometry> type 2 ...");
  w.command("variable demcal_wall_options string \"" + model_options(wl) + "\"",
            "wall_law: ... <geometry> ${demcal_wall_options}");
  const std::string options = model_options(p);
  w.command(
      "pair_style gran " + model_words(p, p.rolling.model) + (options.empty() ? "" : " ") + options,
      "particle_law");
  w.command("pair_coeff * *", "every type pair from the property tables above");
  return w.done();
}

}  // namespace demcal::cli
