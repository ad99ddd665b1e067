#include "core/sim/world.hpp"

#include <algorithm>

#include "core/common/error.hpp"
#include "core/sim/forces.hpp"
#include "core/sim/health.hpp"
#include "core/sim/time_step.hpp"
#include "core/walls/reach.hpp"

namespace demcal::sim {
namespace {

/// The variant indices of the four slots: laws that share them share one compiled kernel.
std::array<std::size_t, 4> composition(const contact::ContactLaw& law) {
  return {law.normal.index(), law.cohesion.index(), law.tangential.index(), law.rolling.index()};
}

}  // namespace

void World::grow_law_tables(int n) {
  if (n <= n_materials_) return;
  std::vector<contact::ContactLaw> laws(static_cast<std::size_t>(n) * n);
  std::vector<bool> set(static_cast<std::size_t>(n) * n, false);
  for (int a = 0; a < n_materials_; ++a)
    for (int b = 0; b < n_materials_; ++b) {
      laws[a * n + b] = pair_laws_[a * n_materials_ + b];
      set[a * n + b] = pair_set_[a * n_materials_ + b];
    }
  pair_laws_.swap(laws);
  pair_set_.swap(set);
  for (auto& row : wall_laws_) row.resize(n);
  for (auto& row : wall_set_) row.resize(n, false);
  n_materials_ = n;
}

void World::set_pair_law(int a, int b, const contact::ContactLaw& law) {
  grow_law_tables(std::max(a, b) + 1);
  pair_laws_[a * n_materials_ + b] = law;
  pair_laws_[b * n_materials_ + a] = law;
  pair_set_[a * n_materials_ + b] = pair_set_[b * n_materials_ + a] = true;
  prepared_ = false;
}

void World::set_wall_law(int wall_material, int particle_material, const contact::ContactLaw& law) {
  grow_law_tables(particle_material + 1);
  if (wall_material >= static_cast<int>(wall_laws_.size())) {
    wall_laws_.resize(wall_material + 1, std::vector<contact::ContactLaw>(n_materials_));
    wall_set_.resize(wall_material + 1, std::vector<bool>(n_materials_, false));
  }
  wall_laws_[wall_material][particle_material] = law;
  wall_set_[wall_material][particle_material] = true;
  prepared_ = false;
}

void World::change_pair_law(int a, int b, const contact::ContactLaw& law) {
  if (!prepared_ || composition(law) != composition(pair_law(a, b))) {
    set_pair_law(a, b, law);
    return;
  }
  pair_laws_[a * n_materials_ + b] = law;
  pair_laws_[b * n_materials_ + a] = law;
  check_time_step(*this);
  check_contact_range(*this);
  rebuild_list();
}

void World::change_wall_law(int wall_material, int particle_material,
                            const contact::ContactLaw& law) {
  if (!prepared_ || wall_material >= static_cast<int>(wall_laws_.size()) ||
      particle_material >= n_materials_ || !wall_set_[wall_material][particle_material] ||
      composition(law) != composition(wall_law(wall_material, particle_material))) {
    set_wall_law(wall_material, particle_material, law);
    return;
  }
  wall_laws_[wall_material][particle_material] = law;
  check_time_step(*this);
  // The new law's reach beyond contact may differ: list the walls' particles again.
  for (auto& reach : wall_reach) reach.valid = false;
}

void World::rebuild_list() {
  for (auto& x : particles.x) domain.wrap(x);
  list.build(particles.x, particles.radius, domain, interaction_range() + skin_, active_threads(),
             pair_history, pair_stride_, clump_bodies());
  for (auto& reach : wall_reach) reach.valid = false;
  balance_owners();
}

void World::balance_owners() {
  const int active = active_threads();
  const int n = static_cast<int>(particles.size());
  owner_bounds_.assign(active + 1, n);
  owner_bounds_[0] = 0;
  if (active == 1) return;
  // The work of each particle, summed along the index order (a particle without a list row yet
  // has its own cost only); thread t starts at the first particle with at least t / active of
  // the total before it.
  const bool rows = list.row_start.size() == particles.size() + 1;
  const double range = interaction_range();
  const MinimumImage image(domain);
  std::vector<long> before(n + 1, 0);
  for (int i = 0; i < n; ++i) {
    long work = kOwnerRowCost;
    const int first = rows ? list.row_start[i] : 0, last = rows ? list.row_start[i + 1] : 0;
    for (int k = first; k < last; ++k) {
      const int j = list.nbr[k];
      const double reach = particles.radius[i] + particles.radius[j] + range;
      work += norm2(image(particles.x[j] - particles.x[i])) < reach * reach ? kOwnerContactCost : 1;
    }
    before[i + 1] = before[i] + work;
  }
  int i = 0;
  for (int t = 1; t < active; ++t) {
    const long share = before[n] * t / active;
    while (i < n && before[i] < share) ++i;
    owner_bounds_[t] = i;
  }
}

namespace {

/// Lists the triangles of `mesh` each particle of reach.near may touch before it or the mesh
/// moves by `margin` (WallReach::triangles).
void list_triangles(const walls::Mesh& mesh, const particles::ParticleStore& particles,
                    double range, double margin, World::WallReach& reach) {
  reach.triangle_start.assign(1, 0);
  reach.triangles.clear();
  for (const int i : reach.near) {
    walls::mesh_candidates(mesh, particles.x[i], particles.radius[i] + range + margin,
                           reach.triangles);
    reach.triangle_start.push_back(static_cast<int>(reach.triangles.size()));
  }
}

}  // namespace

void World::refresh_wall_reach() {
  if (wall_reach.size() != walls.size()) wall_reach.assign(walls.size(), {});
  const double margin = 1.5 * skin_;
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const walls::Wall& wall = walls[k];
    WallReach& reach = wall_reach[k];
    double range = 0.0;
    for (int m = 0; m < n_materials_; ++m)
      range = std::max(range, wall_law(wall.material, m).range());
    const walls::Mesh* mesh = std::get_if<walls::Mesh>(&wall.shape);
    // A restored state has a mesh's near particles but not their triangles: listed again.
    const bool triangles_listed = !mesh || reach.triangle_start.size() == reach.near.size() + 1;
    if (reach.valid && triangles_listed && reach.range == range &&
        walls::surface_shift(reach.shape, wall.shape, reach.extent) <= 0.5 * skin_)
      continue;
    const Vec3 origin = walls::reference_point(wall.shape);
    const int stride = wall_strides_[k];
    double* history = wall_history[k].data();
    const walls::ReachTest test(wall.shape, range, margin);
    reach.near.clear();
    reach.extent = 0.0;
    for (std::size_t i = 0; i < particles.size(); ++i) {
      reach.extent = std::max(reach.extent, norm2(particles.x[i] - origin));
      if (test.may_reach(particles.x[i], particles.radius[i])) {
        reach.near.push_back(static_cast<int>(i));
        continue;
      }
      double* h = history + static_cast<std::ptrdiff_t>(i) * stride;
      std::fill(h, h + stride, 0.0);
    }
    reach.extent = std::sqrt(reach.extent) + 2.0 * skin_;
    reach.shape = wall.shape;
    reach.range = range;
    reach.valid = true;
    if (mesh) list_triangles(*mesh, particles, range, margin, reach);
  }
}

const contact::ContactLaw& World::pair_law(int a, int b) const {
  return pair_laws_[a * n_materials_ + b];
}

const contact::ContactLaw& World::wall_law(int wall_material, int particle_material) const {
  return wall_laws_[wall_material][particle_material];
}

double World::interaction_range() const {
  double range = 0.0;
  for (const auto& law : pair_laws_) range = std::max(range, law.range());
  for (const auto& row : wall_laws_)
    for (const auto& law : row) range = std::max(range, law.range());
  return range;
}

void World::prepare() {
  // Every material present needs its laws, and one compiled kernel must serve each table.
  for (auto m : particles.material) {
    if (m >= n_materials_ || !pair_set_[m * n_materials_ + m])
      throw InputError("contact_laws",
                       "no particle-particle contact law for material " + std::to_string(m));
  }
  for (int a = 0; a < n_materials_ * n_materials_; ++a)
    if (pair_set_[a] && composition(pair_laws_[a]) != composition(pair_laws_[0]))
      throw InputError(
          "contact_laws",
          "all particle-particle laws must use the same models (parameters may differ)");
  wall_strides_.clear();
  for (const auto& w : walls) {
    if (w.material >= wall_laws_.size())
      throw InputError("walls." + w.name,
                       "no contact law for wall material " + std::to_string(w.material));
    for (auto m : particles.material)
      if (!wall_set_[w.material][m])
        throw InputError("walls." + w.name, "no contact law between wall material " +
                                                std::to_string(w.material) +
                                                " and particle material " + std::to_string(m));
    const auto& row = wall_laws_[w.material];
    for (int m = 0; m < n_materials_; ++m)
      if (wall_set_[w.material][m] &&
          composition(row[m]) !=
              composition(row[particles.material.empty() ? 0 : particles.material[0]]))
        throw InputError("walls." + w.name,
                         "all laws of one wall material must use the same models");
    wall_strides_.push_back(walls::history_stride(
        w.shape, row[particles.material.empty() ? 0 : particles.material[0]].history_size()));
  }
  check_time_step(*this);
  check_contact_range(*this);

  double r_min = 1e300;
  for (double r : particles.radius) r_min = std::min(r_min, r);
  skin_ = skin > 0.0 ? skin : (particles.size() ? 0.1 * r_min : 0.0);
  pair_stride_ = n_materials_ ? pair_laws_[0].history_size() : 0;

  for (std::size_t i = 0; i < particles.size(); ++i) domain.wrap(particles.x[i]);
  list = neighbour::VerletList{};
  pair_history.clear();
  list.build(particles.x, particles.radius, domain, interaction_range() + skin_, threads,
             pair_history, pair_stride_, clump_bodies());
  balance_owners();
  clump_frames.reset(particles);
  set_contact_masses();
  wall_history.assign(walls.size(), {});
  for (std::size_t w = 0; w < walls.size(); ++w)
    wall_history[w].assign(particles.size() * wall_strides_[w], 0.0);
  wall_reach.clear();
  prepared_ = true;
  // The forces of this configuration, for the first half kick of the next step: step() relies on
  // them whether it called prepare() itself or the caller did.
  compute_forces(*this);
}

void World::set_contact_masses() {
  clump_inverse_mass_.clear();
  if (particles.clumps.size())
    for (std::size_t i = 0; i < particles.size(); ++i)
      clump_inverse_mass_.push_back(1.0 / contact_mass(particles, i));
}

void World::remove_particles(const std::vector<char>& flags) {
  particles.remove_if(flags);
  prepared_ = false;
}

void insert_random(World& world, particles::InsertRequest request, Rng& rng) {
  // Each thread's contiguous range is then a slab of the bed.
  request.cell_order = world.active_threads_for(world.particles.size() + request.spheres()) > 1;
  particles::insert_random(world.particles, request, rng);
}

}  // namespace demcal::sim
