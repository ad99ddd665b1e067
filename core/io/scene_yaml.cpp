#include "core/io/scene_yaml.hpp"

#include <filesystem>

#include "core/common/rng.hpp"
#include "core/io/contact_law_yaml.hpp"
#include "core/io/liggghts_data.hpp"
#include "core/io/stl.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::io {
namespace {

/// A path from the scene, relative to the scene file's folder unless absolute.
std::string scene_path(const YamlNode& n) {
  const std::filesystem::path p = n.as_string();
  if (p.is_absolute() || !std::filesystem::exists(n.file())) return p.string();
  return (std::filesystem::path(n.file()).parent_path() / p).string();
}

walls::Shape read_shape(const YamlNode& n) {
  if (auto p = n.child("plane")) {
    p->expect_only({"point", "normal"});
    return walls::Plane{(*p)["point"].as_vec3(), normalized((*p)["normal"].as_vec3())};
  }
  if (auto c = n.child("cylinder")) {
    c->expect_only({"point", "axis", "radius", "lo", "hi"});
    walls::Cylinder cyl{(*c)["point"].as_vec3(), normalized((*c)["axis"].as_vec3()),
                        (*c)["radius"].as_number()};
    cyl.lo = c->number("lo", -walls::kInfinity);
    cyl.hi = c->number("hi", walls::kInfinity);
    return cyl;
  }
  if (auto d = n.child("disk")) {
    d->expect_only({"centre", "normal", "radius"});
    return walls::Disk{(*d)["centre"].as_vec3(), normalized((*d)["normal"].as_vec3()),
                       (*d)["radius"].as_number()};
  }
  if (auto m = n.child("mesh")) {
    m->expect_only({"stl", "scale"});
    return read_stl(scene_path((*m)["stl"]), m->number("scale", 1.0));
  }
  n.fail("a wall needs one of: plane, cylinder, disk, mesh");
}

walls::Wall read_wall(const YamlNode& n) {
  n.expect_only(
      {"name", "plane", "cylinder", "disk", "mesh", "velocity", "angular_velocity", "pivot"});
  walls::Wall w = walls::make_wall(n["name"].as_string(), read_shape(n));
  if (auto v = n.child("velocity")) w.velocity = v->as_vec3();
  if (auto o = n.child("angular_velocity")) w.omega = o->as_vec3();
  if (auto p = n.child("pivot")) w.pivot = p->as_vec3();
  return w;
}

particles::Region read_region(const YamlNode& n) {
  if (auto b = n.child("box")) {
    b->expect_only({"lo", "hi"});
    return particles::BoxRegion{(*b)["lo"].as_vec3(), (*b)["hi"].as_vec3()};
  }
  if (auto c = n.child("cylinder")) {
    c->expect_only({"centre", "radius", "z_lo", "z_hi"});
    return particles::CylinderRegion{(*c)["centre"].as_vec3(), (*c)["radius"].as_number(),
                                     (*c)["z_lo"].as_number(), (*c)["z_hi"].as_number()};
  }
  n.fail("a region needs one of: box, cylinder");
}

void read_particles(const YamlNode& n, sim::World& world, double density, Rng& rng) {
  n.expect_only({"lattice", "random", "list", "data_file"});
  if (auto file = n.child("data_file")) {
    read_liggghts_data(scene_path(*file), world.particles);
  } else if (auto list = n.child("list")) {
    for (const auto& item : list->items()) {
      item.expect_only({"radius", "position", "velocity", "angular_velocity", "density"});
      const double r = item["radius"].as_number();
      if (!(r > 0.0)) item["radius"].fail("must be > 0");
      const auto i = world.particles.add_sphere(item["position"].as_vec3(), r,
                                                item.number("density", density), 0);
      if (auto v = item.child("velocity")) world.particles.v[i] = v->as_vec3();
      if (auto w = item.child("angular_velocity")) world.particles.omega[i] = w->as_vec3();
    }
  } else if (auto l = n.child("lattice")) {
    l->expect_only({"origin", "spacing", "counts", "radius", "jitter"});
    const auto counts = (*l)["counts"].as_numbers();
    if (counts.size() != 3) (*l)["counts"].fail("expected 3 counts");
    particles::insert_lattice(
        world.particles, (*l)["origin"].as_vec3(), (*l)["spacing"].as_number(),
        static_cast<int>(counts[0]), static_cast<int>(counts[1]), static_cast<int>(counts[2]),
        (*l)["radius"].as_number(), density, 0, l->number("jitter", 0.0), rng);
  } else if (auto r = n.child("random")) {
    r->expect_only({"region", "count", "sizes", "gap"});
    particles::InsertRequest req;
    req.region = read_region((*r)["region"]);
    req.count = static_cast<std::size_t>((*r)["count"].as_number());
    req.sizes = read_size_distribution((*r)["sizes"]);
    req.density = density;
    req.gap = r->number("gap", 0.0);
    sim::insert_random(world, req, rng);
  } else {
    n.fail("particles need one of: lattice, random, list, data_file");
  }
}

}  // namespace

particles::SizeDistribution read_size_distribution(const YamlNode& n) {
  particles::SizeDistribution d;
  if (auto m = n.child("monodisperse")) {
    m->expect_only({"radius"});
    d = particles::Monodisperse{(*m)["radius"].as_number()};
  } else if (auto c = n.child("discrete")) {
    c->expect_only({"radii", "mass_fractions"});
    d = particles::DiscreteClasses{(*c)["radii"].as_numbers(), (*c)["mass_fractions"].as_numbers()};
  } else if (auto l = n.child("lognormal")) {
    l->expect_only({"median_radius", "sigma_g", "truncate_k"});
    d = particles::LogNormal{(*l)["median_radius"].as_number(), (*l)["sigma_g"].as_number(),
                             l->number("truncate_k", 2.5)};
  } else {
    n.fail("sizes need one of: monodisperse, discrete, lognormal");
  }
  particles::validate(d, n.where());
  return d;
}

Scene read_scene(const YamlNode& root) {
  root.expect_only({"threads", "particles_per_thread", "seed", "time_step", "time_step_safety",
                    "skin", "gravity", "domain", "density", "contact_law", "wall_contact_law",
                    "walls", "particles", "phases"});
  Scene scene;
  sim::World& w = scene.world;
  w.threads = static_cast<int>(root.number("threads", 1));
  if (w.threads < 1) root["threads"].fail("must be >= 1");
  const double per_thread = root.number("particles_per_thread", sim::World::kParticlesPerThread);
  if (!(per_thread >= 1 && per_thread <= 1e9))
    root["particles_per_thread"].fail("must be in [1, 1e9]");
  w.particles_per_thread = static_cast<int>(per_thread);
  Rng rng(static_cast<std::uint64_t>(root.number("seed", 1)));
  w.skin = root.number("skin", 0.0);
  if (auto g = root.child("gravity")) w.gravity = g->as_vec3();
  if (auto d = root.child("domain")) {
    d->expect_only({"lo", "hi", "periodic"});
    w.domain.lo = (*d)["lo"].as_vec3();
    w.domain.hi = (*d)["hi"].as_vec3();
    if (auto p = d->child("periodic")) {
      const auto items = p->items();
      if (items.size() != 3) p->fail("expected 3 booleans");
      for (int k = 0; k < 3; ++k) w.domain.periodic[k] = items[k].as_bool();
    }
  }
  const double density = root["density"].as_number();
  if (!(density > 0.0)) root["density"].fail("must be > 0");
  const auto law = read_contact_law(root["contact_law"]);
  w.set_pair_law(0, 0, law);
  const auto wall_law =
      root.has("wall_contact_law") ? read_contact_law(root["wall_contact_law"]) : law;
  if (auto walls = root.child("walls"))
    for (const auto& item : walls->items()) {
      w.walls.push_back(read_wall(item));
      w.set_wall_law(0, 0, wall_law);
    }
  read_particles(root["particles"], w, density, rng);
  if (root.has("time_step")) {
    w.dt = root["time_step"].as_number();
  } else {
    w.dt = sim::recommended_time_step(w, root.number("time_step_safety", 0.2));
  }
  for (const auto& item : root["phases"].items()) {
    item.expect_only({"name", "steps", "record_every"});
    scene.phases.push_back({item["name"].as_string(), static_cast<long>(item["steps"].as_number()),
                            static_cast<long>(item.number("record_every", 0))});
    if (scene.phases.back().record_every < 0) item["record_every"].fail("must be >= 0");
  }
  return scene;
}

}  // namespace demcal::io
