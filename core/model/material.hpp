#pragma once
// The material model a campaign calibrates: the contact laws (in spec form, so any parameter can
// be addressed by a path), the size distribution, the density and the coarse-graining. Lab tests
// build their worlds from it; factor paths of a campaign name its parameters.
//
// Parameter paths:
//   particle_law.<slot>.<param>   e.g. particle_law.normal.k2_ratio, particle_law.rolling.mu_r
//   wall_law.<slot>.<param>       e.g. wall_law.tangential.mu_s
//   density
//   sizes.radius | sizes.median_radius | sizes.sigma_g | sizes.scale   (scale multiplies every
//   radius) scaling.factor
//   shape.<param>                 e.g. shape.aspect_ratio (particles::ShapeSpec, per shape kind)
//   preparation.<param>           e.g. preparation.cluster_time (PreparationSpec, per method)
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/contact/contact_law.hpp"
#include "core/contact/scaling.hpp"
#include "core/model/preparation.hpp"
#include "core/particles/clump_shape.hpp"
#include "core/particles/size_distribution.hpp"

namespace demcal::lab {

struct MaterialModel {
  contact::ContactLawSpec particle_law;
  contact::ContactLawSpec wall_law;
  particles::SizeDistribution sizes = particles::Monodisperse{1e-3};
  double size_scale =
      1.0;  ///< multiplies every radius of `sizes` (real radii), a factor like any other
  double density = 1500.0;  ///< real particle density (kg/m^3)
  contact::ScalingLaw scaling = contact::ScalingLaw::kNone;
  double scale_factor = 1.0;
  /// The powder's measured number-median radius (m; 0: not stated), when the model's particles
  /// stand for larger ones than the powder's (seed 000 §2.3: spheres scaled to r_real of
  /// 10-20 um for LH220's d50 of 11-15 um). Changes no simulation; the diagnosis's
  /// coarse_graining candidate moves the radius toward it.
  double real_median_radius = 0.0;
  /// Particle shape: spheres, or rigid multisphere clumps whose volume-equivalent radius
  /// follows `sizes` (so mass and volume do not change with the shape).
  particles::ShapeSpec shape;
  /// How every lab test builds its bed before settling (seed 000 §2.7.1).
  PreparationSpec preparation;

  /// The simulated laws, radii and density after coarse-graining (seed 000 eq. 24-30 or
  /// seed 001 eq. 15-18).
  contact::ContactLaw simulated_particle_law() const;
  contact::ContactLaw simulated_wall_law() const;
  particles::SizeDistribution simulated_sizes() const;
  double simulated_density() const;
  /// The clump template of a non-spherical shape; none for spheres.
  std::optional<particles::ClumpTemplate> clump_template() const;
  contact::ScaleFactors factors() const;
  /// Checks both laws and the distribution; errors name the path.
  void validate() const;
};

/// The range of a stated real median radius (m), that of a monodisperse radius.
inline constexpr double kRealMedianRadiusMin = 1e-9, kRealMedianRadiusMax = 10.0;

/// Everything of the model that can change a simulation, as text: every slot's model and given
/// parameters, the size distribution, density, scaling, shape and preparation (numbers to 17
/// digits; not the real median radius, which changes none). Two models with the same identity
/// simulate alike; the key of work that runs share (core/lab/stage_cache.hpp).
std::string material_identity(const MaterialModel& model);

struct ParameterInfo {
  std::string path, unit;
  double lo, hi;  ///< valid range
};

/// Every addressable parameter of the model as it stands (its models' tables, plus density,
/// sizes and scaling), for validating factor paths and bounds.
std::vector<ParameterInfo> parameters(const MaterialModel& model);
/// The agitation time of the clusters preparation by default for this material's largest
/// simulated particles: 3 diameters at sqrt(g d), i.e. 3 sqrt(d / g), g = 9.81 m/s^2 (s).
double default_agitation_time(const MaterialModel& model);
/// Whether the model has a parameter at `path` (a path of parameters(model)).
bool has_parameter(const MaterialModel& model, const std::string& path);
/// The parameter at `path`: its unit and valid range; InputError naming `where` and the known
/// paths when the model has none there.
ParameterInfo require_parameter(const MaterialModel& model, const std::string& path,
                                const std::string& where);
/// Sets one parameter by path; throws InputError naming the path if unknown or out of range.
void set_parameter(MaterialModel& model, const std::string& path, double value);

/// A value for a parameter path and the field of the request it came from.
struct ParameterValue {
  std::string path;
  double value = 0.0;
  std::string where;  ///< the field an error names (e.g. "spec.fixed.density")
};
/// The model with every value set, in one call: each path must be a parameter of the model,
/// each value in its range and the model valid as a whole; otherwise InputError naming the
/// first wrong value's `where`. The given model is not changed.
MaterialModel with_parameters(MaterialModel model, const std::vector<ParameterValue>& values);
double get_parameter(const MaterialModel& model, const std::string& path);
/// The material of a run: every parameter set in path order, then the whole model validated
/// (a run's parameters may pass through an invalid pair on the way, e.g. D_min above D_max).
MaterialModel with_run_parameters(MaterialModel model,
                                  const std::map<std::string, double>& parameters);

}  // namespace demcal::lab
