#pragma once
// Shapes of rigid multisphere clumps (seed 004 §2.2.2.1: "multispheres ... composed out of a set
// of spheres which are partially overlapping and linked together"): rods of a given aspect
// ratio, the helical fibres of seed 004 Table 2.1, and irregular clusters. A template holds the
// member spheres in the body's principal frame, scaled to a volume-equivalent radius of 1, with
// the volume and principal moments of the union of the spheres (overlaps counted once).
#include <array>
#include <map>
#include <string>
#include <vector>

#include "core/common/vec3.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::particles {

enum class ShapeKind { kSphere, kRod, kHelix, kCluster };

/// A particle shape. Parameters are addressed as `shape.<name>` (factors like any other).
struct ShapeSpec {
  static constexpr const char* kName = "shape";
  ShapeKind kind = ShapeKind::kSphere;
  double aspect_ratio = 2.0;  ///< rod, helix: length over sphere diameter
  double offset_ratio = 0.0;  ///< helix: distance of the sphere centres from the axis / diameter
  double revolutions = 0.0;   ///< helix: turns over the length (seed 004 eq. 2.1)
  double spheres = 4.0;       ///< cluster: number of spheres
  double irregularity = 0.5;  ///< cluster: 0 compact .. 1 spread and uneven radii
  double seed = 1.0;          ///< cluster: which random cluster
  /// cluster: every centre's distance from the first sphere's, times this: 1 the cluster as
  /// built, 0 all centres at one point (the cluster is then its largest sphere, a sphere)
  double spread = 1.0;
  double spacing = 0.5;  ///< rod, helix: largest centre distance of neighbours / diameter

  static std::array<contact::ParamInfo<ShapeSpec>, 8> table() {
    using S = ShapeSpec;
    return {
        {{"aspect_ratio", "-", 1.0, 20.0, 2.0, "rod, helix: length / sphere diameter",
          &S::aspect_ratio},
         {"offset_ratio", "-", 0.0, 2.0, 0.267,
          "helix: sphere centres' distance from the axis / diameter (seed 004 Table 2.1: "
          "0.04 / 0.15)",
          &S::offset_ratio},
         {"revolutions", "-", 0.0, 10.0, 0.5, "helix: turns over the length (seed 004 eq. 2.1)",
          &S::revolutions},
         {"spheres", "-", 2.0, 50.0, 4.0, "cluster: number of spheres", &S::spheres},
         {"irregularity", "-", 0.0, 1.0, 0.5,
          "cluster: 0 compact, equal spheres .. 1 spread, uneven radii", &S::irregularity},
         {"seed", "-", 1.0, 1e9, 1.0, "cluster: which random cluster", &S::seed},
         {"spread", "-", 0.0, 1.0, 1.0,
          "cluster: centre distances from the first sphere times this (0: one sphere)", &S::spread},
         {"spacing", "-", 0.05, 1.0, 0.5,
          "rod, helix: largest distance of neighbouring centres / diameter (overlap)",
          &S::spacing}}};
  }
  void finalize(const std::string&) {}
};

ShapeKind parse_shape_kind(const std::string& text, const std::string& where);
std::string shape_kind_name(ShapeKind kind);
/// The parameter names that shape the given kind (the others are ignored for it).
std::vector<std::string> shape_params(ShapeKind kind);
/// A shape from its kind and parameters (others at their defaults); errors name `where.<param>`
/// for an unknown, out-of-range or foreign parameter.
ShapeSpec make_shape_spec(const std::string& kind, const std::map<std::string, double>& params,
                          const std::string& where);
/// The parameters of the shape's kind by name, with their current values.
std::map<std::string, double> shape_values(const ShapeSpec& shape);

/// Volume, centroid and inertia tensor (about the centroid, unit density) of a union of spheres.
struct MassProperties {
  double volume = 0.0;
  Vec3 centroid;
  std::array<std::array<double, 3>, 3> inertia{};
  int columns = 0;  ///< grid columns per side at convergence
};

/// Integrates over the union: a grid of columns along z, each column's intervals inside the
/// union merged and integrated exactly in z, the grid refined until volume and inertia change by
/// less than `tolerance` (relative) between refinements.
MassProperties union_mass_properties(const std::vector<Vec3>& centres,
                                     const std::vector<double>& radii, double tolerance = 2e-5);

struct ClumpTemplate {
  std::vector<Vec3> offsets;  ///< member centres in the principal frame, centroid at 0
  std::vector<double> radii;
  double volume = 0.0;  ///< of the union (= 4/3 pi: volume-equivalent radius 1)
  Vec3 inertia;         ///< principal moments per unit density
  double bounding_radius = 0.0;
  double sphere_volume_sum = 0.0;  ///< sum of the members' own volumes (overlaps counted twice)
  std::size_t size() const { return radii.size(); }
  /// Share of each member's own volume that is the union's: volume / sphere_volume_sum.
  double volume_weight() const { return volume / sphere_volume_sum; }
};

/// The members of a shape before scaling, in units of the (largest) member radius.
void shape_spheres(const ShapeSpec& shape, std::vector<Vec3>& centres, std::vector<double>& radii);
/// The template of a shape: members in the principal frame, scaled to equivalent radius 1.
ClumpTemplate make_template(const ShapeSpec& shape);

}  // namespace demcal::particles
