#pragma once
// The YAML form of a material model, the one reader and writer of a `material:` block: the
// campaign spec's (client/spec_yaml, which sends it as the proto material) and a lab run's
// (lab_run_yaml.hpp) alike.
//   particle_law: {normal: ..., cohesion: ..., tangential: ..., rolling: ...}
//   wall_law: {...}                      # default: particle_law
//   sizes: {monodisperse: {radius}} | {discrete: {radii, mass_fractions}} | {lognormal: {...}}
//   size_scale: 1.0
//   density: 1545
//   scaling: {law: none | kottlan2018 | tiscar2019, factor: 1}
//   shape: {kind: rod, aspect_ratio: 2}  # default: spheres
//   preparation: {method: clusters, ...} # default: pour
//   real_median_radius: 6.5e-6           # the powder's measured median radius; default none
#include <string>

#include "core/io/yaml_node.hpp"
#include "core/model/material.hpp"

namespace demcal::io {

/// The material of a `material:` node; errors name the file, line and field.
lab::MaterialModel read_material(const YamlNode& node);
/// A `preparation: {method: ..., <param>: value}` block, errors at the line of the key they name.
lab::PreparationSpec read_preparation(const YamlNode& node);

/// The YAML that read_material() reads back to the same model, as a `material:` block: both laws
/// (slots without a model left out), the size distribution, size scale, density, scaling, shape
/// and preparation (when not the defaults) and the real median radius (when stated). Numbers to
/// 17 significant digits, so every value reads back to the same double.
std::string material_yaml(const lab::MaterialModel& model);

}  // namespace demcal::io
