// Input errors of the YAML readers (io/scene_yaml, io/contact_law_yaml, the single-contact lab):
// an unknown field, an unknown model, a parameter out of range and a wrong type each throw
// demcal::InputError whose message names the file and line and the field path.
#include <gtest/gtest.h>

#include <string>

#include "core/common/error.hpp"
#include "core/io/contact_law_yaml.hpp"
#include "core/io/scene_yaml.hpp"
#include "core/lab/single_contact.hpp"

namespace demcal::io {
namespace {

// Line numbers below refer to this text (1-based).
const std::string kScene = R"(threads: 1
seed: 3
time_step: 1.0e-6
gravity: [0, 0, -9.81]
density: 2500
contact_law:
  normal: {model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3}
  tangential: {model: history, mu_s: 0.5}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
particles:
  list:
    - {radius: 0.001, position: [0, 0, 0.002]}
phases:
  - {name: run, steps: 10}
)";

/// kScene with line `line` (1-based) replaced.
std::string with_line(const std::string& text, int line, const std::string& replacement) {
  std::string out;
  int current = 1;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    const std::string l = text.substr(start, end - start);
    out += (current == line ? replacement : l) + "\n";
    ++current;
    start = end + 1;
  }
  return out;
}

/// The message of the InputError `f` throws (fails the test if it does not).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an InputError: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no error thrown";
  return {};
}

std::string scene_error(const std::string& text) {
  return error_of([&] { read_scene(YamlNode::load_string(text, "spec.yaml")); });
}

void expect_contains(const std::string& msg, const std::string& part) {
  EXPECT_NE(msg.find(part), std::string::npos) << "'" << part << "' not in: " << msg;
}

TEST(IoYamlErrors, ValidSceneReads) {
  const Scene s = read_scene(YamlNode::load_string(kScene, "spec.yaml"));
  EXPECT_EQ(s.world.particles.size(), 1u);
  EXPECT_EQ(s.world.walls.size(), 1u);
  EXPECT_EQ(s.world.dt, 1e-6);
  ASSERT_EQ(s.phases.size(), 1u);
  EXPECT_EQ(s.phases[0].steps, 10);
  EXPECT_EQ(s.world.particles_per_thread, sim::World::kParticlesPerThread);
  const Scene fine = read_scene(YamlNode::load_string(
      with_line(kScene, 1, "threads: 2\nparticles_per_thread: 1"), "spec.yaml"));
  EXPECT_EQ(fine.world.particles_per_thread, 1);
}

TEST(IoYamlErrors, SceneUnknownField) {
  const std::string top = scene_error(with_line(kScene, 4, "gravty: [0, 0, -9.81]"));
  expect_contains(top, "spec.yaml:4");
  expect_contains(top, "gravty");
  expect_contains(top, "unknown field");

  const std::string wall = scene_error(with_line(
      kScene, 10, "  - {name: floor, colour: red, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}"));
  expect_contains(wall, "spec.yaml:10");
  expect_contains(wall, "walls[0].colour");

  const std::string body =
      scene_error(with_line(kScene, 13, "    - {radius: 0.001, positon: [0, 0, 0.002]}"));
  expect_contains(body, "spec.yaml:13");
  expect_contains(body, "particles.list[0].positon");
}

TEST(IoYamlErrors, SceneUnknownModel) {
  const std::string msg =
      scene_error(with_line(kScene, 8, "  tangential: {model: coulomb, mu_s: 0.5}"));
  expect_contains(msg, "spec.yaml:8");
  expect_contains(msg, "contact_law.tangential.model");
  expect_contains(msg, "coulomb");
  expect_contains(msg, "history");  // the known models are listed
}

TEST(IoYamlErrors, SceneParameterOutOfRange) {
  const std::string mu =
      scene_error(with_line(kScene, 8, "  tangential: {model: history, mu_s: 20}"));
  expect_contains(mu, "spec.yaml:8");
  expect_contains(mu, "contact_law.tangential.mu_s");
  expect_contains(mu, "outside the valid range");

  const std::string k2 = scene_error(
      with_line(kScene, 7, "  normal: {model: luding, k1: 1.0e4, k2_ratio: 0.5, phi_f: 0.05}"));
  expect_contains(k2, "spec.yaml:7");
  expect_contains(k2, "contact_law.normal.k2_ratio");

  const std::string grain =
      scene_error(with_line(kScene, 1, "threads: 2\nparticles_per_thread: 0"));
  expect_contains(grain, "spec.yaml:2");
  expect_contains(grain, "particles_per_thread");

  const std::string density = scene_error(with_line(kScene, 5, "density: -1"));
  expect_contains(density, "spec.yaml:5");
  expect_contains(density, "density");
}

TEST(IoYamlErrors, AKeyThatIsAListIsAnInputErrorNotACrash) {
  // Found by bench/fuzz.sh (tests/fuzz/regressions/scene_yaml): a flow list as a map key escaped
  // as yaml-cpp's bad conversion and terminated the reader.
  const std::string msg =
      scene_error(with_line(kScene, 8, "  tangential: {model: history, mu_s: 0.5, [x]: 1}"));
  expect_contains(msg, "spec.yaml:8");
  expect_contains(msg, "contact_law.tangential");
  expect_contains(msg, "a key must be a name");
}

TEST(IoYamlErrors, SceneWrongType) {
  const std::string radius =
      scene_error(with_line(kScene, 13, "    - {radius: small, position: [0, 0, 0.002]}"));
  expect_contains(radius, "spec.yaml:13");
  expect_contains(radius, "particles.list[0].radius");
  expect_contains(radius, "expected a number");

  const std::string vec = scene_error(with_line(kScene, 4, "gravity: [0, -9.81]"));
  expect_contains(vec, "spec.yaml:4");
  expect_contains(vec, "gravity");
  expect_contains(vec, "3 numbers");

  const std::string param =
      scene_error(with_line(kScene, 8, "  tangential: {model: history, mu_s: lots}"));
  expect_contains(param, "spec.yaml:8");
  expect_contains(param, "contact_law.tangential.mu_s");
}

TEST(IoYamlErrors, ContactLawReader) {
  const std::string law = R"(contact_law:
  normal:
    model: luding
    k1: 1.0e4
    k2_ratio: 0.5
  tangential: {model: history, mu_s: 0.5}
)";
  auto read = [](const std::string& text) {
    return error_of(
        [&] { read_contact_law(YamlNode::load_string(text, "law.yaml")["contact_law"]); });
  };
  const std::string range = read(law);
  expect_contains(range, "law.yaml:5");
  expect_contains(range, "contact_law.normal.k2_ratio");

  const std::string unknown_param = read(with_line(law, 5, "    k3_ratio: 2"));
  expect_contains(unknown_param, "law.yaml:5");
  expect_contains(unknown_param, "contact_law.normal.k3_ratio");
  expect_contains(unknown_param, "unknown parameter");

  const std::string unknown_slot = read(law + "  damping: {model: none}\n");
  expect_contains(unknown_slot, "law.yaml:7");
  expect_contains(unknown_slot, "contact_law.damping");

  const std::string missing = read(with_line(law, 4, "    youngs_modulus: fast"));
  expect_contains(missing, "law.yaml:4");
  expect_contains(missing, "contact_law.normal.youngs_modulus");
  expect_contains(missing, "expected a number");

  const std::string model = read(with_line(law, 3, "    model: ludding"));
  expect_contains(model, "law.yaml:3");
  expect_contains(model, "contact_law.normal.model");
}

TEST(IoYamlErrors, SingleContactReader) {
  const std::string spec = R"(contact_law:
  normal: {model: linear, kn: 1.0e4, damping_ratio: 0.1}
  tangential: {model: history, mu_s: 0.3}
bodies:
  - {radius: 0.001, density: 2500, position: [0, 0, 0]}
  - {radius: 0.001, density: 2500, position: [0.0021, 0, 0], velocity: [-0.1, 0, 0]}
time_step: 1.0e-6
steps: 100
)";
  auto read = [](const std::string& text) {
    return error_of([&] { lab::read_single_contact(YamlNode::load_string(text, "contact.yaml")); });
  };
  EXPECT_NO_THROW(lab::read_single_contact(YamlNode::load_string(spec, "contact.yaml")));

  const std::string type = read(with_line(
      spec, 6,
      "  - {radius: big, density: 2500, position: [0.0021, 0, 0], velocity: [-0.1, 0, 0]}"));
  expect_contains(type, "contact.yaml:6");
  expect_contains(type, "bodies[1].radius");

  const std::string field = read(with_line(spec, 8, "stepz: 100"));
  expect_contains(field, "contact.yaml:8");
  expect_contains(field, "stepz");

  const std::string range =
      read(with_line(spec, 2, "  normal: {model: linear, kn: 1.0e4, damping_ratio: 1.5}"));
  expect_contains(range, "contact.yaml:2");
  expect_contains(range, "contact_law.normal.damping_ratio");

  const std::string model = read(with_line(spec, 3, "  tangential: {model: sticky, mu_s: 0.3}"));
  expect_contains(model, "contact.yaml:3");
  expect_contains(model, "contact_law.tangential.model");

  const std::string mode = read(spec + "mode: wobble\n");
  expect_contains(mode, "contact.yaml:9");
  expect_contains(mode, "mode");
}

TEST(IoYamlErrors, SyntaxErrorNamesTheLine) {
  const std::string msg =
      error_of([] { YamlNode::load_string("a: 1\nb: [1, 2\nc: 3\n", "bad.yaml"); });
  expect_contains(msg, "bad.yaml:");
  expect_contains(msg, "syntax");
}

}  // namespace
}  // namespace demcal::io
