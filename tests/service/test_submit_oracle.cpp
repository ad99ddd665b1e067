// The store-backed oracle of Submit (tests/fuzz/submit_oracle.hpp) over the example campaigns and
// structured mutations of them: one to three fields anywhere in the request set to the values a
// careless or hostile client sends (NaN, infinities, huge and negative numbers, empty, long or
// escape-laden strings, unknown enum values, repeated entries dropped or duplicated). Every
// answer must hold the oracle: refused requests leave the store as it was, accepted ones are
// stored as sent with jobs every worker would run. The libFuzzer harness fuzz_submit runs the
// same oracle on arbitrary bytes (bench/fuzz.sh).
#include <google/protobuf/descriptor.h>
#include <google/protobuf/reflection.h>
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <limits>
#include <random>

#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "tests/fuzz/submit_oracle.hpp"

namespace demcal::test {
namespace {

namespace fs = std::filesystem;
namespace pb = google::protobuf;

std::vector<v1::SubmitRequest> example_requests() {
  std::vector<v1::SubmitRequest> out;
  for (const auto& entry : fs::directory_iterator(fs::path(DEMCAL_SOURCE_DIR) / "examples")) {
    const auto name = entry.path().filename().string();
    if (entry.path().extension() != ".yaml" || name.find("campaign") == std::string::npos) continue;
    v1::SubmitRequest r;
    *r.mutable_spec() = cli::read_campaign_spec(entry.path().string()).spec;
    out.push_back(r);
  }
  return out;
}

template <class T>
T pick(const std::vector<T>& values, std::mt19937_64& rng) {
  return values[rng() % values.size()];
}

void mutate_scalar(pb::Message& m, const pb::FieldDescriptor* f, std::mt19937_64& rng) {
  const pb::Reflection* r = m.GetReflection();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> reals = {std::nan(""), inf, -inf, 0.0, -1.0, 1e308, 1e-300, 3.5};
  const std::vector<std::int64_t> ints = {0, -1, 1, 7, 100000, std::numeric_limits<int>::max()};
  const std::vector<std::string> texts = {"",    std::string(5000, 'a'),   "\x1b[31mred",
                                          "x.y", "particle_law.normal.k1", "rotating_drum"};
  switch (f->cpp_type()) {
    case pb::FieldDescriptor::CPPTYPE_DOUBLE:
      return r->SetDouble(&m, f, pick(reals, rng));
    case pb::FieldDescriptor::CPPTYPE_FLOAT:
      return r->SetFloat(&m, f, static_cast<float>(pick(reals, rng)));
    case pb::FieldDescriptor::CPPTYPE_INT32:
      return r->SetInt32(&m, f, static_cast<std::int32_t>(pick(ints, rng)));
    case pb::FieldDescriptor::CPPTYPE_INT64:
      return r->SetInt64(&m, f, pick(ints, rng));
    case pb::FieldDescriptor::CPPTYPE_UINT32:
      return r->SetUInt32(&m, f, static_cast<std::uint32_t>(pick(ints, rng)));
    case pb::FieldDescriptor::CPPTYPE_UINT64:
      return r->SetUInt64(&m, f, static_cast<std::uint64_t>(pick(ints, rng)));
    case pb::FieldDescriptor::CPPTYPE_BOOL:
      return r->SetBool(&m, f, !r->GetBool(m, f));
    case pb::FieldDescriptor::CPPTYPE_ENUM:
      return r->SetEnumValue(&m, f, static_cast<int>(rng() % 6) - 1);
    case pb::FieldDescriptor::CPPTYPE_STRING:
      return r->SetString(&m, f, pick(texts, rng));
    case pb::FieldDescriptor::CPPTYPE_MESSAGE:
      return;
  }
}

/// One field somewhere under `m` changed: a scalar set to an edge value, a message entered (or
/// created), a repeated field's element dropped, duplicated or entered.
void mutate(pb::Message& m, std::mt19937_64& rng, int depth = 0) {
  const pb::Descriptor* d = m.GetDescriptor();
  if (d->field_count() == 0) return;
  const pb::FieldDescriptor* f = d->field(static_cast<int>(rng() % d->field_count()));
  const pb::Reflection* r = m.GetReflection();
  if (!f->is_repeated()) {
    if (f->cpp_type() != pb::FieldDescriptor::CPPTYPE_MESSAGE) return mutate_scalar(m, f, rng);
    if (depth < 8) mutate(*r->MutableMessage(&m, f), rng, depth + 1);
    return;
  }
  const int n = r->FieldSize(m, f);
  const bool message = f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE;
  switch (n == 0 ? 2 : rng() % 3) {
    case 0:
      r->RemoveLast(&m, f);
      return;
    case 1:
      if (message && !f->is_map() && depth < 8)
        return mutate(*r->MutableRepeatedMessage(&m, f, static_cast<int>(rng() % n)), rng,
                      depth + 1);
      if (message) r->AddMessage(&m, f)->CopyFrom(r->GetRepeatedMessage(m, f, 0));
      return;
    default:
      if (message) {
        pb::Message* added = r->AddMessage(&m, f);
        if (n > 0) added->CopyFrom(r->GetRepeatedMessage(m, f, 0));
        if (depth < 8) mutate(*added, rng, depth + 1);
      } else if (f->cpp_type() == pb::FieldDescriptor::CPPTYPE_STRING) {
        r->AddString(&m, f, n > 0 ? r->GetRepeatedString(m, f, 0) : "a");
      } else if (f->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE) {
        r->AddDouble(&m, f, std::nan(""));
      }
  }
}

TEST(SubmitOracle, TheExamplesAreAcceptedAndStoredAsSent) {
  spdlog::set_level(spdlog::level::warn);
  SubmitOracle oracle;
  const auto requests = example_requests();
  ASSERT_GE(requests.size(), 3u);
  for (const auto& r : requests) {
    const auto out = oracle.submit(r);
    EXPECT_TRUE(out.accepted) << r.spec().name();
    EXPECT_EQ(out.broken, "") << r.spec().name();
  }
}

// A field this build does not know (a newer client's) is refused naming where it is, never
// dropped silently from the spec that is stored and run (found by fuzz_submit).
TEST(SubmitOracle, AFieldTheCoordinatorDoesNotKnowIsRefusedNamingWhereItIs) {
  v1::SubmitRequest r = example_requests().front();
  r.mutable_spec()
      ->mutable_material()
      ->mutable_particle_law()
      ->mutable_cohesion()
      ->GetReflection()
      ->MutableUnknownFields(
          r.mutable_spec()->mutable_material()->mutable_particle_law()->mutable_cohesion())
      ->AddFixed64(2, 42);
  std::vector<server::NewJob> jobs;
  try {
    server::plan_campaign(r.spec(), jobs);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "spec.material.particle_law.cohesion");
    EXPECT_NE(e.message().find("field number 2"), std::string::npos) << e.message();
  }
  SubmitOracle oracle;
  EXPECT_FALSE(oracle.submit(r).accepted);
}

TEST(SubmitOracle, MutatedRequestsHoldTheOracle) {
  spdlog::set_level(spdlog::level::off);
  SubmitOracle oracle;
  const auto requests = example_requests();
  std::mt19937_64 rng(43);
  int accepted = 0, refused = 0;
  for (int k = 0; k < 600; ++k) {
    v1::SubmitRequest r = requests[static_cast<std::size_t>(k) % requests.size()];
    for (int m = 0, n = 1 + static_cast<int>(rng() % 3); m < n; ++m) mutate(r, rng);
    // As gRPC hands it over: a map's duplicate keys collapse to the last on the wire.
    ASSERT_TRUE(r.ParseFromString(r.SerializeAsString()));
    const auto out = oracle.submit(r);
    (out.accepted ? accepted : refused)++;
    EXPECT_EQ(out.broken, "") << "mutation " << k << " of " << r.spec().name() << ":\n"
                              << r.ShortDebugString().substr(0, 4000);
  }
  std::cout << accepted << " mutated requests accepted, " << refused << " refused\n";
  EXPECT_GE(accepted, 60);
  EXPECT_GE(refused, 60);
}

}  // namespace
}  // namespace demcal::test
