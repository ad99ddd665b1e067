#pragma once
// A whole simulation from YAML, for `demcal simulate`, examples and benchmarks:
//   threads, seed, time_step (or time_step_safety), skin, gravity,
//   domain: {lo, hi, periodic: [bool, bool, bool]}
//   density, contact_law, wall_contact_law (default: contact_law)
//   walls: [{name, plane: {point, normal}} | {name, cylinder: {point, axis, radius, lo, hi}}
//           | {name, disk: {centre, normal, radius}} | {name, mesh: {stl, scale}},
//           optional velocity, angular_velocity]
//   particles: {lattice: {origin, spacing, counts, radius, jitter}}
//            | {random: {region: {box: {lo, hi}} | {cylinder: {centre, radius, z_lo, z_hi}},
//                        count, sizes}}
//            | {list: [{radius, position, velocity, angular_velocity, density}]}
//            | {data_file: PATH}  (LIGGGHTS data file, core/io/liggghts_data.hpp)
//   phases: [{name, steps, record_every}]  (record_every: steps between wall records, 0 = none)
// File paths (stl, data_file) are relative to the scene file's folder.
#include <string>
#include <vector>

#include "core/io/yaml_node.hpp"
#include "core/particles/size_distribution.hpp"
#include "core/sim/world.hpp"

namespace demcal::io {

struct Phase {
  std::string name;
  long steps = 0;
  long record_every = 0;  ///< steps between records of every wall's force and displacement
};

struct Scene {
  sim::World world;
  std::vector<Phase> phases;
};

Scene read_scene(const YamlNode& root);
/// sizes: {monodisperse: {radius}} | {discrete: {radii, mass_fractions}} |
///        {lognormal: {median_radius, sigma_g, truncate_k}}
particles::SizeDistribution read_size_distribution(const YamlNode& node);

}  // namespace demcal::io
