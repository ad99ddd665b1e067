// Mesh walls: sphere-triangle distances on a face, an edge and a vertex against
// analytic values; one contact (not two) on a flat seam and on a convex edge, two in a concave
// corner; a sphere sliding across a two-triangle seam feels a constant normal force; STL ASCII
// and binary round trips; a rotating paddle reports the torque of the particle force about its
// pivot; the bounding-box rejection of a fitted mesh changes no contact.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/io/stl.hpp"
#include "core/sim/step.hpp"
#include "core/walls/wall.hpp"

namespace demcal {
namespace {

using walls::Mesh;
using walls::WallGeometry;

Mesh unit_triangle() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  return m;
}

TEST(MeshWalls, FaceEdgeVertexDistancesMatchAnalytic) {
  const Mesh m = unit_triangle();
  WallGeometry g[Mesh::kMaxContacts];
  // Face: above the interior.
  ASSERT_EQ(walls::mesh_contacts(m, {0.2, 0.2, 0.3}, 0.35, 0.0, g), 1);
  EXPECT_NEAR(g[0].delta, 0.05, 1e-12);
  EXPECT_NEAR(g[0].n.z, -1.0, 1e-12);
  EXPECT_NEAR(g[0].point.x, 0.2, 1e-12);
  // Below the face: two-sided, normal up.
  ASSERT_EQ(walls::mesh_contacts(m, {0.2, 0.2, -0.3}, 0.35, 0.0, g), 1);
  EXPECT_NEAR(g[0].n.z, 1.0, 1e-12);
  // Edge y = 0: nearest point (0.5, 0, 0), distance sqrt(0.2^2 + 0.1^2).
  ASSERT_EQ(walls::mesh_contacts(m, {0.5, -0.2, 0.1}, 0.3, 0.0, g), 1);
  EXPECT_NEAR(g[0].delta, 0.3 - std::sqrt(0.05), 1e-12);
  EXPECT_NEAR(g[0].point.x, 0.5, 1e-12);
  EXPECT_NEAR(g[0].point.y, 0.0, 1e-12);
  EXPECT_NEAR(norm(g[0].n - normalized(Vec3{0, 0.2, -0.1})), 0.0, 1e-12);
  // Hypotenuse x + y = 1: from (1, 1, 0) the nearest point is (0.5, 0.5, 0).
  ASSERT_EQ(walls::mesh_contacts(m, {1, 1, 0}, 0.8, 0.0, g), 1);
  EXPECT_NEAR(g[0].delta, 0.8 - std::sqrt(0.5), 1e-12);
  // Vertex (0, 0, 0) from (-0.1, -0.2, 0.2).
  ASSERT_EQ(walls::mesh_contacts(m, {-0.1, -0.2, 0.2}, 0.4, 0.0, g), 1);
  EXPECT_NEAR(g[0].delta, 0.4 - 0.3, 1e-12);
  EXPECT_NEAR(norm(g[0].point), 0.0, 1e-12);
  // Out of reach, and within the cohesion range.
  EXPECT_EQ(walls::mesh_contacts(m, {0.2, 0.2, 0.5}, 0.35, 0.0, g), 0);
  ASSERT_EQ(walls::mesh_contacts(m, {0.2, 0.2, 0.5}, 0.35, 0.2, g), 1);
  EXPECT_NEAR(g[0].delta, -0.15, 1e-12);
}

TEST(MeshWalls, FlatSeamConvexEdgeAndConcaveCornerCountContactsOnce) {
  const Mesh quad = walls::make_quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0});  // diagonal (0,0)-(1,1)
  WallGeometry g[Mesh::kMaxContacts];
  // Across the diagonal seam, through the shared vertices and beside the quad's own edge.
  for (double s = 0.0; s <= 1.0; s += 0.05) {
    const Vec3 x{s, 1.0 - s, 0.1};
    ASSERT_EQ(walls::mesh_contacts(quad, x, 0.15, 0.0, g), 1) << "s = " << s;
    EXPECT_NEAR(g[0].delta, 0.05, 1e-12);
    EXPECT_NEAR(g[0].n.z, -1.0, 1e-12);
  }
  ASSERT_EQ(walls::mesh_contacts(quad, {0.5, 0.5, 0.1}, 0.15, 0.0, g), 1);
  ASSERT_EQ(walls::mesh_contacts(quad, {1.0, 1.0, 0.1}, 0.15, 0.0, g), 1);
  // Convex box edge: beyond both faces, one edge contact at 45 deg.
  const Mesh box = walls::make_box({0, 0, 0}, {1, 1, 1});
  ASSERT_EQ(walls::mesh_contacts(box, {1.1, 0.5, 1.1}, 0.2, 0.0, g), 1);
  EXPECT_NEAR(g[0].delta, 0.2 - 0.1 * std::sqrt(2.0), 1e-12);
  // On the top face near the edge: only the face.
  ASSERT_EQ(walls::mesh_contacts(box, {0.95, 0.5, 1.1}, 0.2, 0.0, g), 1);
  EXPECT_NEAR(g[0].delta, 0.1, 1e-12);
  // Box corner: one vertex contact.
  ASSERT_EQ(walls::mesh_contacts(box, {1.1, 1.1, 1.1}, 0.2, 0.0, g), 1);
  // Concave corner of a floor and a vane: two contacts, one per surface.
  Mesh corner = walls::make_quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  corner.append(walls::make_quad({0.5, 0, 0}, {0, 1, 0}, {0, 0, 1}));
  ASSERT_EQ(walls::mesh_contacts(corner, {0.4, 0.5, 0.1}, 0.12, 0.0, g), 2);
  EXPECT_NEAR(g[0].delta, 0.02, 1e-12);
  EXPECT_NEAR(g[1].delta, 0.02, 1e-12);
  EXPECT_NEAR(std::abs(dot(g[0].n, g[1].n)), 0.0, 1e-12);
}

contact::ContactLaw linear_law(double kn, double mu_s) {
  contact::ContactLawSpec s;
  s.normal = {"linear", {{"kn", kn}, {"damping_ratio", 0.7}, {"damp_approach_only", 0.0}}};
  s.tangential = {"history", {{"mu_s", mu_s}}};
  return contact::ContactLaw::from_spec(s, "law");
}

TEST(MeshWalls, SphereSlidingAcrossATwoTriangleSeamFeelsAConstantNormalForce) {
  sim::World w;
  w.gravity = {0, 0, -9.81};
  w.set_pair_law(0, 0, linear_law(1e3, 0.1));
  w.set_wall_law(0, 0, linear_law(1e3, 0.1));
  w.walls.push_back(
      walls::make_wall("floor", walls::make_quad({-0.02, -0.02, 0}, {0.04, 0, 0}, {0, 0.04, 0})));
  const double r = 0.001;
  w.particles.add_sphere({-0.005, 0.004, r}, r, 2500.0, 0);
  w.dt = 2e-6;
  sim::run(w, 20000);  // at rest on the floor
  const double weight = w.particles.mass[0] * 9.81;
  EXPECT_NEAR(w.walls[0].force.z, -weight, 1e-6 * weight);
  // Slide diagonally across the seam y = x (the quad's diagonal).
  w.particles.v[0] = {0.5, -0.2, 0};
  double max_dev = 0.0;
  bool crossed = false;
  const double side0 = w.particles.x[0].y - w.particles.x[0].x;
  for (int s = 0; s < 20000; ++s) {
    sim::step(w);
    max_dev = std::max(max_dev, std::abs(-w.walls[0].force.z - weight));
    crossed = crossed || (w.particles.x[0].y - w.particles.x[0].x) * side0 < 0.0;
  }
  EXPECT_TRUE(crossed);
  EXPECT_LT(max_dev, 1e-6 * weight) << "normal force jumps at the seam";
  // Sliding friction mu N acted all the way, across the seam too: |v| = v0 - mu g t.
  const double v0 = std::hypot(0.5, 0.2);
  EXPECT_NEAR(norm(w.particles.v[0]), v0 - 0.1 * 9.81 * 20000 * w.dt, 0.002 * v0);
}

TEST(MeshWalls, StlAsciiAndBinaryRoundTrips) {
  const Mesh box = walls::make_box({0.125, -0.25, 0.5}, {1.5, 0.75, 2.0});
  const auto dir = std::filesystem::temp_directory_path();
  const std::string ascii = (dir / "demcal_test_box_ascii.stl").string();
  const std::string binary = (dir / "demcal_test_box_binary.stl").string();
  io::write_stl_ascii(ascii, box, "box");
  io::write_stl_binary(binary, box);
  for (const auto& path : {ascii, binary}) {
    const Mesh m = io::read_stl(path);
    ASSERT_EQ(m.triangles.size(), box.triangles.size()) << path;
    EXPECT_EQ(m.vertices.size(), 8u) << path << ": shared vertices are merged";
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(m.vertices[m.triangles[t][k]], box.vertices[box.triangles[t][k]]) << path;
    WallGeometry a[Mesh::kMaxContacts], b[Mesh::kMaxContacts];
    ASSERT_EQ(walls::mesh_contacts(m, {1.6, 0.8, 2.1}, 0.3, 0.0, a), 1);
    ASSERT_EQ(walls::mesh_contacts(box, {1.6, 0.8, 2.1}, 0.3, 0.0, b), 1);
    EXPECT_DOUBLE_EQ(a[0].delta, b[0].delta);
    std::remove(path.c_str());
  }
}

TEST(MeshWalls, RotatingPaddleReportsTheTorqueOfTheParticleForce) {
  sim::World w;
  w.gravity = {0, 0, 0};
  w.set_pair_law(0, 0, linear_law(1e3, 0.0));
  w.set_wall_law(0, 0, linear_law(1e3, 0.0));
  // A paddle in the x-z plane from the z axis out to x = 0.02, turning about z.
  auto paddle =
      walls::make_wall("paddle", walls::make_quad({0, 0, -0.005}, {0.02, 0, 0}, {0, 0, 0.01}));
  paddle.pivot = {0, 0, 0};
  paddle.omega = {0, 0, 2.0};
  w.walls.push_back(paddle);
  const double r = 0.001;
  w.particles.add_sphere({0.012, 0.0015, 0}, r, 2500.0, 0);  // in front of the paddle (it turns +y)
  w.dt = 2e-6;
  double max_torque = 0.0;
  for (int s = 0; s < 20000; ++s) {
    sim::step(w);
    const Vec3 f = w.particles.f[0];  // only the paddle acts
    if (norm(f) == 0.0) continue;
    // Contact point on the paddle: the particle centre projected on its plane.
    const auto& m = std::get<walls::Mesh>(w.walls[0].shape);
    const Vec3 nrm =
        normalized(cross(m.vertices[1] - m.vertices[0], m.vertices[3] - m.vertices[0]));
    const Vec3 x = w.particles.x[0];
    const Vec3 q = x - nrm * dot(x - m.vertices[0], nrm);
    const Vec3 expected = cross(q - w.walls[0].pivot, -f);
    EXPECT_NEAR(w.walls[0].torque.z, expected.z, 1e-9 * std::abs(expected.z) + 1e-18);
    max_torque = std::max(max_torque, -w.walls[0].torque.z);
  }
  EXPECT_GT(max_torque, 0.0) << "the particle resists the paddle's rotation";
  // The paddle has turned omega t about z.
  const auto& m = std::get<walls::Mesh>(w.walls[0].shape);
  const double angle = std::atan2(m.vertices[1].y, m.vertices[1].x);
  EXPECT_NEAR(angle, 2.0 * w.time, 1e-9);
}

// The bounding-box rejection of a fitted mesh changes no contact: spheres on a grid around and
// through a vane head find the same contacts as with the mesh unfitted; a wall's mesh stays
// fitted to its vertices as it moves and turns.
TEST(MeshWalls, BoundingBoxRejectionKeepsEveryContact) {
  Mesh unfitted = walls::make_vane_head({0, 0, 0.01}, {0, 0, 1}, 0.01, 0.004, 4);
  auto wall = walls::make_wall("head", unfitted);
  wall.velocity = {0.01, 0, -0.02};
  wall.omega = {0, 0, 3.0};
  for (int s = 0; s < 100; ++s) walls::advance(wall, 1e-3);
  const Mesh& fitted = std::get<Mesh>(wall.shape);
  ASSERT_TRUE(fitted.fitted);
  unfitted.vertices = fitted.vertices;
  Mesh refit = fitted;
  refit.fit_bounds();
  EXPECT_EQ(fitted.lo, refit.lo);
  EXPECT_EQ(fitted.hi, refit.hi);
  int touching = 0;
  for (double x = -0.014; x <= 0.016; x += 0.0013)
    for (double y = -0.014; y <= 0.014; y += 0.0013)
      for (double z = -0.006; z <= 0.012; z += 0.0011) {
        WallGeometry a[Mesh::kMaxContacts], b[Mesh::kMaxContacts];
        const int na = walls::mesh_contacts(fitted, {x, y, z}, 0.001, 1e-4, a);
        ASSERT_EQ(na, walls::mesh_contacts(unfitted, {x, y, z}, 0.001, 1e-4, b));
        for (int c = 0; c < na; ++c) EXPECT_EQ(a[c].delta, b[c].delta);
        touching += na > 0;
      }
  EXPECT_GT(touching, 100);
}

// The force kernel looks only at the triangles listed for a particle (mesh_candidates, with the
// reach of its contact plus a margin for later movement): the same contacts to the bit as among
// all triangles, from the candidates listed at the point itself and at a point a margin away;
// on average a point lists a small share of the head's triangles (3.3 of 48 here; all of them
// only on its axis, where the disk's fan meets).
TEST(MeshWalls, TheCandidateTrianglesOfAPointGiveEveryContact) {
  const Mesh head = walls::make_vane_head({0, 0, 0.01}, {0, 0, 1}, 0.01, 0.004, 8, 32);
  const double r = 0.001, range = 1e-4, margin = 3e-4;
  int touching = 0;
  double listed = 0.0, lists = 0.0;
  for (double x = -0.012; x <= 0.012; x += 0.0011)
    for (double y = -0.012; y <= 0.012; y += 0.0011)
      for (double z = 0.004; z <= 0.012; z += 0.0007) {
        const Vec3 p{x, y, z};
        WallGeometry all[Mesh::kMaxContacts];
        const int n = walls::mesh_contacts(head, p, r, range, all);
        for (const Vec3& listed_at : {p, p + Vec3{0.6, -0.5, 0.62} * margin}) {
          std::vector<int> candidates;
          walls::mesh_candidates(head, listed_at, r + range + margin, candidates);
          listed += static_cast<double>(candidates.size());
          lists += 1.0;
          WallGeometry some[Mesh::kMaxContacts];
          ASSERT_EQ(walls::mesh_contacts(head, candidates, p, r, range, some), n);
          for (int c = 0; c < n; ++c) {
            EXPECT_EQ(some[c].delta, all[c].delta);
            EXPECT_EQ(some[c].n, all[c].n);
            EXPECT_EQ(some[c].point, all[c].point);
          }
        }
        touching += n > 0;
      }
  EXPECT_GT(touching, 100);
  EXPECT_LT(listed / lists, 0.25 * static_cast<double>(head.size()));
}

}  // namespace
}  // namespace demcal
