#pragma once
// The single-contact laboratory behind `demcal contact`: two spheres, or a sphere and a plane
// wall, in free motion (collisions, sliding, rolling) or driven through a prescribed overlap path
// (a list of overlap waypoints at a drive speed). It runs the same World, step function and
// contact-law code as every bulk simulation.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/contact/contact_law.hpp"
#include "core/io/yaml_node.hpp"

namespace demcal::lab {

struct Body {
  double radius = 0.0, density = 0.0;
  Vec3 position, velocity, angular_velocity;
  bool fixed = false;  ///< kinematic: keeps its velocity whatever the force
};

struct SingleContactSpec {
  contact::ContactLaw law;
  Body first;
  std::optional<Body> second;      ///< a sphere, or
  std::optional<Vec3> wall_point;  ///< a plane wall through this point ...
  Vec3 wall_normal{0, 0, 1};       ///< ... facing the sphere
  Vec3 gravity;
  double time_step = 0.0;
  long steps = 0;
  bool path_mode = false;
  std::vector<double> waypoints;  ///< overlaps (m) to drive through, in order
  double drive_speed = 0.0;       ///< overlap rate while driving (m/s)
  int output_every = 1;
};

struct SingleContactSummary {
  double restitution = 0.0;     ///< -(normal relative velocity after) / (before), first contact
  double contact_duration = 0;  ///< of the first contact (s)
  double max_overlap = 0.0;     ///< (m)
  double max_force = 0.0;       ///< largest |fn| (N)
  bool contact_ended = false;   ///< whether the first contact ended within the run
  Vec3 final_position[2], final_velocity[2], final_angular_velocity[2];
  long steps = 0;
};

/// One output sample; force quantities are those the contact law gave at this step.
struct SingleContactSample {
  double time, overlap, fn;
  Vec3 x[2], v[2], w[2], ft, rolling_torque;
};

SingleContactSpec read_single_contact(const io::YamlNode& root);
/// Runs the experiment; `sink` receives every `output_every`-th sample (may be empty).
SingleContactSummary run_single_contact(
    const SingleContactSpec& spec, const std::function<void(const SingleContactSample&)>& sink);

/// The CSV column names matching write order of a sample.
std::vector<std::string> single_contact_columns();
std::vector<double> single_contact_row(const SingleContactSample& s);

}  // namespace demcal::lab
