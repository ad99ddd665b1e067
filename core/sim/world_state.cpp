// A world's state as one flat record (World::save_state / restore_state), for checkpoints.
#include <cstring>

#include "core/common/bytes.hpp"
#include "core/sim/world.hpp"

namespace demcal::sim {
namespace {

constexpr char kMagic[] = "demcal-world-state";
constexpr std::uint32_t kVersion = 1;

void put_shape(ByteWriter& out, const walls::Shape& shape) {
  out.put<std::uint8_t>(static_cast<std::uint8_t>(shape.index()));
  std::visit(
      [&](const auto& s) {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, walls::Mesh>) {
          out.put(s.vertices);
          out.put(s.triangles);
          out.put(s.lo);
          out.put(s.hi);
          out.put(s.fitted);
        } else {
          out.put(s);
        }
      },
      shape);
}

walls::Shape get_shape(ByteReader& in) {
  switch (in.get<std::uint8_t>()) {
    case 0:
      return in.get<walls::Plane>();
    case 1:
      return in.get<walls::Cylinder>();
    case 2:
      return in.get<walls::Disk>();
    case 3: {
      walls::Mesh m;
      in.get(m.vertices);
      in.get(m.triangles);
      in.get(m.lo);
      in.get(m.hi);
      in.get(m.fitted);
      return m;
    }
    default:
      throw InputError("checkpoint", "unknown wall shape");
  }
}

void put_particles(ByteWriter& out, const particles::ParticleStore& p) {
  out.put(p.x);
  out.put(p.v);
  out.put(p.omega);
  out.put(p.f);
  out.put(p.torque);
  out.put(p.radius);
  out.put(p.mass);
  out.put(p.inertia);
  out.put(p.inv_mass);
  out.put(p.inv_inertia);
  out.put(p.material);
  out.put(p.motion);
  out.put(p.body);
  out.put(p.body_offset);
  const auto& c = p.clumps;
  out.put(c.first);
  out.put(c.count);
  out.put(c.x);
  out.put(c.v);
  out.put(c.omega);
  out.put(c.angular_momentum);
  out.put(c.q);
  out.put(c.mass);
  out.put(c.inertia);
  out.put(c.volume_weight);
  out.put(c.parked);
}

void get_particles(ByteReader& in, particles::ParticleStore& p) {
  in.get(p.x);
  in.get(p.v);
  in.get(p.omega);
  in.get(p.f);
  in.get(p.torque);
  in.get(p.radius);
  in.get(p.mass);
  in.get(p.inertia);
  in.get(p.inv_mass);
  in.get(p.inv_inertia);
  in.get(p.material);
  in.get(p.motion);
  in.get(p.body);
  in.get(p.body_offset);
  auto& c = p.clumps;
  in.get(c.first);
  in.get(c.count);
  in.get(c.x);
  in.get(c.v);
  in.get(c.omega);
  in.get(c.angular_momentum);
  in.get(c.q);
  in.get(c.mass);
  in.get(c.inertia);
  in.get(c.volume_weight);
  in.get(c.parked);
}

void put_wall(ByteWriter& out, const walls::Wall& w) {
  out.put(w.name);
  put_shape(out, w.shape);
  out.put(w.material);
  out.put(w.velocity);
  out.put(w.omega);
  out.put(w.pivot);
  out.put(w.force);
  out.put(w.torque);
  out.put(w.displacement);
}

walls::Wall get_wall(ByteReader& in) {
  walls::Wall w;
  in.get(w.name);
  w.shape = get_shape(in);
  in.get(w.material);
  in.get(w.velocity);
  in.get(w.omega);
  in.get(w.pivot);
  in.get(w.force);
  in.get(w.torque);
  in.get(w.displacement);
  return w;
}

void put_frames(ByteWriter& out, const integrate::ClumpFrames& f) {
  out.put(f.q);
  out.put(f.rotation);
  out.put(f.inv_inertia);
  out.put(f.force);
  out.put(f.torque);
  out.put(f.has_wrench);
  out.put(f.gravity);
}

void get_frames(ByteReader& in, integrate::ClumpFrames& f) {
  in.get(f.q);
  in.get(f.rotation);
  in.get(f.inv_inertia);
  in.get(f.force);
  in.get(f.torque);
  in.get(f.has_wrench);
  in.get(f.gravity);
  f.q_mid.resize(f.q.size());
}

/// What the saving run's laws were like: a resuming run with other laws cannot go on from it.
struct LawShape {
  std::int32_t materials = 0, pair_stride = 0;
  bool operator==(const LawShape&) const = default;
};

}  // namespace

std::string World::state_mismatch() const {
  const std::size_t n = particles.size();
  const auto& p = particles;
  for (std::size_t size : {p.v.size(), p.omega.size(), p.f.size(), p.torque.size(), p.radius.size(),
                           p.mass.size(), p.inertia.size(), p.inv_mass.size(), p.inv_inertia.size(),
                           p.material.size(), p.motion.size(), p.body.size(), p.body_offset.size()})
    if (size != n) return "particle arrays of different lengths";
  if (!prepared_) return {};  // prepare() makes the rest anew
  if (list.row_start.size() != n + 1 || list.row_start.back() != static_cast<int>(list.pairs()) ||
      pair_history.size() != list.pairs() * static_cast<std::size_t>(pair_stride_))
    return "neighbour list and contact history do not fit the particles";
  for (int j : list.nbr)
    if (j < 0 || static_cast<std::size_t>(j) >= n) return "a listed partner is no particle";
  if (wall_strides_.size() != walls.size() || wall_history.size() != walls.size() ||
      wall_reach.size() > walls.size())
    return "wall histories do not fit the walls";
  for (std::size_t k = 0; k < walls.size(); ++k)
    if (wall_history[k].size() != n * static_cast<std::size_t>(wall_strides_[k]))
      return "a wall history does not fit the particles";
  for (const auto& r : wall_reach)
    for (int i : r.near)
      if (i < 0 || static_cast<std::size_t>(i) >= n) return "a wall lists no particle";
  return {};
}

std::string World::save_state() const {
  ByteWriter out;
  out.put(std::string(kMagic));
  out.put(kVersion);
  out.put(LawShape{n_materials_, pair_stride_});
  put_particles(out, particles);
  out.put<std::uint64_t>(walls.size());
  for (const auto& w : walls) put_wall(out, w);
  out.put(domain);
  out.put(gravity);
  out.put(dt);
  out.put(adaptive_safety);
  out.put(skin);
  out.put(time);
  out.put(step_count);
  out.put(wall_strides_);
  out.put(skin_);
  out.put(prepared_);
  list.save(out);
  out.put(pair_history);
  out.put<std::uint64_t>(wall_history.size());
  for (const auto& h : wall_history) out.put(h);
  out.put<std::uint64_t>(wall_reach.size());
  for (const auto& r : wall_reach) {
    out.put(r.near);
    put_shape(out, r.shape);
    out.put(r.range);
    out.put(r.extent);
    out.put(r.valid);
  }
  put_frames(out, clump_frames);
  return out.take();
}

void World::restore_state(std::string_view state) {
  ByteReader in(state, "checkpoint");
  std::string magic;
  in.get(magic);
  if (magic != kMagic) throw InputError("checkpoint", "not a demcal world state");
  if (const auto version = in.get<std::uint32_t>(); version != kVersion)
    throw InputError("checkpoint", "format version " + std::to_string(version) +
                                       ", this build reads " + std::to_string(kVersion));
  const auto laws = in.get<LawShape>();
  if (!(laws == LawShape{n_materials_, pair_laws_.empty() ? 0 : pair_laws_[0].history_size()}))
    throw InputError("checkpoint", "made with other contact laws than this run's");
  // Read into a copy: a damaged record leaves this world as it was. Every count read below is
  // bounded by the bytes left, as each element takes some.
  World w = *this;
  w.pair_stride_ = laws.pair_stride;
  get_particles(in, w.particles);
  w.walls.clear();
  for (auto n = in.get<std::uint64_t>(); n > 0; --n) w.walls.push_back(get_wall(in));
  in.get(w.domain);
  in.get(w.gravity);
  in.get(w.dt);
  in.get(w.adaptive_safety);
  in.get(w.skin);
  in.get(w.time);
  in.get(w.step_count);
  in.get(w.wall_strides_);
  in.get(w.skin_);
  in.get(w.prepared_);
  w.list.restore(in);
  in.get(w.pair_history);
  w.wall_history.clear();
  for (auto n = in.get<std::uint64_t>(); n > 0; --n) in.get(w.wall_history.emplace_back());
  w.wall_reach.clear();
  for (auto n = in.get<std::uint64_t>(); n > 0; --n) {
    WallReach& r = w.wall_reach.emplace_back();
    in.get(r.near);
    r.shape = get_shape(in);
    in.get(r.range);
    in.get(r.extent);
    in.get(r.valid);
  }
  get_frames(in, w.clump_frames);
  in.expect_end();
  if (const std::string why = w.state_mismatch(); !why.empty()) throw InputError("checkpoint", why);
  w.deferred.clear();
  *this = std::move(w);
}

}  // namespace demcal::sim
