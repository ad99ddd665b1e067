// Peer test: LIGGGHTS 3.8 (Debian's `liggghts`) and `demcal contact` run the same single-contact
// experiments (the scripts of tests/data/liggghts/, copied from the shared peer folder) and must
// agree to 1e-6 relative.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "tests/common/command.hpp"
#include "tests/contact/contact_test_util.hpp"

namespace demcal {
namespace {

namespace fs = std::filesystem;

fs::path peer_dir() {
  return fs::path(DEMCAL_SOURCE_DIR) / "tests" / "data" / "liggghts";
}

/// Runs a LIGGGHTS input in a scratch directory (its output goes to ../out relative to it).
std::string run_liggghts(const std::string& script, const std::string& vars, fs::path& scratch) {
  scratch = fs::temp_directory_path() / ("demcal_peer_" + std::to_string(::getpid()));
  fs::create_directories(scratch / "run");
  fs::create_directories(scratch / "out");
  fs::copy_file(peer_dir() / script, scratch / "run" / script,
                fs::copy_options::overwrite_existing);
  // LIGGGHTS loses its messages when stdout is not a terminal: run it under script(1).
  return test::run_command("cd '" + (scratch / "run").string() + "' && script -qc 'liggghts -in " +
                           script + " " + vars + "' /dev/null 2>&1")
      .out;
}

double result_field(const std::string& log, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(log, m, std::regex(key + "=([-+0-9.eE]+)"))) return NAN;
  return std::stod(m[1]);
}

class PeerLiggghts : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(test::run_command("command -v liggghts").out.empty())
        << "LIGGGHTS is not installed: scripts/setup installs Debian's liggghts package";
    ASSERT_TRUE(fs::exists(peer_dir())) << peer_dir();
  }
};

TEST_F(PeerLiggghts, LinearCollisionRestitutionAgrees) {
  fs::path scratch;
  const std::string log =
      run_liggghts("in.collision_hooke", "-var v0 0.5 -var gn 9859.895661", scratch);
  const double e_liggghts = result_field(log, "e_measured");
  ASSERT_TRUE(std::isfinite(e_liggghts)) << log;
  // gamman = 9859.895661 1/s per effective mass -> xi = gamman sqrt(m*) / (2 sqrt(kn)).
  const double m_star = test::sphere_mass(1e-3, 2500.0) / 2.0;
  const double xi = 9859.895661 * std::sqrt(m_star) / (2.0 * std::sqrt(1e4));
  char yaml[1024];
  std::snprintf(yaml, sizeof yaml, R"(
contact_law:
  normal: {model: linear, kn: 1.0e4, damping_ratio: %.17g, damp_approach_only: 0, clip_attraction: 0}
  tangential: {model: history, mu_s: 0.5}
bodies:
  - {radius: 0.001, density: 2500, position: [-0.0011, 0, 0], velocity: [0.5, 0, 0]}
  - {radius: 0.001, density: 2500, position: [0.0011, 0, 0], velocity: [-0.5, 0, 0]}
time_step: 1.0e-7
end_time: 5.0e-4
)",
                xi);
  const auto sum = test::run_contact(yaml);
  EXPECT_NEAR(sum.restitution, e_liggghts, 1e-6 * e_liggghts);
  fs::remove_all(scratch);
}

TEST_F(PeerLiggghts, HertzCollisionRestitutionAgrees) {
  fs::path scratch;
  const std::string log = run_liggghts("in.collision_hertz", "-var v0 0.5 -var e 0.5", scratch);
  const double e_liggghts = result_field(log, "e_measured");
  ASSERT_TRUE(std::isfinite(e_liggghts)) << log;
  const auto sum = test::run_contact(R"(
contact_law:
  normal: {model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 0.5}
  tangential: {model: history, mu_s: 0.5}
bodies:
  - {radius: 0.001, density: 2500, position: [-0.0011, 0, 0], velocity: [0.5, 0, 0]}
  - {radius: 0.001, density: 2500, position: [0.0011, 0, 0], velocity: [-0.5, 0, 0]}
time_step: 1.0e-7
end_time: 8.0e-4
)");
  EXPECT_NEAR(sum.restitution, e_liggghts, 1e-6 * e_liggghts);
  fs::remove_all(scratch);
}

// The Luding overlap path: LIGGGHTS' `model luding` writes (step, overlap, Fn) every 10 steps;
// `demcal contact` drives the same path with the same step.
TEST_F(PeerLiggghts, LudingOverlapPathForcesAgree) {
  fs::path scratch;
  run_liggghts("in.luding_cycle", "-var hyst 0", scratch);
  std::ifstream in(scratch / "out" / "luding_cycle_hyst0.txt");
  ASSERT_TRUE(in) << "LIGGGHTS wrote no force-overlap file";
  std::map<long, std::pair<double, double>> peer;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    long step;
    double delta, fn;
    ss >> step >> delta >> fn;
    peer[step] = {delta, fn};
  }
  ASSERT_GT(peer.size(), 4000u);
  std::vector<lab::SingleContactSample> samples;
  test::run_contact(test::luding_path_example(), &samples);
  // LIGGGHTS moves the driven sphere as x0 + v t, demcal adds v dt each step: the overlaps differ
  // by rounding (~1e-15 m), which shifts a force crossing zero by up to k2 times that. The
  // tolerance is 1e-6 relative plus k2 * 1e-14 m for this rounding.
  const double k2 = 5e4, rounding = k2 * 1e-14;
  int compared = 0;
  for (const auto& [step, p] : peer) {
    ASSERT_LE(static_cast<std::size_t>(step), samples.size());
    const auto& s = samples[step - 1];
    ASSERT_NEAR(s.overlap, p.first, 1e-6 * std::abs(p.first) + 1e-15) << "step " << step;
    ASSERT_NEAR(s.fn, p.second, 1e-6 * std::abs(p.second) + rounding) << "step " << step;
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<int>(peer.size()));
  fs::remove_all(scratch);
}

}  // namespace
}  // namespace demcal
