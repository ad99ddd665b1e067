#include "core/sim/forces.hpp"

#include <omp.h>

#include <algorithm>
#include <span>
#include <vector>

#include "core/sim/pair_input.hpp"

namespace demcal::sim {
namespace {

template <class N, class C, class T, class R>
struct TypedLaw {
  N n;
  C c;
  T t;
  R r;
  contact::PairOutput evaluate(const contact::PairInput& in, double* history) const {
    return contact::evaluate(n, c, t, r, in, history);
  }
};

template <class N, class C, class T, class R>
TypedLaw<N, C, T, R> typed(const contact::ContactLaw& law) {
  return {std::get<N>(law.normal), std::get<C>(law.cohesion), std::get<T>(law.tangential),
          std::get<R>(law.rolling)};
}

/// The largest k / m* of a thread's contacts (World::contact_rate2 and contact_stable_rate2):
/// kept in `accurate` for the normal models whose step resolves the stiffness in use, in
/// `stable` for those whose accuracy comes from a bound of their own (Hertz: the Rayleigh time).
struct Rates {
  double accurate = 0.0, stable = 0.0;
  template <class N>
  void add(double k_over_m) {
    double& rate = contact::normal::stiffness_sets_accuracy<N>() ? accurate : stable;
    rate = std::max(rate, k_over_m);
  }
};

/// A force and a torque, e.g. the particles' push on a wall.
struct Wrench {
  Vec3 force, torque;
  double stiffness = 0.0;  ///< sum of the contacts' normal stiffnesses (walls::Wall::stiffness)
};

/// Adds the contact forces of wall `wall_index` to the particles [lo, hi) and their reaction to
/// `on_wall`.
template <class N, class C, class T, class R>
void wall_kernel(World& w, std::size_t wall_index, int lo, int hi, Wrench& on_wall, Rates& rates,
                 const N&, const C&, const T&, const R&) {
  using Law = TypedLaw<N, C, T, R>;
  constexpr int kStride = contact::History<N, C, T, R>::kSize;
  walls::Wall& wall = w.walls[wall_index];
  std::vector<Law> laws;
  for (int m = 0; m < w.materials(); ++m)
    laws.push_back(typed<N, C, T, R>(w.wall_law(wall.material, m)));
  double range = 0.0;
  for (const auto& l : laws) range = std::max(range, l.c.range());

  auto& p = w.particles;
  double* hist = w.wall_history[wall_index].data();
  const double* inverse_mass = w.contact_inverse_mass();
  const walls::Mesh* mesh = std::get_if<walls::Mesh>(&wall.shape);
  // Only the particles that may touch the wall (World::wall_reach), those of [lo, hi).
  const World::WallReach& reach = w.wall_reach[wall_index];
  const std::vector<int>& near = reach.near;
  const auto first = std::lower_bound(near.begin(), near.end(), lo);
  const auto last = std::lower_bound(first, near.end(), hi);
  {
    Vec3 wf{}, wt{};
    double ks = 0.0;
    auto apply = [&](int i, const walls::WallGeometry& g, double* h) {
      contact::PairInput in;
      in.n = g.n;
      in.delta = g.delta;
      in.r_i = p.radius[i];
      in.r_j = 0.0;
      in.r_star = p.radius[i];
      in.m_star = p.mass[i];
      const Vec3 v_rel = p.v[i] - wall.velocity_at(g.point);
      in.vn = dot(v_rel, in.n);
      in.vt = v_rel - in.n * in.vn + cross(p.omega[i] * p.radius[i], in.n);
      in.w_rel = p.omega[i] - wall.omega;
      in.dt = w.dt;
      const contact::PairOutput out = laws[p.material[i]].evaluate(in, h);
      if (out.stiffness > 0.0)
        rates.add<N>(out.stiffness * (inverse_mass ? inverse_mass[i] : 1.0 / in.m_star));
      p.f[i] += out.force;
      p.torque[i] += out.torque_i;
      wf -= out.force;
      wt += cross(g.point - wall.pivot, -out.force) + out.torque_j;
      ks += out.stiffness;
    };
    if (!mesh) {
      // Plane, cylinder, disk: at most one contact per particle, one history per particle; the
      // loop is compiled for the wall's shape.
      std::visit(
          [&](const auto& shape) {
            if constexpr (!std::is_same_v<std::decay_t<decltype(shape)>, walls::Mesh>) {
              for (auto it = first; it != last; ++it) {
                const int i = *it;
                double* h = hist + static_cast<std::ptrdiff_t>(i) * kStride;
                walls::WallGeometry g;
                if (!walls::primitive_geometry(shape, p.x[i], p.radius[i], range, g)) {
                  contact::clear_history<kStride>(h);
                  continue;
                }
                apply(i, g, h);
              }
            }
          },
          wall.shape);
    } else {
      // Mesh: up to kMaxContacts contacts per particle, each continuing the history slot whose
      // last normal is nearest its own (within 45 deg), so a contact keeps its tangential spring
      // while it slides across triangles of one surface or rolls round an edge (mesh.hpp).
      // Slot layout: [law history (kStride) | last normal (3)]; a zero normal marks a free slot.
      constexpr int kSlots = walls::Mesh::kMaxContacts;
      constexpr int kSlot = kStride + 3;
      constexpr double kSameContact = 0.7071;
      for (auto it = first; it != last; ++it) {
        const int i = *it;
        double* h = hist + static_cast<std::ptrdiff_t>(i) * kSlots * kSlot;
        walls::WallGeometry g[kSlots];
        // Its triangles within reach, listed with it (World::WallReach::triangles).
        const auto at = static_cast<std::size_t>(it - near.begin());
        const std::span<const int> candidates(
            reach.triangles.data() + reach.triangle_start[at],
            static_cast<std::size_t>(reach.triangle_start[at + 1] - reach.triangle_start[at]));
        const int found = walls::mesh_contacts(*mesh, candidates, p.x[i], p.radius[i], range, g);
        bool used[kSlots] = {};
        int slot_of[kSlots];
        for (int c = 0; c < found; ++c) {
          int best = -1;
          double best_dot = kSameContact;
          for (int s = 0; s < kSlots; ++s) {
            if (used[s]) continue;
            const double* hn = h + s * kSlot + kStride;
            const double d = hn[0] * g[c].n.x + hn[1] * g[c].n.y + hn[2] * g[c].n.z;
            if (d > best_dot) {
              best_dot = d;
              best = s;
            }
          }
          slot_of[c] = best;
          if (best >= 0) used[best] = true;
        }
        // New contacts take free slots (a slot not continued this step starts afresh).
        for (int c = 0; c < found; ++c) {
          if (slot_of[c] >= 0) continue;
          for (int s = 0; s < kSlots; ++s)
            if (!used[s]) {
              slot_of[c] = s;
              used[s] = true;
              for (int k = 0; k < kStride; ++k) h[s * kSlot + k] = 0.0;
              break;
            }
        }
        for (int s = 0; s < kSlots; ++s)
          if (!used[s]) contact::clear_history<kSlot>(h + s * kSlot);
        for (int c = 0; c < found; ++c) {
          double* hs = h + slot_of[c] * kSlot;
          hs[kStride] = g[c].n.x;
          hs[kStride + 1] = g[c].n.y;
          hs[kStride + 2] = g[c].n.z;
          apply(i, g[c], hs);
        }
      }
    }
    on_wall = {wf, wt, ks};
  }
}

void add_wall_forces(World& w, std::size_t k, int lo, int hi, Wrench& on_wall, Rates& rates) {
  const int m0 = w.particles.material[0];
  contact::visit(w.wall_law(w.walls[k].material, m0),
                 [&](const auto& n, const auto& c, const auto& t, const auto& r) {
                   wall_kernel(w, k, lo, hi, on_wall, rates, n, c, t, r);
                 });
}

/// The wall's force, torque and contact stiffness: the threads' parts in thread order.
void sum_wall_wrench(walls::Wall& wall, const std::vector<Wrench>& parts) {
  wall.force = {};
  wall.torque = {};
  wall.stiffness = 0.0;
  for (const Wrench& part : parts) {
    wall.force += part.force;
    wall.torque += part.torque;
    wall.stiffness += part.stiffness;
  }
}

/// The force region: every thread resets and sums the forces of the particles it owns (pairs,
/// then walls), then runs `after` on them.
template <class N, class C, class T, class R>
void force_region(World& w, const OwnedRangeTask& after, const N&, const C&, const T&, const R&) {
  using Law = TypedLaw<N, C, T, R>;
  constexpr int kStride = contact::History<N, C, T, R>::kSize;
  const int n_mat = w.materials();
  std::vector<Law> laws;
  laws.reserve(n_mat * n_mat);
  for (int a = 0; a < n_mat; ++a)
    for (int b = 0; b < n_mat; ++b) laws.push_back(typed<N, C, T, R>(w.pair_law(a, b)));
  const double range = w.interaction_range();

  auto& p = w.particles;
  const auto& start = w.list.row_start;
  const auto& nbr = w.list.nbr;
  double* hist = w.pair_history.data();
  const MinimumImage image(w.domain);
  const bool periodic = w.domain.any_periodic();
  const double dt = w.dt;
  const int threads = w.active_threads();
  // Each wall's force and torque, per thread, summed in thread order after the region.
  std::vector<std::vector<Wrench>> on_walls(w.walls.size(), std::vector<Wrench>(threads));
  // Each thread's largest k / m* of its contacts.
  std::vector<Rates> rates(threads);
  const double* inverse_mass = w.contact_inverse_mass();

  if (static_cast<int>(w.deferred.size()) != threads) w.deferred.assign(threads, {});

    // Each thread owns a contiguous range of particles and evaluates the pairs of its rows. A pair
    // force on a partner j inside the own range is added directly; one on a partner owned by a
    // later thread is deferred and added after the loop, in thread order. No two threads write the
    // same particle, and the order of every sum is fixed for a given thread count.
#pragma omp parallel num_threads(threads)
  {
    const int tid = omp_get_thread_num();
    const auto [lo, hi] = w.owned_range(tid);
    auto& deferred = w.deferred[tid];
    deferred.clear();
    Rates rate;
    for (int i = lo; i < hi; ++i) {
      // A clump's weight acts at its centre of mass (rigid_body.hpp), not through its members.
      p.f[i] = p.motion[i] == particles::Motion::kClumpMember ? Vec3{} : w.gravity * p.mass[i];
      p.torque[i] = {};
    }
    for (int i = lo; i < hi; ++i) {
      const Vec3 xi = p.x[i], vi = p.v[i], wi = p.omega[i];
      const double ri = p.radius[i], mi = p.mass[i];
      const Law* law_row = &laws[p.material[i] * n_mat];
      Vec3 fi{}, ti{};
      for (int k = start[i]; k < start[i + 1]; ++k) {
        const int j = nbr[k];
        double* h = hist + static_cast<std::ptrdiff_t>(k) * kStride;
        const Vec3 d = periodic ? image(p.x[j] - xi) : p.x[j] - xi;
        const double rj = p.radius[j];
        const double reach = ri + rj + range;
        const double dist2 = norm2(d);
        if (dist2 >= reach * reach) {
          contact::clear_history<kStride>(h);
          continue;
        }
        const contact::PairInput in = particle_pair_input(
            d, std::sqrt(dist2), ri, rj, mi, p.mass[j], vi, p.v[j], wi, p.omega[j], dt);
        const contact::PairOutput out = law_row[p.material[j]].evaluate(in, h);
        if (out.stiffness > 0.0)
          rate.add<N>(out.stiffness *
                      (inverse_mass ? inverse_mass[i] + inverse_mass[j] : 1.0 / in.m_star));
        fi += out.force;
        ti += out.torque_i;
        if (j < hi) {
          p.f[j] -= out.force;
          p.torque[j] += out.torque_j;
        } else {
          deferred.push_back({j, -out.force, out.torque_j});
        }
      }
      p.f[i] += fi;
      p.torque[i] += ti;
    }
#pragma omp barrier
    for (int b = 0; b < tid; ++b)
      for (const auto& c : w.deferred[b])
        if (c.particle >= lo && c.particle < hi) {
          p.f[c.particle] += c.force;
          p.torque[c.particle] += c.torque;
        }
    for (std::size_t k = 0; k < w.walls.size(); ++k)
      add_wall_forces(w, k, lo, hi, on_walls[k][tid], rate);
    rates[tid] = rate;
    if (after) after(lo, hi);
  }
  for (std::size_t k = 0; k < w.walls.size(); ++k) sum_wall_wrench(w.walls[k], on_walls[k]);
  w.contact_rate2 = w.contact_stable_rate2 = 0.0;
  for (const Rates& r : rates) {
    w.contact_rate2 = std::max(w.contact_rate2, r.accurate);
    w.contact_stable_rate2 = std::max(w.contact_stable_rate2, r.stable);
  }
}

}  // namespace

void compute_forces(World& world, const OwnedRangeTask& after) {
  if (world.particles.size() == 0) {
    for (auto& wall : world.walls) {
      wall.force = wall.torque = {};
      wall.stiffness = 0.0;
    }
    world.contact_rate2 = world.contact_stable_rate2 = 0.0;
    return;
  }
  world.refresh_wall_reach();
  contact::visit(world.pair_law(0, 0),
                 [&](const auto& n, const auto& c, const auto& t, const auto& r) {
                   force_region(world, after, n, c, t, r);
                 });
}

}  // namespace demcal::sim
