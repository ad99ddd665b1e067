// Insertion without overlap: random sequential insertion into box and cylinder
// regions, the error for a request too dense for random insertion, and lattices with jitter.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/particles/insertion.hpp"

namespace demcal::particles {
namespace {

/// Smallest surface gap over all pairs (negative = overlap).
double min_gap(const ParticleStore& s) {
  double worst = 1e300;
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = i + 1; j < s.size(); ++j)
      worst = std::min(worst, norm(s.x[j] - s.x[i]) - s.radius[i] - s.radius[j]);
  return worst;
}

TEST(ParticlesInsertion, RandomBoxNoOverlapAllInside) {
  ParticleStore s;
  Rng rng(7);
  InsertRequest req;
  req.region = BoxRegion{{-0.01, 0.0, 0.02}, {0.01, 0.03, 0.05}};
  req.sizes = LogNormal{4e-4, 1.3, 2.0};
  req.count = 600;
  req.density = 1500;
  req.gap = 2e-5;
  insert_random(s, req, rng);
  ASSERT_EQ(s.size(), 600u);
  EXPECT_GE(min_gap(s), req.gap - 1e-15);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double r = s.radius[i] + req.gap;
    EXPECT_GE(s.x[i].x - r, -0.01 - 1e-15);
    EXPECT_LE(s.x[i].x + r, 0.01 + 1e-15);
    EXPECT_GE(s.x[i].y - r, 0.0 - 1e-15);
    EXPECT_LE(s.x[i].y + r, 0.03 + 1e-15);
    EXPECT_GE(s.x[i].z - r, 0.02 - 1e-15);
    EXPECT_LE(s.x[i].z + r, 0.05 + 1e-15);
    // Mass and inertia of a solid sphere of the requested density.
    const double m = 1500 * 4.0 / 3.0 * M_PI * std::pow(s.radius[i], 3);
    EXPECT_NEAR(s.mass[i], m, 1e-12 * m);
    EXPECT_NEAR(s.inertia[i], 0.4 * m * s.radius[i] * s.radius[i], 1e-12 * s.inertia[i]);
  }
  // The region is filled evenly: each half of the box (in x) holds 50 % +- 5 sigma.
  int left = 0;
  for (const auto& x : s.x) left += x.x < 0.0;
  EXPECT_NEAR(left, 300, 5.0 * std::sqrt(600 * 0.25));
}

TEST(ParticlesInsertion, RandomCylinderNoOverlapAllInside) {
  ParticleStore s;
  s.add_sphere({0.0, 0.0, 0.5}, 0.001, 2500, 0);  // an existing sphere must be respected too
  Rng rng(11);
  InsertRequest req;
  const Vec3 centre{0.1, -0.2, 0.0};
  req.region = CylinderRegion{centre, 0.01, 0.0, 0.02};
  req.sizes = DiscreteClasses{{5e-4, 8e-4, 1.2e-3}, {0.2, 0.5, 0.3}};
  req.count = 300;
  req.density = 2500;
  req.material = 3;
  insert_random(s, req, rng);
  ASSERT_EQ(s.size(), 301u);
  EXPECT_GE(min_gap(s), 0.0);
  for (std::size_t i = 1; i < s.size(); ++i) {
    const double rho = std::hypot(s.x[i].x - centre.x, s.x[i].y - centre.y);
    EXPECT_LE(rho + s.radius[i], 0.01 + 1e-15);
    EXPECT_GE(s.x[i].z - s.radius[i], 0.0 - 1e-15);
    EXPECT_LE(s.x[i].z + s.radius[i], 0.02 + 1e-15);
    EXPECT_EQ(s.material[i], 3);
    EXPECT_EQ(s.motion[i], Motion::kFree);
  }
}

TEST(ParticlesInsertion, TooDenseRequestThrows) {
  // 2000 spheres of r = 1 mm in a 1 cm cube would be a solid fraction of 8.4: impossible.
  ParticleStore s;
  Rng rng(3);
  InsertRequest req;
  req.region = BoxRegion{{0, 0, 0}, {0.01, 0.01, 0.01}};
  req.sizes = Monodisperse{0.001};
  req.count = 2000;
  req.density = 1000;
  req.max_attempts_per_particle = 200;
  try {
    insert_random(s, req, rng);
    FAIL() << "an impossible insertion succeeded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "insertion.count");
    EXPECT_NE(std::string(e.what()).find("of 2000"), std::string::npos) << e.what();
    // The spheres placed before it gave up stay in the store, as many as the message says.
    EXPECT_NE(std::string(e.what()).find("only " + std::to_string(s.size()) + " of"),
              std::string::npos)
        << e.what();
    EXPECT_GT(s.size(), 20u);
    EXPECT_GE(min_gap(s), -1e-15);
  }
  // A region narrower than one sphere is a different error.
  req.region = BoxRegion{{0, 0, 0}, {0.001, 0.01, 0.01}};
  req.count = 1;
  ParticleStore t;
  try {
    insert_random(t, req, rng);
    FAIL() << "a sphere wider than the region was inserted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "insertion.region");
  }
}

/// The store's spheres as (z, y, x, r) tuples, sorted: the set placed, whatever the order.
std::vector<std::array<double, 4>> placed_set(const ParticleStore& s) {
  std::vector<std::array<double, 4>> out;
  for (std::size_t i = 0; i < s.size(); ++i)
    out.push_back({s.x[i].z, s.x[i].y, s.x[i].x, s.radius[i]});
  std::sort(out.begin(), out.end());
  return out;
}

TEST(ParticlesInsertion, CellOrderStoresTheSameSpheresLayerByLayer) {
  InsertRequest req;
  req.region = CylinderRegion{{0, 0, 0}, 0.01, 0.0, 0.08};
  req.sizes = DiscreteClasses{{9e-4, 1e-3, 1.1e-3}, {0.3, 0.4, 0.3}};
  req.count = 800;
  req.density = 2500;
  ParticleStore drawn, ordered;
  Rng rng_a(5), rng_b(5);
  insert_random(drawn, req, rng_a);
  req.cell_order = true;
  insert_random(ordered, req, rng_b);
  // The same spheres at the same places, bit for bit; the draw itself is unchanged.
  ASSERT_EQ(ordered.size(), drawn.size());
  EXPECT_EQ(placed_set(ordered), placed_set(drawn));
  EXPECT_EQ(rng_a.uniform(), rng_b.uniform());
  // Stored by layers of the placement grid's cell (the largest diameter): the z cell never
  // decreases along the store, and within a layer the y cell never decreases. The drawn order
  // goes down again hundreds of times.
  const double cell = 2.0 * 1.1e-3;
  auto layer = [&](const ParticleStore& s, std::size_t i) {
    return std::array<long, 2>{static_cast<long>(std::floor(s.x[i].z / cell)),
                               static_cast<long>(std::floor(s.x[i].y / cell))};
  };
  int drawn_descents = 0;
  for (std::size_t i = 1; i < ordered.size(); ++i) {
    EXPECT_LE(layer(ordered, i - 1), layer(ordered, i)) << "sphere " << i;
    drawn_descents += layer(drawn, i)[0] < layer(drawn, i - 1)[0];
  }
  EXPECT_GT(drawn_descents, 200);
}

TEST(ParticlesInsertion, LatticeSpacingAndJitter) {
  ParticleStore s;
  Rng rng(5);
  const Vec3 origin{0.001, 0.002, 0.003};
  const double spacing = 0.0022, jitter = 9e-5;
  insert_lattice(s, origin, spacing, 4, 3, 5, 0.001, 2500, 1, jitter, rng);
  ASSERT_EQ(s.size(), 60u);
  double max_dx = 0.0, max_dy = 0.0;
  std::size_t idx = 0;
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i, ++idx) {
        const Vec3 ideal = origin + Vec3{i * spacing, j * spacing, k * spacing};
        const Vec3 d = s.x[idx] - ideal;
        EXPECT_LE(std::abs(d.x), jitter);
        EXPECT_LE(std::abs(d.y), jitter);
        EXPECT_NEAR(d.z, 0.0, 1e-15);  // jitter is lateral only
        max_dx = std::max(max_dx, std::abs(d.x));
        max_dy = std::max(max_dy, std::abs(d.y));
        EXPECT_EQ(s.material[idx], 1);
      }
  // The jitter is really applied (60 draws of U(-j, j): the largest exceeds j/2 almost surely).
  EXPECT_GT(max_dx, 0.5 * jitter);
  EXPECT_GT(max_dy, 0.5 * jitter);
  EXPECT_GE(min_gap(s), spacing - 2.0 * 0.001 - 2.0 * jitter - 1e-15);

  // Without jitter the lattice is exact; spacing below the diameter + 2 jitter is refused.
  ParticleStore t;
  insert_lattice(t, origin, spacing, 2, 2, 2, 0.001, 2500, 0, 0.0, rng);
  EXPECT_NEAR(norm(t.x[1] - t.x[0]), spacing, 1e-15);
  EXPECT_NEAR(norm(t.x[7] - t.x[0]), spacing * std::sqrt(3.0), 1e-15);
  EXPECT_THROW(insert_lattice(t, origin, 0.0021, 2, 2, 2, 0.001, 2500, 0, 9e-5, rng), InputError);
}

}  // namespace
}  // namespace demcal::particles
