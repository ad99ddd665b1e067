#pragma once
// YAML form of a material model and of one lab-test run (`demcal lab run`):
//   test: packing
//   settings: {particles: 300}            # the test's settings table (demcal lab list)
//   seed: 1
//   threads: 2
//   material:
//     particle_law: {normal: ..., cohesion: ..., tangential: ..., rolling: ...}
//     wall_law: {...}                      # default: particle_law
//     sizes: {monodisperse: {radius}} | {discrete: {radii, mass_fractions}} | {lognormal: {...}}
//     size_scale: 1.0
//     density: 1545
//     scaling: {law: none | kottlan2018 | tiscar2019, factor: 1}
//     real_median_radius: 6.5e-6           # the powder's measured median radius; default none
#include <string>

#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run.hpp"

namespace demcal::lab {

struct LabRunSpec {
  std::string test;
  Settings settings;
  MaterialModel material;
  RunOptions options;
};

MaterialModel read_material(const io::YamlNode& node);
LabRunSpec read_lab_run(const io::YamlNode& root);

/// The YAML that read_material() reads back to the same model, as a `material:` block: both laws
/// (slots without a model left out), the size distribution, size scale, density, scaling, shape
/// and preparation (when not the defaults) and the real median radius (when stated). Numbers to
/// 17 significant digits, so every value reads back to the same double.
std::string material_yaml(const MaterialModel& model);
/// The YAML that read_lab_run() reads back to the same run (`demcal lab run FILE`).
std::string lab_run_yaml(const LabRunSpec& spec);

}  // namespace demcal::lab
