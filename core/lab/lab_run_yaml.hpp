#pragma once
// YAML form of one lab-test run (`demcal lab run`); its material block is material_yaml.hpp's:
//   test: packing
//   settings: {particles: 300}            # the test's settings table (demcal lab list)
//   seed: 1
//   threads: 2
//   material: {...}
//   expected: {solid_fraction: 0.5912}  # optional: what a stored run of this spec gave
#include <map>
#include <string>
#include <vector>

#include "core/io/material_yaml.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run.hpp"

namespace demcal::lab {

struct LabRunSpec {
  std::string test;
  Settings settings;
  MaterialModel material;
  RunOptions options;
  /// Metrics a stored run of this spec gave (a campaign's job, written by `demcal export`):
  /// `demcal lab run` says whether it reproduces them. Empty: none.
  std::map<std::string, double> expected;
};

/// One expected metric against the run: the stored value, the simulated one and their relative
/// difference |simulated - stored| / |stored| (the absolute one when stored is 0).
struct ExpectedMetric {
  std::string metric;
  double stored = 0.0, simulated = 0.0, difference = 0.0;
  bool reproduced = false;  ///< difference <= the tolerance
};

/// Each expected metric of `spec` against `metrics`, reproduced when its relative difference is
/// at most `tolerance` (0: the same double).
std::vector<ExpectedMetric> compare_expected(const LabRunSpec& spec,
                                             const std::map<std::string, double>& metrics,
                                             double tolerance);

LabRunSpec read_lab_run(const io::YamlNode& root);

/// The YAML that read_lab_run() reads back to the same run (`demcal lab run FILE`).
std::string lab_run_yaml(const LabRunSpec& spec);

}  // namespace demcal::lab
