#pragma once
// The registry of lab tests. A lab test is a type T with T::info(), its catalogue entry (name,
// metrics, settings table; core/model, no physics), and T::run(), its runner (core/lab/<name>.cpp,
// the physics). Adding one takes two files, core/model/<name>_settings.hpp (the settings struct
// and T) and core/lab/<name>.cpp (T::run), and its line here (docs/engine.md).
#include <tuple>

#include "core/model/compaction_settings.hpp"
#include "core/model/confined_compression_settings.hpp"
#include "core/model/hopper_settings.hpp"
#include "core/model/packing_settings.hpp"
#include "core/model/rotating_drum_settings.hpp"
#include "core/model/shear_cell_settings.hpp"
#include "core/model/tensile_settings.hpp"
#include "core/model/wall_friction_settings.hpp"

namespace demcal::lab {

/// Every lab test, in catalogue order.
using LabTests = std::tuple<PackingTest, ConfinedCompressionTest, TensileTest, WallFrictionTest,
                            ShearCellTest, RotatingDrumTest, HopperTest, CompactionTest>;

}  // namespace demcal::lab
