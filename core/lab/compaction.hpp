#pragma once
// compaction (seed 004 §2.3-2.4, §3.1): a fully periodic cell of particles (spheres or rigid
// clumps: rods, helices, clusters) compacted by shrinking the cell affinely, the particles
// remapped with it, through a list of target solid fractions; at each the cell is held and its
// contact stress tensor (Love-Weber, metrics/stress.hpp) read. No walls: the cheapest
// representative volume of a bulk.
#include <array>

#include "core/lab/lab_test.hpp"
#include "core/model/compaction_settings.hpp"

namespace demcal::lab {

LabOutput run_compaction(const MaterialModel& material, const Settings& settings,
                         const RunOptions& options);

}  // namespace demcal::lab
