#include "client/service_client.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "client/format.hpp"
#include "core/common/error.hpp"
#include "core/common/relative_error.hpp"

namespace demcal::cli {
namespace {

std::string duration(double s) {
  if (s < 0 || !std::isfinite(s)) return "--:--";
  const long t = std::lround(s);
  std::ostringstream o;
  if (t >= 3600) o << t / 3600 << ":";
  o << std::setw(t >= 3600 ? 2 : 1) << std::setfill('0') << (t % 3600) / 60 << ":" << std::setw(2)
    << std::setfill('0') << t % 60;
  return o.str();
}

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

void add_connection_options(CLI::App& cmd, rpc::ChannelOptions& o) {
  o.address = "127.0.0.1:7311";
  cmd.add_option("--coordinator", o.address, "host:port of demcal-server")
      ->envname("DEMCAL_COORDINATOR")
      ->capture_default_str();
  cmd.add_option("--token", o.token,
                 "bearer token (visible in the process list: prefer "
                 "--token-file or DEMCAL_TOKEN)")
      ->envname("DEMCAL_TOKEN");
  cmd.add_option_function<std::string>(
      "--token-file",
      [&o](const std::string& file) {
        try {
          o.token = rpc::read_token_file(file);
        } catch (const std::exception& e) {
          throw InputError("--token-file", e.what());  // never "no token": exit code 2
        }
      },
      "read the bearer token from the first line of this file");
  cmd.add_option("--tls-ca", o.tls_ca, "CA certificate (PEM) for a TLS coordinator");
  cmd.add_flag("--insecure", o.insecure, "plain TCP (coordinator started with --insecure)");
}

std::unique_ptr<v1::CampaignService::Stub> campaign_stub(const rpc::ChannelOptions& o) {
  return v1::CampaignService::NewStub(rpc::make_channel(o));
}

void check(const grpc::Status& s, const std::string& what) {
  if (s.ok()) return;
  if (s.error_code() == grpc::StatusCode::INVALID_ARGUMENT) throw InputError("", s.error_message());
  static const char* names[] = {"OK",
                                "CANCELLED",
                                "UNKNOWN",
                                "INVALID_ARGUMENT",
                                "DEADLINE_EXCEEDED",
                                "NOT_FOUND",
                                "ALREADY_EXISTS",
                                "PERMISSION_DENIED",
                                "RESOURCE_EXHAUSTED",
                                "FAILED_PRECONDITION",
                                "ABORTED",
                                "OUT_OF_RANGE",
                                "UNIMPLEMENTED",
                                "INTERNAL",
                                "UNAVAILABLE",
                                "DATA_LOSS",
                                "UNAUTHENTICATED"};
  const int c = static_cast<int>(s.error_code());
  throw std::runtime_error(what + ": " + (c >= 0 && c <= 16 ? names[c] : "?") + ": " +
                           s.error_message());
}

std::string state_name(v1::CampaignState s) {
  switch (s) {
    case v1::RUNNING:
      return "running";
    case v1::DONE:
      return "done";
    case v1::CANCELLED:
      return "cancelled";
    default:
      return "?";
  }
}

void print_design_summary(std::ostream& out, const v1::DesignSummary& d) {
  out << "design: " << d.description() << "\n  " << d.runs() << " runs, " << d.jobs()
      << " jobs, resolution " << d.resolution();
  if (!d.generators().empty()) out << ", generators " << d.generators();
  out << "\n  factors:\n";
  for (const auto& f : d.factor_letters()) out << "    " << f << "\n";
  if (d.defining_relation_size()) {
    out << "  defining relation: I";
    for (const auto& w : d.defining_relation()) out << " = " << w;
    out << "\n";
  }
  if (d.main_effect_alias_chains_size()) {
    out << "  main effects aliased with 2FIs:\n";
    for (const auto& c : d.main_effect_alias_chains()) out << "    " << c << "\n";
  }
  if (d.two_factor_alias_chains_size()) {
    out << "  2FI alias chains (" << d.two_factor_alias_chains_size() << "):\n";
    for (const auto& c : d.two_factor_alias_chains()) out << "    " << c << "\n";
  }
  out << "  clear 2FIs: " << d.clear_two_factor_interactions_size();
  if (d.clear_two_factor_interactions_size()) {
    out << " (";
    for (int i = 0; i < d.clear_two_factor_interactions_size(); ++i)
      out << (i ? " " : "") << d.clear_two_factor_interactions(i);
    out << ")";
  }
  out << "\n";
}

std::string progress_line(const v1::Progress& p, int width) {
  const double total = std::max<double>(1, double(p.total() - p.cancelled()));
  const double finished = double(p.done() + p.failed());
  const int filled = static_cast<int>(std::lround(width * finished / total));
  std::ostringstream s;
  s << "[" << std::string(std::size_t(filled), '#') << std::string(std::size_t(width - filled), '.')
    << "] " << p.done() + p.failed() << "/" << p.total() - p.cancelled() << " done";
  if (p.failed()) s << " (" << p.failed() << " failed)";
  if (p.reused()) s << " (" << p.reused() << " reused)";
  s << ", " << p.leased() << " running, elapsed " << duration(p.elapsed_seconds()) << ", ETA "
    << duration(p.eta_seconds());
  return s.str();
}

v1::Progress watch_campaign(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& o,
                            std::int64_t id, std::ostream& out) {
  const bool tty = isatty(STDERR_FILENO) && &out == &std::cerr;
  v1::Progress last;
  for (int reconnects = 0;; ++reconnects) {
    auto ctx = rpc::make_context(o, 7 * 24 * 3600.0);
    v1::WatchRequest req;
    req.set_id(id);
    auto reader = stub.Watch(ctx.get(), req);
    v1::Progress p;
    while (reader->Read(&p)) {
      last = p;
      out << (tty ? "\r" : "") << progress_line(p) << (tty ? "   " : "\n") << std::flush;
    }
    const auto s = reader->Finish();
    if (s.ok()) break;
    if (s.error_code() != grpc::StatusCode::UNAVAILABLE || reconnects > 100) check(s, "watch");
    std::this_thread::sleep_for(std::chrono::seconds(1));  // coordinator restarting
  }
  if (tty) out << "\n";
  return last;
}

nlohmann::ordered_json analysis_json(const v1::MetricEffects& m) {
  return nlohmann::ordered_json::parse(message_json(m));
}

nlohmann::ordered_json effects_json(const v1::EffectsReply& e) {
  nlohmann::ordered_json j = {
      {"factor_letters",
       std::vector<std::string>(e.factor_letters().begin(), e.factor_letters().end())},
      {"metrics", nlohmann::ordered_json::array()}};
  for (const auto& m : e.metrics()) j["metrics"].push_back(analysis_json(m));
  return j;
}

void print_effects(std::ostream& out, const v1::EffectsReply& e, const std::string& format) {
  if (format == "json") {
    out << effects_json(e).dump(2) << "\n";
    return;
  }
  if (format == "csv") {
    out << "metric,chain,effect,active_me,active_sme,pse,me,sme\n";
    for (const auto& m : e.metrics())
      for (const auto& x : m.effects())
        out << csv_quote(m.metric()) << "," << csv_quote(x.chain()) << "," << std::setprecision(10)
            << x.effect() << "," << x.active_me() << "," << x.active_sme() << "," << m.pse() << ","
            << m.me() << "," << m.sme() << "\n";
    return;
  }
  out << "factors:\n";
  for (const auto& f : e.factor_letters()) out << "  " << f << "\n";
  for (const auto& m : e.metrics()) {
    out << "\n== " << m.metric() << " (" << m.runs_used() << " of " << m.runs_total()
        << " runs) ==\n";
    if (m.effects_size() == 0) {
      for (const auto& n : m.notes()) out << "  " << n << "\n";
      continue;
    }
    out << "  Lenth on the " << m.lenth_terms() << " model terms: PSE " << fmt(m.pse()) << ", ME "
        << fmt(m.me()) << ", SME " << fmt(m.sme()) << " (t with " << fmt(m.lenth_df(), 3)
        << " df);  ** > SME, * > ME, (r) residual contrast outside the model\n";
    out << "  " << std::setw(13) << "effect"
        << "  sig  alias chain\n";
    for (const auto& x : m.effects())
      out << "  " << std::setw(13) << fmt(x.effect()) << "  "
          << (x.active_sme()  ? "** "
              : x.active_me() ? "*  "
                              : "   ")
          << "  " << x.chain() << (x.in_model() ? "" : " (r)") << "\n";
    out << "  mean " << fmt(m.intercept()) << ", R^2 " << fmt(m.r_squared(), 4);
    out << "\n  noise: ";
    if (m.noise_df() > 0)
      out << "sd " << fmt(m.noise_sd()) << " with " << fmt(m.noise_df(), 3) << " df, "
          << m.noise_source();
    else
      out << m.noise_source();
    out << "\n  curvature: ";
    if (m.curvature_available())
      out << "factorial - centre mean " << fmt(m.curvature_difference())
          << ", t = " << fmt(m.curvature_t(), 3) << " (" << fmt(m.curvature_df(), 3)
          << " df), p = " << fmt(m.curvature_p(), 3) << " against " << m.curvature_error()
          << (m.curvature_significant() ? " (significant)" : " (not significant)");
    else
      out << "not tested (needs centre points and a noise estimate)";
    out << "\n";
  }
}

void print_rounds(std::ostream& out,
                  const google::protobuf::RepeatedPtrField<v1::CalibrationRound>& rounds) {
  if (rounds.empty()) return;
  out << "\n  calibration rounds:\n";
  for (const auto& r : rounds) {
    out << "    round " << r.round() << " (stage " << r.stage() << ", batch " << r.batch()
        << "): " << r.state();
    if (r.state() == "done")
      out << ", " << (r.within() ? "within" : "not within") << " tolerance; worst "
          << r.worst_metric() << " at " << fmt(r.worst_deviation(), 3) << " x tolerance";
    out << "\n      at";
    for (const double v : r.proposed_values()) out << " " << fmt(v, 5);
    out << "\n";
    for (int m = 0; m < r.metrics_size(); ++m)
      out << "      " << std::left << std::setw(34) << r.metrics(m) << std::right << " predicted "
          << std::setw(11) << fmt(r.predicted(m)) << "  simulated "
          << (m < r.simulated_size() ? fmt(r.simulated(m)) : "-") << "\n";
  }
}

namespace {

/// A multi-fidelity campaign: per response the model of its high level (low and high at the
/// rows run at both), and the particle-steps of each level against the all-high design.
void print_fidelity(std::ostream& out, const v1::CalibrateReply& c) {
  if (c.fidelity_size() == 0) return;
  out << "\n  high fidelity level from the low one (docs/doe.md, \"Multi-fidelity "
         "calibration\"):\n";
  for (const auto& f : c.fidelity()) {
    out << "    " << f.statement() << "; correction sd " << f.correction_sd() << "\n";
    for (int i = 0; i < f.rows_size(); ++i)
      out << "      row " << f.rows(i) << ": low " << f.low(i) << ", high " << f.high(i) << "\n";
  }
  print_fidelity_cost(out, c.fidelity_cost());
}

}  // namespace

void print_fidelity_cost(std::ostream& out, const v1::FidelityCost& k) {
  const double design = k.low_particle_steps() + k.high_particle_steps();
  out << "  particle-steps: low " << k.low_particle_steps() << " (" << k.low_jobs()
      << " jobs), high " << k.high_particle_steps() << " (" << k.high_jobs()
      << " jobs), verification " << k.verify_particle_steps() << " (" << k.verify_jobs()
      << " jobs); the design at the high level in every row: " << k.all_high_particle_steps();
  if (k.all_high_particle_steps() > 0)
    out << " (this design: " << std::lround(100.0 * design / k.all_high_particle_steps()) << " %)";
  out << "\n";
}

void print_calibration(std::ostream& out, const v1::CalibrateReply& c, const std::string& format) {
  if (format == "json") {
    out << message_json(c) << "\n";
    return;
  }
  // While a round runs its set is shown with the predictions it was queued with; while a stage's
  // design runs there is no set to show.
  const bool round_running = c.rounds_size() && c.rounds(c.rounds_size() - 1).state() == "running";
  const bool predicted = c.fitted() || round_running;
  if (c.fitted())
    out << "proposed parameter set (objective " << fmt(c.objective(), 4) << "):\n";
  else if (round_running)
    out << "parameter set of calibration round " << c.rounds(c.rounds_size() - 1).round()
        << ", running (the models are refitted once its jobs are done):\n";
  else
    out << "no parameter set: a calibration stage's design is running\n";
  for (int i = 0; i < c.factor_paths_size(); ++i)
    out << "  " << std::left << std::setw(40) << c.factor_paths(i) << std::right << " = "
        << fmt(c.proposed_values(i), 6) << "\n";
  // Each "dev %" follows its value: the relative deviation from the measurement.
  out << "\n  " << std::left << std::setw(36) << "metric" << std::right << std::setw(12)
      << "measured" << std::setw(12) << "predicted" << std::setw(8) << "dev %" << std::setw(12)
      << "simulated" << std::setw(8) << "dev %" << std::setw(11) << "tolerance"
      << "  within  reach [min, max]\n";
  for (const auto& m : c.metrics()) {
    out << "  " << std::left << std::setw(36) << m.metric() << std::right << std::setw(12)
        << fmt(m.target()) << std::setw(12) << (predicted ? fmt(m.predicted()) : "-")
        << std::setw(8) << (predicted ? fmt(100 * m.relative_error(), 3) : "-") << std::setw(12)
        << (m.simulated_available() ? fmt(m.simulated()) : "-") << std::setw(8)
        << (m.simulated_available() ? fmt(100 * relative_error(m.simulated(), m.target()), 3) : "-")
        << std::setw(11) << fmt(m.tolerance(), 3) << "  " << std::setw(6)
        << (m.simulated_available() ? (m.within() ? "yes" : "no") : "-") << "  "
        << (c.fitted() ? "[" + fmt(m.envelope_min()) + ", " + fmt(m.envelope_max()) + "]" : "-")
        << "\n";
    if (!m.statement().empty()) out << "      " << m.statement() << "\n";
  }
  out << "  tolerance = sqrt(uncertainty^2 + noise sd^2) (docs/doe.md); surrogate " << c.surrogate()
      << "\n";
  if (c.intervals_size()) out << "\n  parameters predicted within tolerance:\n";
  for (const auto& i : c.intervals()) out << "    " << i.statement() << "\n";
  if (c.trade_offs_size()) out << "\n  factors the data fix only in combination:\n";
  for (const auto& t : c.trade_offs()) out << "    " << t.statement() << "\n";
  print_fidelity(out, c);
  print_rounds(out, c.rounds());
  out << "  verification: " << c.verification_state() << ", " << c.simulations()
      << " simulation(s) added by the calibration\n  " << c.conclusion() << "\n";
}

v1::CalibrateReply drive_calibration(v1::CampaignService::Stub& stub,
                                     const rpc::ChannelOptions& channel,
                                     const v1::CalibrateRequest& request, std::ostream& progress) {
  for (;;) {
    v1::CalibrateReply reply;
    check(stub.Calibrate(rpc::make_context(channel, 300).get(), request, &reply), "calibrate");
    if (!request.verify() || reply.verification_state() != "running") return reply;
    progress << "calibration: " << reply.conclusion() << "\n";
    watch_campaign(stub, channel, request.id(), progress);
  }
}

}  // namespace demcal::cli
