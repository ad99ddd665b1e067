// Writes the seed corpus of fuzz_submit: each campaign spec given on the command line, read by
// the CLI's parser (as `demcal submit` does), serialised as the SubmitRequest the CLI would send.
//   submit_seeds OUT_DIR SPEC.yaml...
#include <filesystem>
#include <fstream>
#include <iostream>

#include "client/spec_yaml.hpp"
#include "demcal/v1/campaign.pb.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: submit_seeds OUT_DIR SPEC.yaml...\n";
    return 2;
  }
  const std::filesystem::path out = argv[1];
  for (int i = 2; i < argc; ++i) {
    demcal::v1::SubmitRequest request;
    try {
      *request.mutable_spec() = demcal::cli::read_campaign_spec(argv[i]).spec;
    } catch (const std::exception& e) {
      std::cerr << e.what() << "\n";
      return 1;
    }
    const auto name = std::filesystem::path(argv[i]).stem().string() + ".pb";
    std::ofstream(out / name, std::ios::binary) << request.SerializeAsString();
  }
  return 0;
}
