#pragma once
// How a lab test's bed is built before it settles (seed 000 §2.7.1: "the packing created in this
// step is the basis for all following simulations"), a property of the material model so that
// every test of a campaign builds its bed the same way. The seed's four methods, its numbering:
//   1 clusters          van der Waals cluster formation: Gaussian velocities, free motion without
//                       cohesion and gravity under a lid, motion stopped, the full van der Waals
//                       law on without gravity (clusters and networks form), then settling;
//   2 random_motion     contact promotion by random motion: as 1, but the motion is not stopped
//                       and cohesion acts only between touching particles;
//   3 terminal_velocity limited settling velocity: poured with every particle's speed capped at
//                       its Stokes terminal velocity in air, cohesion only in contact;
//   4 pour              plain pouring (the default), cohesion only in contact.
// and one of demcal's own, for beds that start near where they end:
//   5 growth            inserted at reduced radii (real masses) in the die up to the height of
//                       the bed at `solid_fraction`, grown to full size without gravity under a
//                       lid with the motion quenched, cohesion only in contact; then gravity on
//                       and a settle that also waits out creep, within a budget
//                       (docs/lab-tests.md, "Bed preparation").
// "Cohesion only in contact" is the van der Waals law with D_max = 1.01 D_min. This header
// holds the description only (no physics); bed.hpp runs it.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "core/contact/param_table.hpp"

namespace demcal::lab {

enum class PreparationMethod {
  kClusters = 1,
  kRandomMotion = 2,
  kTerminalVelocity = 3,
  kPour = 4,
  kGrowth = 5
};
/// Every method, in the order of the enumeration.
inline constexpr std::array<PreparationMethod, 5> kPreparationMethods = {
    PreparationMethod::kClusters, PreparationMethod::kRandomMotion,
    PreparationMethod::kTerminalVelocity, PreparationMethod::kPour, PreparationMethod::kGrowth};

struct PreparationSpec {
  static constexpr const char* kName = "preparation";
  PreparationMethod method = PreparationMethod::kPour;
  double agitation_speed = 0.0;    ///< (m/s, real) per velocity component; 0 = sqrt(g d_mean)
  double agitation_time = 0.0;     ///< (s, simulated); 0 = 3 d_mean / agitation_speed
  double cluster_time = 0.0;       ///< (s, simulated); clusters: 0 = agitation_time
  double terminal_velocity = 0.0;  ///< (m/s); 0 = Stokes rho g d^2 / (18 mu_air) per particle
  /// growth: solid fraction of the die volume the particles are grown in (its height)
  double solid_fraction = kGrowthSolidFraction;
  /// growth: relative radius growth per critical time sqrt(m / k) of a fresh contact
  double growth_rate = kGrowthRate;
  static constexpr double kGrowthSolidFraction = 0.5;
  static constexpr double kGrowthRate = 1e-3;

  bool operator==(const PreparationSpec&) const = default;

  static std::array<contact::ParamInfo<PreparationSpec>, 6> table() {
    using S = PreparationSpec;
    return {{{"agitation_speed", "m/s", 0.0, 1e3, 0.0,
              "clusters, random_motion: Gaussian velocity per component; 0 = sqrt(g d_mean)",
              &S::agitation_speed},
             {"agitation_time", "s", 0.0, 10.0, 0.0,
              "clusters, random_motion: free motion without gravity; 0 = 3 mean diameters at "
              "agitation_speed",
              &S::agitation_time},
             {"cluster_time", "s", 0.0, 10.0, 0.0,
              "clusters, random_motion: cohesion on without gravity; 0 = agitation_time",
              &S::cluster_time},
             {"terminal_velocity", "m/s", 0.0, 1e3, 0.0,
              "terminal_velocity: speed cap; 0 = Stokes rho g d^2 / (18 mu_air) per particle",
              &S::terminal_velocity},
             {"solid_fraction", "-", 0.3, 0.64, kGrowthSolidFraction,
              "growth: solid fraction of the die volume the bed is grown in (sets its height)",
              &S::solid_fraction},
             {"growth_rate", "-", 1e-4, 1e-2, kGrowthRate,
              "growth: relative radius growth per critical time sqrt(m / k1) of a fresh contact",
              &S::growth_rate}}};
  }
  void finalize(const std::string&) {}
};

PreparationMethod parse_preparation_method(const std::string& text, const std::string& where);
std::string preparation_method_name(PreparationMethod method);
/// The parameters that act in the given method (the others are refused for it).
std::vector<std::string> preparation_params(PreparationMethod method);

/// The parameters of the preparation's method with their values (make_preparation reads them).
std::map<std::string, double> preparation_values(const PreparationSpec& prep);

/// A preparation from its method and parameters; errors name `where.<param>` for an unknown,
/// out-of-range or foreign parameter.
PreparationSpec make_preparation(const std::string& method,
                                 const std::map<std::string, double>& params,
                                 const std::string& where);

}  // namespace demcal::lab
