// LIGGGHTS data files (core/io/liggghts_data): a written bed reads back exactly (positions,
// radii, densities, materials, velocities, box); without velocities it reads back at rest; a
// malformed line names the file and line; a scene takes its particles from a data file and a
// wall from an STL and reads its phases' record_every.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/common/error.hpp"
#include "core/io/liggghts_data.hpp"
#include "core/io/scene_yaml.hpp"
#include "core/io/stl.hpp"
#include "core/walls/mesh.hpp"

namespace demcal::io {
namespace {

namespace fs = std::filesystem;

class LiggghtsData : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("demcal_data_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

particles::ParticleStore three_spheres() {
  particles::ParticleStore p;
  p.add_sphere({0.1, -0.2, 0.3}, 1.0e-3, 2500.0, 0);
  p.add_sphere({1.0 / 3.0, 2.0 / 7.0, 1e-9}, 1.1e-3, 1234.5678, 1);
  p.add_sphere({-5e-3, 4e-3, 2.5e-2}, 0.9e-3, 2500.0, 0);
  p.v[1] = {0.5, -1.0 / 3.0, 2.0};
  p.omega[2] = {10.0, 0.0, -7.0 / 9.0};
  return p;
}

const DataBox kBox{{-0.01, -0.02, 0.0}, {0.01, 0.02, 0.05}};

TEST_F(LiggghtsData, RoundTripIsExact) {
  const auto out = three_spheres();
  write_liggghts_data(file("bed.data"), out, kBox, true);
  particles::ParticleStore in;
  const DataBox box = read_liggghts_data(file("bed.data"), in);
  EXPECT_EQ(box.lo, kBox.lo);
  EXPECT_EQ(box.hi, kBox.hi);
  ASSERT_EQ(in.size(), out.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(in.x[i], out.x[i]) << i;
    EXPECT_EQ(in.radius[i], out.radius[i]) << i;
    EXPECT_NEAR(in.mass[i], out.mass[i], 1e-15 * out.mass[i]) << i;
    EXPECT_EQ(in.material[i], out.material[i]) << i;
    EXPECT_EQ(in.v[i], out.v[i]) << i;
    EXPECT_EQ(in.omega[i], out.omega[i]) << i;
  }
}

TEST_F(LiggghtsData, WithoutVelocitiesReadsAtRest) {
  write_liggghts_data(file("bed.data"), three_spheres(), kBox, false);
  particles::ParticleStore in;
  read_liggghts_data(file("bed.data"), in);
  ASSERT_EQ(in.size(), 3u);
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(in.v[i], Vec3{}) << i;
    EXPECT_EQ(in.omega[i], Vec3{}) << i;
  }
}

TEST_F(LiggghtsData, MalformedAtomLineNamesFileAndLine) {
  std::ofstream(file("bad.data")) << "title\n\n2 atoms\n1 atom types\n\n"
                                     "-1 1 xlo xhi\n-1 1 ylo yhi\n0 1 zlo zhi\n\nAtoms\n\n"
                                     "1 1 0.002 2500 0 0 0.001\n2 1 0.002 2500 0.5\n";
  particles::ParticleStore in;
  try {
    read_liggghts_data(file("bad.data"), in);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), file("bad.data") + ":13");
  }
}

TEST_F(LiggghtsData, SceneReadsDataFileMeshWallAndRecordEvery) {
  write_liggghts_data(file("bed.data"), three_spheres(), kBox, true);
  write_stl_ascii(file("piston.stl"), walls::make_disk({0, 0, 0.03}, {0, 0, -1}, 0.01, 8));
  std::ofstream(file("scene.yaml")) << R"(time_step: 1.0e-6
density: 2500
contact_law:
  normal: {model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3}
  tangential: {model: history, mu_s: 0.5}
walls:
  - {name: piston, mesh: {stl: piston.stl}, velocity: [0, 0, -0.01]}
particles: {data_file: bed.data}
phases:
  - {name: press, steps: 10, record_every: 5}
)";
  const Scene scene = read_scene(YamlNode::load_file(file("scene.yaml")));
  ASSERT_EQ(scene.world.particles.size(), 3u);
  EXPECT_EQ(scene.world.particles.v[1], three_spheres().v[1]);
  ASSERT_EQ(scene.world.walls.size(), 1u);
  EXPECT_EQ(std::get<walls::Mesh>(scene.world.walls[0].shape).size(), 8u);
  EXPECT_EQ(scene.world.walls[0].velocity, (Vec3{0, 0, -0.01}));
  ASSERT_EQ(scene.phases.size(), 1u);
  EXPECT_EQ(scene.phases[0].record_every, 5);
}

}  // namespace
}  // namespace demcal::io
