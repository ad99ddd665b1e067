#pragma once
// YAML form of one lab-test run (`demcal lab run`); its material block is material_yaml.hpp's:
//   test: packing
//   settings: {particles: 300}            # the test's settings table (demcal lab list)
//   seed: 1
//   threads: 2
//   material: {...}
#include <string>

#include "core/io/material_yaml.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run.hpp"

namespace demcal::lab {

struct LabRunSpec {
  std::string test;
  Settings settings;
  MaterialModel material;
  RunOptions options;
};

LabRunSpec read_lab_run(const io::YamlNode& root);

/// The YAML that read_lab_run() reads back to the same run (`demcal lab run FILE`).
std::string lab_run_yaml(const LabRunSpec& spec);

}  // namespace demcal::lab
