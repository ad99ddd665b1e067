#include "core/model/catalog.hpp"

#include "core/common/error.hpp"
#include "core/model/compaction_settings.hpp"
#include "core/model/confined_compression_settings.hpp"
#include "core/model/hopper_settings.hpp"
#include "core/model/material.hpp"
#include "core/model/packing_settings.hpp"
#include "core/model/rotating_drum_settings.hpp"
#include "core/model/shear_cell_settings.hpp"
#include "core/model/tensile_settings.hpp"
#include "core/model/wall_friction_settings.hpp"

namespace demcal::lab {

// packing: seed 000 §2.7.1, §3.1 (runner in packing.cpp).
LabTestInfo packing_info() {
  return {
      "packing",
      "bed built in a cylindrical die by the material's preparation and settled; solid fraction "
      "and coordination number in a sampling volume away from the walls",
      "seed 000 §2.7.1, §3.1",
      {{"solid_fraction", "-", "solid volume over sampling volume"},
       {"coordination_number", "-",
        "mean number of touching particles (clumps: bodies) per particle in the sampling volume"}},
      settings_docs<PackingSettings>()};
}

// confined_compression: seed 000 §2.7.2 (eq. 31-33), seed 001 §3.2.1 (eq. 19); runner in
// confined_compression.cpp.
LabTestInfo confined_compression_info() {
  return {
      "confined_compression",
      "bed in a cylindrical die loaded by a stress-servo piston to 15 kPa, unloaded to 0.5 kPa "
      "and reloaded five times, then unloaded",
      "seed 000 §2.7.2 (eq. 31-33); seed 001 §3.2.1 (eq. 19)",
      {{"compressibility", "%", "(h0 - h1) / h0 at the first load (seed 000 eq. 31)"},
       {"k_load", "MPa",
        "mean reload bulk stiffness (sigma_max - sigma_min) h1 / (h_unloaded - h_loaded) "
        "(seed 000 eq. 32)"},
       {"k_unload", "MPa",
        "mean unload bulk stiffness (sigma_max - sigma_min) h1 / (h_unloaded - h_loaded_before) "
        "(seed 000 eq. 33)"},
       {"final_solid_fraction", "-", "solid fraction after the final unload"},
       {"confined_modulus", "MPa",
        "E' = (sigma_max - sigma_min) / (eps_max - eps_min) of the last cycle, eps = "
        "(h0 - h) / h0 (seed 001 eq. 19)"}},
      settings_docs<ConfinedCompressionSettings>()};
}

// tensile: seed 000 §2.7.3 (eq. 34-35); runner in tensile.cpp.
LabTestInfo tensile_info() {
  return {"tensile",
          "bed consolidated in the die by an adhesive piston (eq. 34-35), unloaded, and pulled "
          "apart at constant slow speed inside a frictionless non-cohesive die wall",
          "seed 000 §2.7.3 (eq. 34-35, Fig. 10-11)",
          {{"tensile_strength", "kPa",
            "peak tensile stress on the piston less the weight of the powder stuck to it, over "
            "the piston area"}},
          settings_docs<TensileSettings>()};
}

// wall_friction: seed 000 §2.7.5, §3.3.4; runner in wall_friction.cpp.
LabTestInfo wall_friction_info() {
  return {"wall_friction",
          "bed pressed by the container against a piston that turns at constant normal stress "
          "(1, 1.25, 1.5, 1.75, 2, 3 kPa); tau = 3 T / (2 pi R^3); regression through the origin",
          "seed 000 §2.7.5, §3.3.4",
          {{"wall_friction_angle", "deg",
            "atan of the slope of the wall shear stress over the normal stress, fitted through "
            "the origin"}},
          settings_docs<WallFrictionSettings>()};
}

// shear_cell: seed 000 §2.7.4, Table 3, Fig. 12 and 23 (runner in shear_cell.cpp).
LabTestInfo shear_cell_info() {
  return {"shear_cell",
          "FT4 standard shear test: vaned shear head (mesh) in a cylindrical vessel, normal stress "
          "applied by the container; pre-shear at 3 kPa, then yield under torque control at 2, "
          "1.75, 1.5, 1.25 and 1 kPa, each from the pre-sheared state; tau = 3 T / (2 pi R^3)",
          "seed 000 §2.7.4 (Table 3, Fig. 12, Fig. 23)",
          {{"pre_shear_stress", "kPa", "steady shear stress of the pre-shear at sigma_pre = 3 kPa"},
           {"yield_locus_slope", "-", "slope of the least-squares yield locus"},
           {"yield_locus_intercept", "kPa", "intercept (cohesion) of the yield locus"},
           {"ffc", "-",
            "flow function sigma_1 / sigma_c from the Mohr circles, at most 100 (100 without "
            "cohesion, 0 if inconsistent)"},
           {"effective_friction_angle", "deg",
            "angle of the origin line touching the consolidation circle (0 if inconsistent)"},
           {"mohr_consistent", "0/1",
            "0 when the pre-shear point lies above the yield locus (seed 000 Fig. 23b)"},
           {"unconfined_yield_strength", "kPa", "sigma_c of the Mohr circle through the origin"},
           {"major_consolidation_stress", "kPa",
            "sigma_1 of the circle through the pre-shear point touching the locus"}},
          settings_docs<ShearCellSettings>()};
}

// rotating_drum: seed 001 §3.2.2-3.2.3, eq. 20 (runner in rotating_drum.cpp).
LabTestInfo rotating_drum_info() {
  return {"rotating_drum",
          "drum of D x W mm (100 x 44 in the seed), fill 43 %: the particle count follows from "
          "the drum, the fill and the simulated sizes; dynamic angle of repose at `rpm` (4) from "
          "a line fitted to the projected free surface, and the area method at 4, 40, 80, 105 and "
          "116 rpm from a raster of the projected bed; also reports drum_diameter_ratio D/d and "
          "particles",
          "seed 001 §3.2.2-3.2.3 (eq. 20, Fig. 13)",
          {{"dynamic_angle_of_repose", "deg", "free-surface angle at `rpm` (image fit)"},
           {"csa_occupied_4", "%", "occupied cross-sectional area at 4 rpm (eq. 20)"},
           {"csa_occupied_40", "%", "occupied cross-sectional area at 40 rpm (eq. 20)"},
           {"csa_occupied_80", "%", "occupied cross-sectional area at 80 rpm (eq. 20)"},
           {"csa_occupied_105", "%", "occupied cross-sectional area at 105 rpm (eq. 20)"},
           {"csa_occupied_116", "%", "occupied cross-sectional area at 116 rpm (eq. 20)"},
           {"centrifuging_116", "0/1", "1 when the bed centrifuges at 116 rpm"}},
          settings_docs<RotatingDrumSettings>()};
}

// hopper: seed 000 §2.7.6 (runner in hopper.cpp).
LabTestInfo hopper_info() {
  return {
      "hopper",
      "wedge hopper slice with periodic front and back: fill and settle with the gate closed, "
      "open it, discharge rate from the mass-time curve, arching, ratio to Beverloo's slot "
      "law (hydraulic-diameter form) W = (4 sqrt 2 / pi) C rho_b sqrt(g) L (b - k d)^1.5 with "
      "C = 0.58, k = 1.5, times Rose and Tanaka's factor (tan theta tan 45 deg)^-0.35 for walls "
      "steeper than 45 deg",
      "seed 000 §2.7.6",
      {{"discharge_rate", "kg/s", "slope of the discharged mass over time after start-up"},
       {"arched", "0/1", "1 when no particle left for arch_time before the hopper emptied"},
       {"beverloo_rate", "kg/s", "Beverloo's slot-form rate with the wall factor"},
       {"beverloo_ratio", "-", "discharge_rate over beverloo_rate"}},
      settings_docs<HopperSettings>()};
}

// compaction: seed 004 §2.3-2.4, §3.1 (runner in compaction.cpp).
LabTestInfo compaction_info() {
  return {
      "compaction",
      "fully periodic cell filled at random and compacted by shrinking it affinely through "
      "target solid fractions, held at each; contact stress tensor (Love-Weber), "
      "pressure-density curve, a constant-volume shear probe from the last, and yield probes "
      "along five strain paths from an unloaded reference state with the modified Cam-clay "
      "ellipse fitted to their yield points",
      "seed 004 §2.3-2.4, §3.1",
      {{"jamming_fraction", "-",
        "solid fraction at which the contact pressure of the compression first exceeds 1e-2 of "
        "the final held pressure"},
       {"final_pressure", "kPa", "mean contact stress p = tr(sigma) / 3 held at phi_max"},
       {"final_coordination_number", "-", "contacts per body at phi_max"},
       {"peak_stress_ratio", "-",
        "yield: the largest q / p of the constant-volume axisymmetric shear probe from "
        "phi_max"},
       {"steady_stress_ratio", "-", "mean q / p over the last fifth of the probe"},
       {"isotropic_yield_pressure", "kPa",
        "p at yield of the isotropic reload from the reference state (seed 004 eq. 2.11)"},
       {"yield_cap_pressure", "kPa",
        "p_c of the modified Cam-clay ellipse q^2 = M^2 p (p_c - p) fitted to the yield points"},
       {"yield_slope", "-", "M of that ellipse: the critical state stress ratio q / p"}},
      settings_docs<CompactionSettings>()};
}

const std::vector<LabTestInfo>& lab_catalog() {
  static const std::vector<LabTestInfo> tests = {
      packing_info(),    confined_compression_info(), tensile_info(), wall_friction_info(),
      shear_cell_info(), rotating_drum_info(),        hopper_info(),  compaction_info()};
  return tests;
}

const LabTestInfo& find_lab_info(const std::string& name) {
  std::string known;
  for (const auto& t : lab_catalog()) {
    if (t.name == name) return t;
    known += (known.empty() ? "" : ", ") + t.name;
  }
  throw InputError("test", "unknown lab test '" + name + "' (known: " + known + ")");
}

void validate_settings(const LabTestInfo& info, const Settings& settings,
                       const std::string& where) {
  for (const auto& [key, value] : settings) {
    const contact::ParamDoc* doc = nullptr;
    for (const auto& d : info.settings)
      if (d.name == key) doc = &d;
    if (!doc) throw InputError(where + "." + key, "not a setting of lab test '" + info.name + "'");
    if (!(value >= doc->lo && value <= doc->hi))
      throw InputError(where + "." + key,
                       "value " + std::to_string(value) + " outside the valid range [" +
                           std::to_string(doc->lo) + ", " + std::to_string(doc->hi) + "]");
  }
}

void check_size(const std::string& test, const MaterialModel& material, const Settings& settings,
                const std::string& where) {
  if (test != "rotating_drum") return;  // the other tests are sized by their particle count
  drum_bed(read_settings<RotatingDrumSettings>(settings, where), material.simulated_sizes(), where);
}

}  // namespace demcal::lab
