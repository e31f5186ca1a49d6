#include "axon/c4g/apps/serve.hpp"

#include "axon/c4g/apps/moni.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <thread>

namespace axon::c4g::apps {

namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

Clock::duration seconds(double s) { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)); }
double s_of(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }

ServeTiming timing_of(const host::Server& server) {
  const auto& t = server.cycle().timing();
  const auto& h = t.cycle_times();
  ServeTiming v;
  v.cycles = t.cycles();
  v.nominal_known = t.nominal_known();
  v.nominal_period_s = s_of(t.nominal_period_ns());
  v.worst_cycle_time_s = s_of(t.worst_cycle_time_ns());
  v.inter_packet_min_s = s_of(t.min_inter_step_ns());
  v.inter_packet_max_s = s_of(t.max_inter_step_ns());
  v.inter_step_p50_s = s_of(t.inter_step_times().percentile(50));
  v.jitter_min_s = s_of(t.min_jitter_ns());
  v.jitter_max_s = s_of(t.max_jitter_ns());
  v.jitter_min_percent = t.min_percent_jitter();
  v.jitter_max_percent = t.max_percent_jitter();
  v.cycle_time_p50_s = s_of(h.percentile(50));
  v.cycle_time_p99_s = s_of(h.percentile(99));
  v.cycle_time_p999_s = s_of(h.percentile(99.9));
  v.cycle_time_max_s = s_of(h.max());
  v.missed_deadlines = t.missed_deadlines();
  v.deadline_s = s_of(t.config().deadline_ns);
  return v;
}

json timing_json(const ServeTiming& t) {
  // Figures relative to the controller's period are null while it is unknown.
  auto relative = [&](const json& v) { return t.nominal_known ? v : json(nullptr); };
  return json{{"cycles", t.cycles},
              {"nominal_period_s", relative(t.nominal_period_s)},
              {"worst_cycle_time_s", t.worst_cycle_time_s},
              {"inter_packet_period_s", {t.inter_packet_min_s, t.inter_packet_max_s}},
              {"inter_step_p50_s", t.inter_step_p50_s},
              {"jitter_s", relative({t.jitter_min_s, t.jitter_max_s})},
              {"jitter_percent", relative({t.jitter_min_percent, t.jitter_max_percent})},
              {"cycle_time_p50_s", t.cycle_time_p50_s},
              {"cycle_time_p99_s", t.cycle_time_p99_s},
              {"cycle_time_p999_s", t.cycle_time_p999_s},
              {"cycle_time_max_s", t.cycle_time_max_s},
              {"missed_deadlines", t.missed_deadlines},
              {"deadline_s", t.deadline_s}};
}

json or_null(const std::string& s) { return s.empty() ? json(nullptr) : json(s); }

}  // namespace

struct ServeSession::Recorder {
  std::unique_ptr<MoniCsvWriter> csv;
};

int ServeReport::exit_code() const noexcept {
  if (safety_fault) return 4;
  return error.empty() ? 0 : 1;
}

std::string ServeReport::json() const {
  const auto& c = stats;
  nlohmann::json j{{"app", app},
                   {"reason", reason},
                   {"app_cycles", app_cycles},
                   {"finished", finished},
                   {"error", error},
                   {"app_summary", app_summary},
                   {"session", {{"controller", or_null(c.controller)}, {"sessions", c.sessions}, {"foreign", c.foreign},
                                {"last_foreign_source", or_null(c.last_foreign_source)}}},
                   {"packets", c.packets},
                   {"init_packets", c.init_packets},
                   {"cyclic_packets", c.cyclic_packets},
                   {"protocol_errors", c.protocol_errors},
                   {"safe_replies", c.safe_replies},
                   {"refused_mode_changes", c.refused_mode_changes},
                   {"controller_late", c.controller_late},
                   {"freezes", c.freezes},
                   {"frozen_cycles", c.frozen_cycles},
                   {"safety_fault", c.safety_fault},
                   {"controller_errors", c.controller_errors},
                   {"currents_clamped", c.currents_clamped},
                   {"timing", timing_json(c.timing)}};
  if (c.csv) {
    j["csv_rows"] = c.csv_rows;
    j["csv_rotations"] = c.csv_rotations;
    j["csv_write_errors"] = c.csv_write_errors;
  }
  if (c.pcap) {
    j["pcap_written"] = c.pcap_written;
    j["pcap_rotations"] = c.pcap_rotations;
    j["pcap_write_failures"] = c.pcap_write_failures;
  }
  return j.dump(2);
}

std::string ServeReport::text() const {
  std::string out = fmt::format("stopped: {}\n{}{}", reason, server_summary, app_summary);
  if (stats.csv)
    out += fmt::format("CSV {}: {} rows (moni type {}), {} rotations, {} write errors\n", csv_path, stats.csv_rows, moni,
                       stats.csv_rotations, stats.csv_write_errors);
  if (!error.empty()) out += fmt::format("error: {}\n", error);
  return out;
}

ServeSession::ServeSession(App& app, ServeOptions options)
    : app_(app), options_(std::move(options)), recorder_(std::make_unique<Recorder>()) {
  if (!options_.csv.empty()) {
    recorder_->csv = MoniCsvWriter::open(options_.csv, options_.moni, options_.csv_rotation).value();
    app_.record_samples(8192);
  }
}

ServeSession::~ServeSession() {
  if (!server_ || stopped_) return;
  try {
    graceful_stop({});
    server_->stop();
  } catch (...) {  // a destructor must not throw; the server's own destructor stops it
  }
}

void ServeSession::start() {
  server_ = host::Server::start(app_, options_.server).value();
  for (const auto& step : server_->realtime_report().steps)
    if (!step.granted) spdlog::warn("c4g serve: {} refused: {}", step.name, step.reason);
}

host::Server& ServeSession::server() {
  if (!server_) throw Exception(Error(CoreErrc::invalid_argument, "c4g serve: the session has not started"));
  return *server_;
}

std::string ServeSession::local_address() const { return server_ ? server_->local_address().to_string() : std::string(); }

std::string ServeSession::status_line() const {
  const auto& t = server_->cycle().timing();
  return fmt::format("status {} | {} | cycle time last {:.1f} us worst {:.1f} us, missed {} | foreign {}", app_.status(),
                     host::to_string(server_->state()), static_cast<double>(t.last_cycle_time_ns()) * 1e-3,
                     static_cast<double>(t.worst_cycle_time_ns()) * 1e-3, t.missed_deadlines(),
                     server_->counters().foreign.load());
}

void ServeSession::pump(const Hooks& hooks) {
  if (const auto peer = server_->peer()) {
    const std::string p = peer->to_string();
    if (p != shown_peer_ && hooks.on_session) hooks.on_session(p);
    shown_peer_ = p;
  } else {
    shown_peer_.reset();
  }
  for (const auto& e : app_.drain_events())
    if (hooks.on_event) hooks.on_event(e, app_.describe(e));
  if (recorder_->csv)
    app_.drain_samples([&](const Sample& s) { recorder_->csv->write(s.cycle, s.wall_ns, s.request, s.reply); });
  if (hooks.on_poll) hooks.on_poll();
}

bool ServeSession::settled() const {
  const auto st = server_->state();
  return app_.quiescent() || st == host::ServerState::silent || st == host::ServerState::waiting || app_.controller_exited() ||
         server_->safety().obeyed();
}

ServeReport ServeSession::run(const Hooks& hooks) {
  if (!server_) start();
  auto interruptions = [&] { return hooks.interruptions ? hooks.interruptions() : 0; };
  const auto began = Clock::now();
  auto next_status = began + seconds(options_.status_interval_s);
  std::string why = "stopped";
  while (true) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    pump(hooks);
    const auto now = Clock::now();
    if (stop_.load(std::memory_order_acquire)) break;
    if (interruptions() > 0) { why = "signal"; break; }
    if (options_.duration_s > 0 && now - began >= seconds(options_.duration_s)) { why = "duration reached"; break; }
    if (app_.finished() && !options_.until_controller_ends) { why = "application finished"; break; }
    if (app_.finished() && server_->state() == host::ServerState::silent) { why = "application finished"; break; }
    if (app_.has_error()) {
      why = "application error";
      if (app_.drive_off_on_error()) server_->safety().trip(host::FaultReason::user_request);
      break;
    }
    if (app_.controller_exited()) { why = "controller ended the exchange (504)"; break; }
    if (const auto fault = server_->safety().reason(); fault != host::FaultReason::none && fault != host::FaultReason::user_request) {
      why = fmt::format("safety stop: {}", host::to_string(fault));  // the server asks for drive off meanwhile
      break;
    }
    if (options_.status_interval_s > 0 && now >= next_status) {
      if (hooks.on_status) hooks.on_status(status_line());
      next_status = now + seconds(options_.status_interval_s);
    }
  }
  spdlog::info("c4g serve: stopping ({})", why);
  graceful_stop(hooks);
  server_->stop();
  stopped_ = true;
  pump(hooks);
  if (recorder_->csv) recorder_->csv->flush();
  return report(why);
}

// Leave cleanly: the app ends its open modes (replies stay safe meanwhile); if the controller does
// not come back to mode 0 in time, ask for drive off and give it a moment to obey.
void ServeSession::graceful_stop(const Hooks& hooks) {
  auto interruptions = [&] { return hooks.interruptions ? hooks.interruptions() : 0; };
  app_.request_stop();
  if (hooks.on_stopping) hooks.on_stopping();
  auto wait_until = [&](double s) {
    const auto until = Clock::now() + seconds(s);
    while (!settled() && Clock::now() < until && interruptions() < 2) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      pump(hooks);
    }
    return settled();
  };
  if (wait_until(options_.stop_timeout_s)) return;
  if (interruptions() >= 2) spdlog::warn("c4g serve: a second signal: asking for drive off now");
  else spdlog::warn("c4g serve: the controller is still in an open mode after {} s: asking for drive off", options_.stop_timeout_s);
  server_->safety().trip(host::FaultReason::user_request);
  if (interruptions() < 2) wait_until(1.0);
  // The drive off must go out before the socket closes: wait for one more answer (at most 0.1 s).
  const auto before = server_->counters().packets.load();
  const auto until = Clock::now() + seconds(0.1);
  while (server_->counters().packets.load() == before && Clock::now() < until && server_->state() == host::ServerState::running)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

ServeReport ServeSession::report(std::string reason) const {
  const host::Server& s = *server_;
  ServeReport r;
  r.app = std::string(app_.name());
  r.reason = std::move(reason);
  r.app_cycles = app_.cycles();
  r.finished = app_.finished();
  r.error = app_.error();
  r.safety_fault = s.safety().faulted() && s.safety().reason() != host::FaultReason::user_request;
  r.app_summary = app_.summary();
  r.server_summary = s.summary();
  r.csv_path = options_.csv;
  r.moni = options_.moni;
  r.stats = serve_stats(s);
  if (const auto* csv = recorder_->csv.get()) {
    r.stats.csv = true;
    r.stats.csv_rows = csv->rows();
    r.stats.csv_rotations = csv->rotations();
    r.stats.csv_write_errors = csv->write_errors();
  }
  return r;
}

ServeStats serve_stats(const host::Server& s) {
  ServeStats st;
  const auto& c = s.counters();
  if (const auto peer = s.peer()) st.controller = peer->to_string();
  st.sessions = c.sessions.load();
  st.foreign = c.foreign.load();
  if (const auto last = host::SessionPeer::unpack(c.last_foreign.load())) st.last_foreign_source = last->to_string();
  st.packets = c.packets.load();
  st.init_packets = c.init_packets.load();
  st.cyclic_packets = c.cyclic_packets.load();
  st.protocol_errors = c.protocol_errors.load();
  st.safe_replies = c.safe_replies.load();
  st.refused_mode_changes = c.refused_mode_changes.load();
  st.controller_late = c.controller_late.load();
  st.freezes = c.freezes.load();
  st.frozen_cycles = c.frozen_cycles.load();
  st.safety_fault = std::string(host::to_string(s.safety().reason()));
  st.currents_clamped = s.safety().counters().currents_clamped.load();
  st.controller_errors = s.controller_errors().names();
  st.timing = timing_of(s);
  if (const auto* pcap = s.recorder()) {
    st.pcap = true;
    st.pcap_written = pcap->written();
    st.pcap_rotations = pcap->rotations();
    st.pcap_write_failures = pcap->write_failures();
  }
  return st;
}

}  // namespace axon::c4g::apps
