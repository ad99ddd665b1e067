#pragma once
// Running a virtual lab test: a scenario that builds its own bed from a material model and
// settings, runs named phases and returns named metrics, time series and optional VTK snapshots.
// A blow-up is a SimulationFailure with its reason, never numbers.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/lab/catalog.hpp"
#include "core/lab/material.hpp"

namespace demcal::lab {

struct Series {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

struct LabOutput {
  std::map<std::string, double> metrics;  ///< by the names of the catalogue
  std::map<std::string, Series> series;
  std::vector<std::string> snapshots;  ///< VTK files written
  std::vector<std::string> notes;      ///< plain statements about the result
};

struct RunOptions {
  int threads = 1;
  std::uint64_t seed = 1;
  std::string snapshot_dir;                       ///< empty: no VTK
  std::function<void(double fraction)> progress;  ///< optional, 0..1
};

using LabRunner = LabOutput (*)(const MaterialModel&, const Settings&, const RunOptions&);

/// The runner of a catalogued test; InputError for an unknown name.
LabRunner find_lab_runner(const std::string& name);

/// Runs a test by name: validates the settings, runs, and checks that every catalogued metric
/// was produced.
LabOutput run_lab_test(const std::string& name, const MaterialModel& material,
                       const Settings& settings, const RunOptions& options);

}  // namespace demcal::lab
