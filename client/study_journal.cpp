#include "client/study_journal.hpp"

#include <cmath>
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
    : file_(std::move(path)), identity_(std::move(identity)) {
  file_.read([this](const std::string& text, std::size_t line) { take(text, line); },
             "a run of a study journal");
}

void StudyJournalFile::take(const std::string& text, std::size_t line) {
  const auto j = nlohmann::json::parse(text);
  if (line == 1) {
    if (j.value("study", nlohmann::json()) != identity_)
      throw InputError(file_.path().string(),
                       "holds the runs of another study (its spec, axis, --threads or the "
                       "test's lab protocol version differ): remove it or give another --out");
    return;
  }
  const double value = j.at("value").get<double>();
  if (!std::isfinite(value)) throw std::invalid_argument("value must be finite");
  auto r = replicate_from(j);
  done_[{value, r.seed}] = std::move(r);
}

void StudyJournalFile::append(double value, const lab::StudyReplicate& r) {
  std::vector<std::string> lines;
  if (file_.lines() == 0) lines.push_back(nlohmann::json{{"study", identity_}}.dump());
  lines.push_back(nlohmann::json{{"value", value},
                                 {"seed", r.seed},
                                 {"metrics", r.metrics},
                                 {"flags", r.flags},
                                 {"wall_seconds", r.wall_seconds}}
                      .dump());
  file_.append(lines);
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
