#include "core/particles/insertion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "core/common/error.hpp"

namespace demcal::particles {
namespace {

/// Hash grid of the spheres already placed (their centres and radii), for the overlap check of a
/// candidate.
class PlacementGrid {
 public:
  explicit PlacementGrid(double cell) : cell_(cell) {}
  void add(const Vec3& x, double r) {
    cells_[key(x)].push_back(x_.size());
    x_.push_back(x);
    r_.push_back(r);
  }
  bool overlaps(const Vec3& x, double r, double gap) const {
    const auto c = coords(x);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(pack(c[0] + dx, c[1] + dy, c[2] + dz));
          if (it == cells_.end()) continue;
          for (std::size_t j : it->second) {
            const double min_d = r + r_[j] + gap;
            if (norm2(x_[j] - x) < min_d * min_d) return true;
          }
        }
    return false;
  }
  /// The cell of x as (z, y, x) integer coordinates: ordering by it stores a bed layer by layer.
  std::array<std::int64_t, 3> layer_order(const Vec3& x) const {
    const auto c = coords(x);
    return {c[2], c[1], c[0]};
  }

 private:
  std::array<std::int64_t, 3> coords(const Vec3& x) const {
    return {static_cast<std::int64_t>(std::floor(x.x / cell_)),
            static_cast<std::int64_t>(std::floor(x.y / cell_)),
            static_cast<std::int64_t>(std::floor(x.z / cell_))};
  }
  static std::int64_t pack(std::int64_t a, std::int64_t b, std::int64_t c) {
    return ((a & 0x1FFFFF) << 42) | ((b & 0x1FFFFF) << 21) | (c & 0x1FFFFF);
  }
  std::int64_t key(const Vec3& x) const {
    const auto c = coords(x);
    return pack(c[0], c[1], c[2]);
  }
  double cell_;
  std::unordered_map<std::int64_t, std::vector<std::size_t>> cells_;
  std::vector<Vec3> x_;
  std::vector<double> r_;
};

/// A sphere or clump placed by the insertion, added to the store once all are placed.
struct Placement {
  Vec3 centre;
  Quat orientation;
  double radius;
};

/// Adds the placements to the store: as drawn, or (req.cell_order) in the order of their grid
/// cells, layer by layer (z, then y, then x; drawn order within a cell).
void add_placed(ParticleStore& store, const InsertRequest& req, const PlacementGrid& grid,
                const std::vector<Placement>& placed) {
  std::vector<std::size_t> order(placed.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  if (req.cell_order)
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return grid.layer_order(placed[a].centre) < grid.layer_order(placed[b].centre);
    });
  for (std::size_t k : order) {
    const Placement& p = placed[k];
    if (req.shape)
      store.add_clump(p.centre, p.orientation, *req.shape, p.radius, req.density, req.material);
    else
      store.add_sphere(p.centre, p.radius, req.density, req.material);
  }
}

/// A uniformly random centre for a sphere of radius r that lies wholly inside the region.
bool random_centre(const Region& region, double r, Rng& rng, Vec3& out) {
  return std::visit(
      [&](const auto& g) {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, BoxRegion>) {
          const Vec3 lo = g.lo + Vec3{r, r, r}, hi = g.hi - Vec3{r, r, r};
          if (lo.x > hi.x || lo.y > hi.y || lo.z > hi.z) return false;
          out = {rng.uniform(lo.x, hi.x), rng.uniform(lo.y, hi.y), rng.uniform(lo.z, hi.z)};
          return true;
        } else {
          const double rr = g.radius - r;
          if (rr <= 0.0 || g.z_lo + r > g.z_hi - r) return false;
          // Uniform in the disk: radius from sqrt of a uniform number.
          const double rho = rr * std::sqrt(rng.uniform());
          const double phi = 2.0 * M_PI * rng.uniform();
          out = {g.centre.x + rho * std::cos(phi), g.centre.y + rho * std::sin(phi),
                 rng.uniform(g.z_lo + r, g.z_hi - r)};
          return true;
        }
      },
      region);
}

/// A uniformly random orientation (Shoemake 1992, three uniforms).
Quat random_orientation(Rng& rng) {
  const double u1 = rng.uniform(), u2 = 2.0 * M_PI * rng.uniform(), u3 = 2.0 * M_PI * rng.uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return Quat{a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3)}.normalized();
}

}  // namespace

void insert_random(ParticleStore& store, const InsertRequest& req, Rng& rng) {
  validate(req.sizes, "sizes");
  const ClumpTemplate* shape = req.shape ? &*req.shape : nullptr;
  double largest_member = 1.0, bounding = 1.0;
  if (shape) {
    largest_member = *std::max_element(shape->radii.begin(), shape->radii.end());
    bounding = shape->bounding_radius;
  }
  const double r_max = max_radius(req.sizes) * largest_member;
  PlacementGrid grid(2.0 * r_max + req.gap);
  for (std::size_t i = 0; i < store.size(); ++i) grid.add(store.x[i], store.radius[i]);
  store.reserve(store.size() + req.count * (shape ? shape->size() : 1));
  std::vector<Placement> placed;
  placed.reserve(req.count);
  std::vector<Vec3> members;
  while (placed.size() < req.count) {
    const double r = sample_radius(req.sizes, rng);
    bool ok = false;
    for (std::size_t attempt = 0; attempt < req.max_attempts_per_particle && !ok; ++attempt) {
      Vec3 c;
      if (!random_centre(req.region, r * bounding + req.gap, rng, c)) {
        add_placed(store, req, grid, placed);
        throw InputError("insertion.region",
                         "region too small for a particle of radius " + std::to_string(r));
      }
      if (!shape) {
        if (grid.overlaps(c, r, req.gap)) continue;
        grid.add(c, r);
        placed.push_back({c, Quat{}, r});
        ok = true;
        continue;
      }
      const Quat q = random_orientation(rng);
      members.clear();
      bool free = true;
      for (std::size_t k = 0; k < shape->size() && free; ++k) {
        members.push_back(c + q.rotate(shape->offsets[k] * r));
        free = !grid.overlaps(members.back(), shape->radii[k] * r, req.gap);
      }
      if (!free) continue;
      for (std::size_t k = 0; k < shape->size(); ++k) grid.add(members[k], shape->radii[k] * r);
      placed.push_back({c, q, r});
      ok = true;
    }
    if (!ok) {
      // What was placed stays placed: a caller may let the bed settle and insert the rest.
      add_placed(store, req, grid, placed);
      throw InputError("insertion.count", "could place only " + std::to_string(placed.size()) +
                                              " of " + std::to_string(req.count) +
                                              " particles without overlap; enlarge the region or "
                                              "insert fewer");
    }
  }
  add_placed(store, req, grid, placed);
}

void insert_lattice(ParticleStore& store, const Vec3& origin, double spacing, int nx, int ny,
                    int nz, double radius, double density, std::uint16_t material, double jitter,
                    Rng& rng) {
  if (spacing < 2.0 * radius + 2.0 * jitter)
    throw InputError("lattice.spacing", "spacing must exceed the diameter plus twice the jitter");
  store.reserve(store.size() + static_cast<std::size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 c = origin + Vec3{i * spacing + rng.uniform(-jitter, jitter),
                                     j * spacing + rng.uniform(-jitter, jitter), k * spacing};
        store.add_sphere(c, radius, density, material);
      }
}

}  // namespace demcal::particles
