#include "client/study_journal.hpp"

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "core/common/error.hpp"

namespace demcal::cli {
namespace {

/// A metric as JSON writes it: a number, or null for a value that is not finite.
double metric_value(const nlohmann::json& v) {
  if (v.is_null()) return std::numeric_limits<double>::quiet_NaN();
  return v.get<double>();
}

lab::StudyReplicate replicate_from(const nlohmann::json& j) {
  lab::StudyReplicate r;
  r.seed = j.at("seed").get<std::uint64_t>();
  for (const auto& [name, v] : j.at("metrics").items()) r.metrics[name] = metric_value(v);
  r.flags = j.at("flags").get<std::map<std::string, std::string>>();
  r.wall_seconds = j.at("wall_seconds").get<double>();
  if (!(std::isfinite(r.wall_seconds) && r.wall_seconds >= 0.0))
    throw std::invalid_argument("wall_seconds must be finite and >= 0");
  return r;
}

}  // namespace

StudyJournalFile::StudyJournalFile(std::filesystem::path path, nlohmann::json identity)
    : path_(std::move(path)), identity_(std::move(identity)) {
  if (std::filesystem::exists(path_)) read();
}

void StudyJournalFile::read() {
  std::ifstream in(path_);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string where = path_.string() + ":" + std::to_string(i + 1);
    try {
      const auto j = nlohmann::json::parse(lines[i]);
      if (i == 0) {
        if (j.value("study", nlohmann::json()) != identity_)
          throw InputError(path_.string(),
                           "holds the runs of another study (its spec, axis or --threads "
                           "differ): remove it or give another --out");
        continue;
      }
      const double value = j.at("value").get<double>();
      if (!std::isfinite(value)) throw std::invalid_argument("value must be finite");
      auto r = replicate_from(j);
      done_[{value, r.seed}] = std::move(r);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      if (i + 1 == lines.size() && i > 0) {
        std::cerr << where << ": a run cut short while it was written, dropped\n";
        lines.pop_back();
        rewrite(lines);
        break;
      }
      throw InputError(where, std::string("not a run of a study journal: ") + e.what());
    }
  }
}

void StudyJournalFile::rewrite(const std::vector<std::string>& lines) const {
  std::ofstream out(path_, std::ios::trunc);
  for (const auto& line : lines) out << line << "\n";
  if (!out) throw std::runtime_error("cannot write the study journal " + path_.string());
}

void StudyJournalFile::append(double value, const lab::StudyReplicate& r) {
  const bool fresh = !std::filesystem::exists(path_) || std::filesystem::file_size(path_) == 0;
  std::ofstream out(path_, std::ios::app);
  if (fresh) out << nlohmann::json{{"study", identity_}}.dump() << "\n";
  out << nlohmann::json{{"value", value},
                        {"seed", r.seed},
                        {"metrics", r.metrics},
                        {"flags", r.flags},
                        {"wall_seconds", r.wall_seconds}}
             .dump()
      << "\n"
      << std::flush;
  if (!out) throw std::runtime_error("cannot write the study journal " + path_.string());
  done_[{value, r.seed}] = r;
}

lab::StudyJournal StudyJournalFile::journal() {
  return {[this](double value, std::uint64_t seed) -> std::optional<lab::StudyReplicate> {
            const auto it = done_.find({value, seed});
            if (it == done_.end()) return std::nullopt;
            return it->second;
          },
          [this](double value, const lab::StudyReplicate& r) { append(value, r); }};
}

}  // namespace demcal::cli
