// Rigid multisphere clumps (seed 004 §2.2.2.1): the mass properties of a union of spheres against
// closed forms (one sphere, two touching spheres by the parallel-axis theorem, two overlapping
// spheres less their lens), the rod / helix / cluster templates, the shape.* parameter errors,
// clump insertion without overlap and the removal of whole clumps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"
#include "core/particles/clump_shape.hpp"
#include "core/particles/insertion.hpp"

namespace demcal::particles {
namespace {

constexpr double kSphereVolume = 4.0 / 3.0 * M_PI;

/// Volume of the lens common to two spheres of radius r whose centres are d apart (d < 2r).
double lens_volume(double r, double d) {
  return M_PI * (4.0 * r + d) * (2.0 * r - d) * (2.0 * r - d) / 12.0;
}

void expect_rel(double actual, double expected, double rel, const char* what) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << what;
}

TEST(ParticlesClumps, UnionMassPropertiesOfOneSphere) {
  const auto p = union_mass_properties({{0.3, -0.2, 0.1}}, {1.0});
  expect_rel(p.volume, kSphereVolume, 1e-4, "volume");
  // Unit density: I = 2/5 m r^2 = 2/5 (4/3 pi) = 8/15 pi.
  for (int a = 0; a < 3; ++a) {
    expect_rel(p.inertia[a][a], 8.0 / 15.0 * M_PI, 1e-4, "diagonal");
    for (int b = 0; b < 3; ++b) {
      if (a != b) {
        EXPECT_NEAR(p.inertia[a][b], 0.0, 1e-4 * 8.0 / 15.0 * M_PI) << a << b;
      }
    }
  }
  EXPECT_NEAR(p.centroid.x, 0.3, 1e-6);
  EXPECT_NEAR(p.centroid.y, -0.2, 1e-6);
  EXPECT_NEAR(p.centroid.z, 0.1, 1e-6);
}

TEST(ParticlesClumps, UnionMassPropertiesOfTwoTouchingSpheres) {
  // Centres 2 apart along y: touching, no overlap. Parallel axis: across = 2 (2/5 m + m 1^2).
  const auto p = union_mass_properties({{1.0, 0.0, 0.5}, {1.0, 2.0, 0.5}}, {1.0, 1.0});
  const double m = kSphereVolume;
  expect_rel(p.volume, 2.0 * m, 1e-3, "volume");
  EXPECT_NEAR(p.centroid.x, 1.0, 1e-3);
  EXPECT_NEAR(p.centroid.y, 1.0, 1e-3);
  EXPECT_NEAR(p.centroid.z, 0.5, 1e-3);
  const double along = 2.0 * 0.4 * m, across = 2.0 * (0.4 * m + m * 1.0);
  expect_rel(p.inertia[1][1], along, 1e-3, "about the axis");
  expect_rel(p.inertia[0][0], across, 1e-3, "across (x)");
  expect_rel(p.inertia[2][2], across, 1e-3, "across (z)");
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      if (a != b) {
        EXPECT_NEAR(p.inertia[a][b], 0.0, 1e-3 * along) << a << b;
      }
    }
  }
}

TEST(ParticlesClumps, UnionMassPropertiesOfTwoOverlappingSpheres) {
  const double d = 1.0;
  const auto p = union_mass_properties({{0.0, 0.0, 0.0}, {0.0, 0.0, d}}, {1.0, 1.0});
  expect_rel(p.volume, 2.0 * kSphereVolume - lens_volume(1.0, d), 1e-3, "volume");
  EXPECT_NEAR(p.centroid.z, 0.5 * d, 1e-3);
}

std::vector<std::string> names(ShapeKind k) {
  return shape_params(k);
}

ShapeSpec spec(const std::string& kind, const std::map<std::string, double>& params) {
  return make_shape_spec(kind, params, "shape");
}

TEST(ParticlesClumps, SphereTemplateIsOneUnitSphere) {
  const auto t = make_template(spec("sphere", {}));
  ASSERT_EQ(t.size(), 1u);
  EXPECT_NEAR(t.radii[0], 1.0, 1e-4);
  EXPECT_NEAR(norm(t.offsets[0]), 0.0, 1e-6);
  expect_rel(t.volume, kSphereVolume, 1e-9, "volume");
  EXPECT_TRUE(names(ShapeKind::kSphere).empty());
}

TEST(ParticlesClumps, RodTemplateHasItsAspectRatioAndLiesAlongItsSmallestMoment) {
  const double ar = 3.0;
  const auto t = make_template(spec("rod", {{"aspect_ratio", ar}, {"spacing", 0.5}}));
  ASSERT_GE(t.size(), 3u);
  const double r = t.radii[0];
  for (double rk : t.radii) EXPECT_NEAR(rk, r, 1e-12);
  // Principal moments ascending; the smallest about the rod axis (body x), the others equal.
  EXPECT_LT(t.inertia.x, t.inertia.y);
  EXPECT_LE(t.inertia.y, t.inertia.z);
  expect_rel(t.inertia.z, t.inertia.y, 1e-3, "the two moments across a rod");
  double lo = 1e300, hi = -1e300;
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_NEAR(t.offsets[k].y, 0.0, 1e-9) << k;  // collinear along body x
    EXPECT_NEAR(t.offsets[k].z, 0.0, 1e-9) << k;
    lo = std::min(lo, t.offsets[k].x - t.radii[k]);
    hi = std::max(hi, t.offsets[k].x + t.radii[k]);
  }
  EXPECT_NEAR((hi - lo) / (2.0 * r), ar, 1e-9);
  EXPECT_NEAR(lo, -hi, 1e-9 * hi);  // centred
  EXPECT_NEAR(t.bounding_radius, 0.5 * (hi - lo), 1e-9);
  expect_rel(t.volume, kSphereVolume, 1e-9, "volume-equivalent radius 1");
  // Length 2 AR (member radius 1) with neighbours at most one radius apart: n = 5 members,
  // neighbours exactly 1 apart, others >= 2 apart (no triple overlaps). The union is then
  // n spheres less (n - 1) lenses, analytic.
  ASSERT_EQ(t.size(), 5u);
  const double n = 5.0;
  const double union_unscaled = n * kSphereVolume - (n - 1.0) * lens_volume(1.0, 1.0);
  expect_rel(t.volume_weight(), union_unscaled / (n * kSphereVolume), 2e-4, "volume weight");
  EXPECT_LT(t.volume_weight(), 1.0);
  // Scale: lengths by k = cbrt(4/3 pi / V_union).
  expect_rel(r, std::cbrt(kSphereVolume / union_unscaled), 1e-4, "member radius");
}

TEST(ParticlesClumps, HelixTemplateIsCentredAndNotCollinear) {
  const auto t = make_template(
      spec("helix", {{"aspect_ratio", 4.0}, {"revolutions", 1.0}, {"offset_ratio", 0.267}}));
  ASSERT_GE(t.size(), 3u);
  // Equal members, neighbours equally far apart, no other overlaps (axial step 1, second
  // neighbours > 2 radii apart): the union's centroid is (V_s sum c_k - V_lens sum of the lens
  // centres (c_k + c_k+1) / 2) / V, which the template puts at the origin. (The plain mean of the
  // centres is not the centroid: the end spheres lose half a lens only.)
  const double rm = t.radii[0], d = norm(t.offsets[1] - t.offsets[0]);
  Vec3 moment{};
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_NEAR(t.radii[k], rm, 1e-12);
    moment += t.offsets[k] * (kSphereVolume * rm * rm * rm);
    if (k + 1 < t.size()) {
      EXPECT_NEAR(norm(t.offsets[k + 1] - t.offsets[k]), d, 1e-9);
      moment -= 0.5 * (t.offsets[k] + t.offsets[k + 1]) * lens_volume(rm, d);
    }
    for (std::size_t j = k + 2; j < t.size(); ++j)
      EXPECT_GT(norm(t.offsets[j] - t.offsets[k]), 2.0 * rm) << k << " " << j;
  }
  EXPECT_LT(norm(moment) / (t.volume * rm), 1e-3);
  expect_rel(t.sphere_volume_sum - (static_cast<double>(t.size()) - 1.0) * lens_volume(rm, d),
             t.volume, 1e-3, "union = spheres - lenses");
  expect_rel(t.volume, kSphereVolume, 1e-9, "volume");
  // Not collinear: some member lies well off the line through the first two.
  const Vec3 axis = (t.offsets[1] - t.offsets[0]) / norm(t.offsets[1] - t.offsets[0]);
  double off_line = 0.0;
  for (const auto& o : t.offsets)
    off_line = std::max(off_line, norm(cross(axis, o - t.offsets[0])));
  EXPECT_GT(off_line, 0.1 * t.radii[0]);
  EXPECT_LT(t.inertia.x, t.inertia.y);
  EXPECT_LE(t.inertia.y, t.inertia.z);
}

/// True when the spheres form one connected cluster (overlap graph).
bool connected(const ClumpTemplate& t) {
  std::vector<char> seen(t.size(), 0);
  std::vector<std::size_t> todo{0};
  seen[0] = 1;
  while (!todo.empty()) {
    const std::size_t i = todo.back();
    todo.pop_back();
    for (std::size_t j = 0; j < t.size(); ++j)
      if (!seen[j] && norm(t.offsets[j] - t.offsets[i]) < t.radii[i] + t.radii[j]) {
        seen[j] = 1;
        todo.push_back(j);
      }
  }
  return std::all_of(seen.begin(), seen.end(), [](char c) { return c != 0; });
}

TEST(ParticlesClumps, ClusterTemplateIsDeterministicPerSeedAndConnected) {
  auto cluster = [](double seed) {
    return make_template(
        spec("cluster", {{"spheres", 6.0}, {"irregularity", 0.7}, {"seed", seed}}));
  };
  const auto a = cluster(5), b = cluster(5), c = cluster(6);
  ASSERT_EQ(a.size(), 6u);
  ASSERT_EQ(c.size(), 6u);
  double same = 0.0, different = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    same = std::max(same, norm(a.offsets[k] - b.offsets[k]));
    different = std::max(different, norm(a.offsets[k] - c.offsets[k]));
    EXPECT_EQ(a.radii[k], b.radii[k]);
  }
  EXPECT_EQ(same, 0.0);
  EXPECT_GT(different, 0.05);
  for (const auto* t : {&a, &c}) {
    EXPECT_TRUE(connected(*t));
    for (std::size_t i = 0; i < t->size(); ++i) {  // every sphere overlaps another
      bool overlaps = false;
      for (std::size_t j = 0; j < t->size(); ++j)
        overlaps |= j != i && norm(t->offsets[j] - t->offsets[i]) < t->radii[i] + t->radii[j];
      EXPECT_TRUE(overlaps) << i;
    }
    expect_rel(t->volume, kSphereVolume, 1e-9, "volume");
    EXPECT_LT(t->volume_weight(), 1.0);
  }
}

TEST(ParticlesClumps, ClusterSpreadShrinksItToItsLargestSphere) {
  const std::map<std::string, double> base{{"spheres", 5.0}, {"irregularity", 0.6}, {"seed", 3}};
  auto at = [&](double spread) {
    auto params = base;
    params["spread"] = spread;
    std::vector<Vec3> centres;
    std::vector<double> radii;
    shape_spheres(spec("cluster", params), centres, radii);
    return std::make_pair(centres, radii);
  };
  // Spread 1 is the cluster as built; 0 puts every centre at the first sphere's, which (radius
  // 1, the largest) encloses the others: one sphere is left, and the template is a unit sphere.
  const auto [built, built_radii] = at(1.0);
  std::vector<Vec3> unspread;
  std::vector<double> unspread_radii;
  shape_spheres(spec("cluster", base), unspread, unspread_radii);
  ASSERT_EQ(built.size(), 5u);
  for (std::size_t k = 0; k < built.size(); ++k) EXPECT_EQ(norm(built[k] - unspread[k]), 0.0);
  const auto [point, point_radii] = at(0.0);
  ASSERT_EQ(point.size(), 1u);
  EXPECT_EQ(point_radii[0], 1.0);
  const auto sphere = make_template(spec("cluster", {{"spread", 0.0}}));
  ASSERT_EQ(sphere.size(), 1u);
  expect_rel(sphere.radii[0], 1.0, 1e-5, "radius");  // the union's volume is integrated to 2e-5
  expect_rel(sphere.volume, kSphereVolume, 1e-9, "volume");
  // Between, a sphere is left out exactly when another one encloses it: the count of members
  // falls with the spread, through values between 5 and 1, and no kept sphere is enclosed.
  std::size_t last = 5;
  bool between = false;
  for (int step = 50; step >= 0; --step) {
    const double spread = step / 50.0;
    const auto [near, near_radii] = at(spread);
    EXPECT_LE(near.size(), last) << spread;
    last = near.size();
    between |= near.size() > 1 && near.size() < 5;
    for (std::size_t k = 0; k < near.size(); ++k)
      for (std::size_t j = 0; j < near.size(); ++j)
        if (j != k) {
          EXPECT_GT(norm(near[k] - near[j]) + near_radii[k], near_radii[j]) << k << j;
        }
  }
  EXPECT_TRUE(between);
  EXPECT_EQ(last, 1u);
}

TEST(ParticlesClumps, ShapeSpecErrorsNameTheParameter) {
  try {
    spec("rod", {{"spheres", 4.0}});
    FAIL() << "a cluster parameter was accepted for a rod";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "shape.spheres");
  }
  EXPECT_THROW(spec("cube", {}), InputError);
  try {
    spec("rod", {{"aspect_ratio", 0.5}});
    FAIL() << "aspect_ratio 0.5 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.where().find("aspect_ratio"), std::string::npos) << e.where();
  }
  const auto rod = spec("rod", {{"aspect_ratio", 4.0}});
  EXPECT_EQ(rod.kind, ShapeKind::kRod);
  EXPECT_EQ(rod.aspect_ratio, 4.0);
}

TEST(ParticlesClumps, InsertedRodsDoNotOverlapAndKeepTheirVolume) {
  ParticleStore s;
  Rng rng(11);
  InsertRequest req;
  const Vec3 lo{-0.01, 0.0, 0.02}, hi{0.01, 0.02, 0.04};
  const double r = 1e-3, density = 1500;
  req.region = BoxRegion{lo, hi};
  req.sizes = Monodisperse{r};
  req.count = 60;
  req.density = density;
  req.shape = make_template(spec("rod", {{"aspect_ratio", 2.5}}));
  insert_random(s, req, rng);
  const std::size_t members = req.shape->size();
  ASSERT_GE(members, 2u);
  ASSERT_EQ(s.clumps.size(), 60u);
  ASSERT_EQ(s.size(), 60u * members);
  for (std::size_t b = 0; b < s.clumps.size(); ++b) {
    ASSERT_EQ(s.clumps.count[b], members);
    EXPECT_EQ(s.clumps.first[b], b * members);
    for (std::size_t k = s.clumps.first[b]; k < s.clumps.first[b] + s.clumps.count[b]; ++k) {
      EXPECT_EQ(s.body[k], static_cast<std::int32_t>(b));
      EXPECT_EQ(s.motion[k], Motion::kClumpMember);
    }
  }
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(s.x[i][a] - s.radius[i], lo[a] - 1e-15) << i;
      EXPECT_LE(s.x[i][a] + s.radius[i], hi[a] + 1e-15) << i;
    }
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      if (s.body[i] != s.body[j]) {
        EXPECT_GE(norm(s.x[j] - s.x[i]), s.radius[i] + s.radius[j] - 1e-15) << i << " " << j;
      }
    }
  }
  const double volume = 60.0 * kSphereVolume * r * r * r;
  double solid = 0.0, body_mass = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) solid += s.solid_volume(i);
  for (double m : s.clumps.mass) body_mass += m;
  EXPECT_NEAR(s.total_mass(), density * volume, 1e-9 * density * volume);
  EXPECT_NEAR(body_mass, density * volume, 1e-9 * density * volume);
  EXPECT_NEAR(solid, volume, 1e-9 * volume);
}

TEST(ParticlesClumps, RemovingOneMemberRemovesItsWholeClump) {
  ParticleStore s;
  const auto rod = make_template(spec("rod", {{"aspect_ratio", 3.0}}));
  const double r = 1e-3;
  // Lone spheres between the clumps: sphere, clump 0, sphere, clump 1, ...
  for (int b = 0; b < 6; ++b) {
    s.add_sphere({0.1 * b, 0.05, 0.0}, r, 1000, 0);
    s.add_clump({0.1 * b, 0.0, 0.0}, rotation_quat({0.1 * b, 0.2, -0.3}), rod, r, 1000, 0);
  }
  const std::size_t members = rod.size(), before = s.size();
  std::vector<char> flags(s.size(), 0);
  flags[s.clumps.first[3] + 1] = 1;
  s.remove_if(flags);
  ASSERT_EQ(s.clumps.size(), 5u);
  ASSERT_EQ(s.size(), before - members);
  const int survivors[] = {0, 1, 2, 4, 5};
  std::size_t lone = 0;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.body[i] < 0) {
      EXPECT_EQ(s.x[i].y, 0.05);
      ++lone;
    }
  EXPECT_EQ(lone, 6u);
  for (std::size_t b = 0; b < 5; ++b) {
    EXPECT_EQ(s.clumps.x[b].x, 0.1 * survivors[b]) << b;
    ASSERT_EQ(s.clumps.count[b], members);
    // Order kept: the lone spheres S0..S_survivor and the earlier surviving clumps precede it.
    const std::size_t first = s.clumps.first[b];
    EXPECT_EQ(first, static_cast<std::size_t>(survivors[b] + 1) + b * members) << b;
    for (std::size_t k = first; k < first + members; ++k) {
      EXPECT_EQ(s.body[k], static_cast<std::int32_t>(b));
      const Vec3 expected = s.clumps.x[b] + s.clumps.q[b].rotate(s.body_offset[k]);
      EXPECT_NEAR(norm(s.x[k] - expected), 0.0, 1e-15);
    }
  }
}

}  // namespace
}  // namespace demcal::particles
