#include "core/lab/single_contact.hpp"

#include <cmath>

#include "core/common/error.hpp"
#include "core/io/contact_law_yaml.hpp"
#include "core/sim/step.hpp"

namespace demcal::lab {
namespace {

Body read_body(const io::YamlNode& n) {
  n.expect_only({"radius", "density", "position", "velocity", "angular_velocity", "fixed"});
  Body b;
  b.radius = n["radius"].as_number();
  b.density = n["density"].as_number();
  if (!(b.radius > 0.0)) n["radius"].fail("must be > 0");
  if (!(b.density > 0.0)) n["density"].fail("must be > 0");
  b.position = n["position"].as_vec3();
  if (auto v = n.child("velocity")) b.velocity = v->as_vec3();
  if (auto w = n.child("angular_velocity")) b.angular_velocity = w->as_vec3();
  if (auto f = n.child("fixed")) b.fixed = f->as_bool();
  return b;
}

struct Geometry {
  Vec3 n;
  double overlap;
};

Geometry geometry(const sim::World& w) {
  const auto& p = w.particles;
  if (p.size() == 2) {
    const Vec3 d = p.x[1] - p.x[0];
    const double dist = norm(d);
    return {d / dist, p.radius[0] + p.radius[1] - dist};
  }
  walls::WallGeometry g;
  walls::wall_geometry(w.walls[0].shape, p.x[0], p.radius[0], 1e300, g);
  return {g.n, g.delta};
}

/// Rate of overlap change of the pair (> 0 approaching).
double approach_speed(const sim::World& w, const Vec3& n) {
  const auto& p = w.particles;
  const Vec3 v_rel = p.size() == 2 ? p.v[0] - p.v[1] : p.v[0];
  return dot(v_rel, n);
}

void add_body(sim::World& w, const Body& b, bool kinematic) {
  const auto i =
      w.particles.add_sphere(b.position, b.radius, b.density, 0,
                             kinematic ? particles::Motion::kKinematic : particles::Motion::kFree);
  w.particles.v[i] = b.velocity;
  w.particles.omega[i] = b.angular_velocity;
}

SingleContactSample sample(const sim::World& w) {
  const auto& p = w.particles;
  const Geometry g = geometry(w);
  SingleContactSample s{};
  s.time = w.time;
  s.overlap = g.overlap;
  for (std::size_t k = 0; k < p.size(); ++k) {
    s.x[k] = p.x[k];
    s.v[k] = p.v[k];
    s.w[k] = p.omega[k];
  }
  // Body 0 feels only the contact (and gravity): its force and torque give the law's output.
  const Vec3 f = p.f[0] - w.gravity * p.mass[0];
  s.fn = -dot(f, g.n);
  s.ft = f + g.n * s.fn;
  s.rolling_torque = p.torque[0] - cross(g.n, s.ft) * p.radius[0];
  return s;
}

}  // namespace

SingleContactSpec read_single_contact(const io::YamlNode& root) {
  root.expect_only({"contact_law", "bodies", "wall", "gravity", "time_step", "steps", "end_time",
                    "mode", "path", "output_every"});
  SingleContactSpec spec;
  spec.law = io::read_contact_law(root["contact_law"]);
  const auto bodies = root["bodies"].items();
  if (bodies.empty() || bodies.size() > 2)
    root["bodies"].fail("give one sphere (with a wall) or two spheres");
  spec.first = read_body(bodies[0]);
  if (bodies.size() == 2) spec.second = read_body(bodies[1]);
  if (auto wall = root.child("wall")) {
    if (spec.second) wall->fail("give either a second sphere or a wall, not both");
    wall->expect_only({"point", "normal"});
    spec.wall_point = (*wall)["point"].as_vec3();
    spec.wall_normal = normalized((*wall)["normal"].as_vec3());
  } else if (!spec.second) {
    root["bodies"].fail("one sphere needs a wall");
  }
  if (auto g = root.child("gravity")) spec.gravity = g->as_vec3();
  spec.time_step = root["time_step"].as_number();
  if (!(spec.time_step > 0.0)) root["time_step"].fail("must be > 0");
  const std::string mode = root.string("mode", "free");
  if (mode != "free" && mode != "path") root["mode"].fail("expected 'free' or 'path'");
  spec.path_mode = mode == "path";
  if (spec.path_mode) {
    const auto path = root["path"];
    path.expect_only({"waypoints", "speed"});
    spec.waypoints = path["waypoints"].as_numbers();
    spec.drive_speed = path["speed"].as_number();
    if (spec.waypoints.empty()) path["waypoints"].fail("needs at least one overlap");
    if (!(spec.drive_speed > 0.0)) path["speed"].fail("must be > 0");
  } else if (root.has("steps")) {
    spec.steps = static_cast<long>(root["steps"].as_number());
  } else {
    spec.steps = std::lround(root["end_time"].as_number() / spec.time_step);
  }
  spec.output_every = static_cast<int>(root.number("output_every", 1));
  if (spec.output_every < 1) root["output_every"].fail("must be >= 1");
  return spec;
}

SingleContactSummary run_single_contact(
    const SingleContactSpec& spec, const std::function<void(const SingleContactSample&)>& sink) {
  sim::World w;
  w.gravity = spec.gravity;
  w.dt = spec.time_step;
  w.set_pair_law(0, 0, spec.law);
  add_body(w, spec.first, spec.first.fixed || spec.path_mode);
  if (spec.second) {
    add_body(w, *spec.second, spec.second->fixed || spec.path_mode);
  } else {
    w.walls.push_back(walls::make_wall("wall", walls::Plane{*spec.wall_point, spec.wall_normal}));
    w.set_wall_law(0, 0, spec.law);
  }

  SingleContactSummary sum;
  bool in_contact = false, had_contact = false;
  double vn_before = 0.0, t_start = 0.0;
  long step_index = 0;
  auto advance = [&]() {
    const double vn_prev = approach_speed(w, geometry(w).n);
    sim::step(w);
    ++step_index;
    const SingleContactSample s = sample(w);
    sum.max_overlap = std::max(sum.max_overlap, s.overlap);
    sum.max_force = std::max(sum.max_force, std::abs(s.fn));
    if (s.overlap > 0.0 && !in_contact && !had_contact) {
      in_contact = had_contact = true;
      vn_before = vn_prev;
      t_start = w.time - w.dt;
    } else if (s.overlap <= 0.0 && in_contact) {
      in_contact = false;
      if (!sum.contact_ended) {
        sum.contact_ended = true;
        sum.contact_duration = w.time - w.dt - t_start;
        const double vn_after = approach_speed(w, geometry(w).n);
        sum.restitution = vn_before != 0.0 ? -vn_after / vn_before : 0.0;
      }
    }
    if (sink && step_index % spec.output_every == 0) sink(s);
  };

  if (spec.path_mode) {
    // The second body (or the sphere, against the wall) is driven along the contact normal so the
    // overlap moves to each waypoint in turn at the drive speed.
    const std::size_t driven = spec.second ? 1 : 0;
    double current = geometry(w).overlap;
    for (double target : spec.waypoints) {
      const Vec3 n = geometry(w).n;
      const double direction = target > current ? 1.0 : -1.0;
      // Increasing the overlap means moving body 1 against n (or the sphere along n to the wall).
      w.particles.v[driven] =
          n * (spec.second ? -direction * spec.drive_speed : direction * spec.drive_speed);
      const long n_steps =
          std::lround(std::abs(target - current) / (spec.drive_speed * spec.time_step));
      for (long k = 0; k < n_steps; ++k) advance();
      current = target;
    }
  } else {
    for (long k = 0; k < spec.steps; ++k) advance();
  }
  for (std::size_t k = 0; k < w.particles.size(); ++k) {
    sum.final_position[k] = w.particles.x[k];
    sum.final_velocity[k] = w.particles.v[k];
    sum.final_angular_velocity[k] = w.particles.omega[k];
  }
  sum.steps = step_index;
  return sum;
}

std::vector<std::string> single_contact_columns() {
  std::vector<std::string> c{"time"};
  for (const char* q : {"x", "v", "w"})
    for (int b = 1; b <= 2; ++b)
      for (const char* a : {"x", "y", "z"})
        c.push_back(std::string(q) + std::to_string(b) + "_" + a);
  for (const char* q : {"overlap", "fn", "ft_x", "ft_y", "ft_z", "troll_x", "troll_y", "troll_z"})
    c.emplace_back(q);
  return c;
}

std::vector<double> single_contact_row(const SingleContactSample& s) {
  std::vector<double> r{s.time};
  for (const Vec3* q : {s.x, s.v, s.w})
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 3; ++a) r.push_back(q[b][a]);
  r.push_back(s.overlap);
  r.push_back(s.fn);
  for (const Vec3& v : {s.ft, s.rolling_torque})
    for (int a = 0; a < 3; ++a) r.push_back(v[a]);
  return r;
}

}  // namespace demcal::lab
