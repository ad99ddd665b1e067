// A world's state as one flat record (World::save_state / restore_state), for checkpoints.
#include <cstring>

#include "core/common/bytes.hpp"
#include "core/sim/health.hpp"
#include "core/sim/world.hpp"

namespace demcal::sim {
namespace {

constexpr char kMagic[] = "demcal-world-state";
constexpr std::uint32_t kVersion = 1;

/// The fields of a mesh, a particle store, a wall and the clumps' frames, in record order, each
/// handed to `a.field` (ByteWriter to save, ByteReader to restore).
template <class A, class M>
void mesh_fields(A& a, M& m) {
  a.field(m.vertices);
  a.field(m.triangles);
  a.field(m.lo);
  a.field(m.hi);
  a.field(m.fitted);
}

template <class A, class P>
void particle_fields(A& a, P& p) {
  for (auto* v : {&p.x, &p.v, &p.omega, &p.f, &p.torque, &p.body_offset}) a.field(*v);
  for (auto* v : {&p.radius, &p.mass, &p.inertia, &p.inv_mass, &p.inv_inertia}) a.field(*v);
  a.field(p.material);
  a.field(p.motion);
  a.field(p.body);
  auto& c = p.clumps;
  a.field(c.first);
  a.field(c.count);
  for (auto* v : {&c.x, &c.v, &c.omega, &c.angular_momentum, &c.inertia}) a.field(*v);
  a.field(c.q);
  a.field(c.mass);
  a.field(c.volume_weight);
  a.field(c.parked);
}

template <class A, class W>
void wall_fields(A& a, W& w) {
  a.field(w.name);
  a.field(w.material);
  for (auto* v : {&w.velocity, &w.omega, &w.pivot, &w.force, &w.torque, &w.displacement})
    a.field(*v);
}

template <class A, class F>
void frame_fields(A& a, F& f) {
  a.field(f.q);
  a.field(f.rotation);
  for (auto* v : {&f.inv_inertia, &f.force, &f.torque}) a.field(*v);
  a.field(f.has_wrench);
  a.field(f.gravity);
}

/// A wall shape in a record: its alternative's index, then the shape (a mesh field by field).
void shape_field(ByteWriter& out, const walls::Shape& shape) {
  out.put<std::uint8_t>(static_cast<std::uint8_t>(shape.index()));
  std::visit(
      [&](const auto& s) {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, walls::Mesh>)
          mesh_fields(out, s);
        else
          out.put(s);
      },
      shape);
}

void shape_field(ByteReader& in, walls::Shape& shape) {
  switch (in.get<std::uint8_t>()) {
    case 0:
      shape = in.get<walls::Plane>();
      return;
    case 1:
      shape = in.get<walls::Cylinder>();
      return;
    case 2:
      shape = in.get<walls::Disk>();
      return;
    case 3: {
      walls::Mesh m;
      mesh_fields(in, m);
      shape = std::move(m);
      return;
    }
    default:
      throw InputError("checkpoint", "unknown wall shape");
  }
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

template <class A, class W>
void World::state_fields(A& a, W& w) {
  particle_fields(a, w.particles);
  a.each(w.walls, [&a](auto& wall) {
    shape_field(a, wall.shape);
    wall_fields(a, wall);
  });
  a.field(w.domain);
  a.field(w.gravity);
  a.field(w.dt);
  a.field(w.adaptive_safety);
  a.field(w.skin);
  a.field(w.time);
  a.field(w.step_count);
  a.field(w.wall_strides_);
  a.field(w.skin_);
  a.field(w.prepared_);
  a.field(w.list);
  a.field(w.pair_history);
  a.field(w.wall_history);
  a.each(w.wall_reach, [&a](auto& r) {
    a.field(r.near);
    shape_field(a, r.shape);
    a.field(r.range);
    a.field(r.extent);
    a.field(r.valid);
  });
  frame_fields(a, w.clump_frames);
}

std::string World::save_state() const {
  ByteWriter out;
  out.put(std::string(kMagic));
  out.put(kVersion);
  out.put(LawShape{n_materials_, pair_stride_});
  state_fields(out, *this);
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
  // Read into a copy: a damaged record leaves this world as it was. Every count read is bounded
  // by the bytes left, as each element takes some.
  World w = *this;
  w.pair_stride_ = laws.pair_stride;
  state_fields(in, w);
  w.clump_frames.q_mid.resize(w.clump_frames.q.size());
  in.expect_end();
  if (const std::string why = w.state_mismatch(); !why.empty()) throw InputError("checkpoint", why);
  w.deferred.clear();
  w.balance_owners();
  w.set_contact_masses();
  // The record was prepared by the run that wrote it, perhaps under a build that did not refuse
  // its laws: they are checked as a fresh world's are when it is prepared.
  check_contact_range(w);
  *this = std::move(w);
}

}  // namespace demcal::sim
