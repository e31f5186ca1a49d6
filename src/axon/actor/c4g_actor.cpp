#include "axon/actor/c4g_actor.hpp"
#include "axon/actor/schemas.hpp"

#include "axon/c4g/apps/app_factory.hpp"
#include "axon/c4g/apps/app_switch.hpp"
#include "axon/c4g/apps/serve.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/core/error.hpp"
#include "axon/core/latency_histogram.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <charconv>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

// Helpers in a namespace of their own: the library is a unity build with the other actors, whose
// anonymous namespaces have their own `number`, `Clock`, `json`...
namespace axon::actor::c4g_keywords {

namespace apps = c4g::apps;
namespace host = c4g::host;
namespace protocol = c4g::protocol;
using SteadyClock = std::chrono::steady_clock;

Exception c4g_bad(std::string text) { return Exception(Error(CoreErrc::invalid_argument, std::move(text))); }

std::optional<double> c4g_number(std::string_view s) {
  double v = 0;
  const auto* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, v);
  if (r.ec != std::errc() || r.ptr != end) return std::nullopt;
  return v;
}

double c4g_number_of(const std::string& option, std::string_view text) {
  const auto v = c4g_number(text);
  if (!v) throw c4g_bad(fmt::format("start: {} takes a number, not {:?}", option, text));
  return *v;
}

std::size_t c4g_count_of(const std::string& option, std::string_view text) {
  const double v = c4g_number_of(option, text);
  if (v < 0 || v > 1e6 || v != static_cast<double>(static_cast<std::size_t>(v)))
    throw c4g_bad(fmt::format("start: {} takes a whole number, not {:?}", option, text));
  return static_cast<std::size_t>(v);
}

// "1,2.5,3": one value per axis.
std::vector<double> c4g_list_of(const std::string& option, const std::string& text) {
  std::vector<double> out;
  std::size_t from = 0;
  while (from <= text.size()) {
    const auto comma = text.find(',', from);
    const auto part = std::string_view(text).substr(from, comma == std::string::npos ? std::string::npos : comma - from);
    out.push_back(c4g_number_of(option, part));
    if (comma == std::string::npos) break;
    from = comma + 1;
  }
  return out;
}

using ValueSetter = std::function<void(apps::AppConfig&, const std::string& option, const std::string& value)>;
using FlagSetter = std::function<void(apps::AppConfig&)>;

const std::map<std::string, ValueSetter>& value_options() {
  using C = apps::AppConfig;
  static const std::map<std::string, ValueSetter> table{
      {"--file", [](C& c, const std::string&, const std::string& v) { c.file = v; }},
      {"--segment", [](C& c, const std::string&, const std::string& v) { c.segments.push_back(v); }},
      {"--correct-file", [](C& c, const std::string&, const std::string& v) { c.correct_file = v; }},
      {"--mode", [](C& c, const std::string& o, const std::string& v) { c.mode = static_cast<int>(c4g_count_of(o, v)); }},
      {"--units", [](C& c, const std::string&, const std::string& v) { c.units = v; }},
      {"--start-tolerance", [](C& c, const std::string& o, const std::string& v) { c.start_tolerance_deg = c4g_number_of(o, v); }},
      {"--max-motor-speed", [](C& c, const std::string& o, const std::string& v) { c.max_motor_speed = c4g_number_of(o, v); }},
      {"--arm", [](C& c, const std::string& o, const std::string& v) { c.arm = c4g_count_of(o, v); }},
      {"--amplitude", [](C& c, const std::string& o, const std::string& v) { c.amplitude = c4g_list_of(o, v); }},
      {"--frequency", [](C& c, const std::string& o, const std::string& v) { c.frequency_hz = c4g_list_of(o, v); }},
      {"--open-time", [](C& c, const std::string& o, const std::string& v) { c.open_time_s = c4g_number_of(o, v); }},
      {"--ramp", [](C& c, const std::string& o, const std::string& v) { c.ramp_s = c4g_number_of(o, v); }},
      {"--feed", [](C& c, const std::string&, const std::string& v) { c.feed = v; }},
      {"--feed-from", [](C& c, const std::string&, const std::string& v) { c.feed_from = v; }},
      {"--feed-axes", [](C& c, const std::string& o, const std::string& v) { c.feed_axes = c4g_count_of(o, v); }},
      {"--feed-timeout-ms", [](C& c, const std::string& o, const std::string& v) { c.feed_timeout_ms = c4g_number_of(o, v); }},
      {"--max-correction", [](C& c, const std::string& o, const std::string& v) { c.max_correction_deg = c4g_list_of(o, v); }},
      {"--max-correction-step",
       [](C& c, const std::string& o, const std::string& v) { c.max_correction_step_deg = c4g_list_of(o, v); }},
      {"--kp", [](C& c, const std::string& o, const std::string& v) { c.kp = c4g_list_of(o, v); }},
      {"--kv", [](C& c, const std::string& o, const std::string& v) { c.kv = c4g_list_of(o, v); }},
      {"--ki", [](C& c, const std::string& o, const std::string& v) { c.ki = c4g_list_of(o, v); }},
  };
  return table;
}

const std::map<std::string, FlagSetter>& flag_options() {
  using C = apps::AppConfig;
  static const std::map<std::string, FlagSetter> table{
      {"--rearm", [](C& c) { c.rearm = true; }},
      {"--relative", [](C& c) { c.relative = true; }},
      {"--no-dynamic-model", [](C& c) { c.no_dynamic_model = true; }},
      {"--reduce-in-pc", [](C& c) { c.reduce_in_pc = true; }},
  };
  return table;
}

// `start APP [--option VALUE | --option=VALUE | --flag ...]`, as `axon c4g serve --app APP ...`.
apps::AppConfig app_config(const std::vector<std::string>& args) {
  if (args.empty() || args[0].starts_with("-"))
    throw c4g_bad("start takes APP [OPTION ...] (monitor, echo, stream, correct, pid, handover, contribute)");
  apps::AppConfig c;
  c.app = args[0];
  for (std::size_t i = 1; i < args.size(); ++i) {
    std::string option = args[i], value;
    const auto eq = option.find('=');
    const bool inline_value = eq != std::string::npos;
    if (inline_value) {
      value = option.substr(eq + 1);
      option.resize(eq);
    }
    if (const auto f = flag_options().find(option); f != flag_options().end() && !inline_value) {
      f->second(c);
      continue;
    }
    const auto v = value_options().find(option);
    if (v == value_options().end()) throw c4g_bad(fmt::format("start: unknown option {:?}", option));
    if (!inline_value) {
      if (i + 1 >= args.size()) throw c4g_bad(fmt::format("start: {} takes a value", option));
      value = args[++i];
    }
    v->second(c, option, value);
  }
  return c;
}

std::string mode_label(std::int32_t code) {
  const auto* m = protocol::find_mode(code);
  return m != nullptr ? std::string(m->label) : std::to_string(code);
}

// Each open axis: its place (arm, logical axis) from the last initialization packet, its mode.
Keywords axes_json(const apps::AppSwitch& sw) {
  const auto init = sw.init_packet();
  Keywords axes = Keywords::array();
  const auto modes = sw.modes();
  for (std::size_t i = 0; i < modes.size(); ++i) {
    Keywords a{{"axis", i + 1}, {"mode", modes[i]}, {"label", mode_label(modes[i])},
               {"name", std::string(protocol::mode_name(modes[i]))}};
    const auto ref = init ? init->second.logical(i) : protocol::AxisRef{};
    a["arm"] = ref.arm != 0 ? Keywords(ref.arm) : Keywords(nullptr);
    a["arm_axis"] = ref.axis != 0 ? Keywords(ref.axis) : Keywords(nullptr);
    axes.push_back(std::move(a));
  }
  return axes;
}

// The arms with open axes (every arm until the initialization packet tells).
Keywords drives_json(const apps::AppSwitch& sw) {
  const auto init = sw.init_packet();
  Keywords drives = Keywords::array();
  for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm)
    if (!init || init->second.arm_count(arm) > 0) drives.push_back({{"arm", arm}, {"on", sw.drives_on(arm)}});
  return drives;
}

Keywords app_json(const apps::AppInForce& a) {
  return Keywords{{"name", a.app},     {"installed", a.installed}, {"phase", a.phase},
                  {"status", a.status}, {"stopping", a.stopping},   {"error", a.error},
                  {"cycles", a.cycles}, {"in_force_s", a.in_force_s}};
}

Keywords ended_json(const apps::AppEnded& e) {
  return Keywords{{"name", e.app},           {"reason", e.reason},       {"finished", e.finished},
                  {"error", e.error},         {"left_cleanly", e.left_cleanly}, {"drive_off", e.drive_off},
                  {"summary", e.summary},     {"in_force_s", e.in_force_s}};
}

// Identifiers for the server's state and the safety's fault (the library's words go beside them).
std::string_view state_id(host::ServerState s) {
  switch (s) {
    case host::ServerState::waiting: return "waiting";
    case host::ServerState::syncing: return "syncing";
    case host::ServerState::running: return "running";
    case host::ServerState::silent: return "silent";
    case host::ServerState::stopped: return "stopped";
  }
  return "stopped";
}

std::string_view fault_id(host::FaultReason r) {
  switch (r) {
    case host::FaultReason::none: return "none";
    case host::FaultReason::following_error: return "following_error";
    case host::FaultReason::stroke_end: return "stroke_end";
    case host::FaultReason::discontinuity: return "discontinuity";
    case host::FaultReason::not_finite: return "not_finite";
    case host::FaultReason::unused_field: return "unused_field";
    case host::FaultReason::controller_exception: return "controller_exception";
    case host::FaultReason::controller_late: return "controller_late";
    case host::FaultReason::bad_packet: return "bad_packet";
    case host::FaultReason::user_request: return "user_request";
  }
  return "none";
}

std::string_view freeze_id(host::FreezeState f) {
  switch (f) {
    case host::FreezeState::off: return "off";
    case host::FreezeState::pending: return "pending";
    case host::FreezeState::entering: return "entering";
    case host::FreezeState::frozen: return "frozen";
    case host::FreezeState::leaving: return "leaving";
  }
  return "off";
}

Keywords server_json(const host::Server& s) {
  const auto period = s.period_ns();
  const auto peer = s.peer();
  return Keywords{{"address", s.local_address().to_string()},
                  {"state", std::string(state_id(s.state()))},
                  {"state_text", std::string(host::to_string(s.state()))},
                  {"controller", peer ? Keywords(peer->to_string()) : Keywords(nullptr)},
                  {"sessions", s.counters().sessions.load(std::memory_order_relaxed)},
                  {"cycles", s.counters().cyclic_packets.load(std::memory_order_relaxed)},
                  {"period_ms", period > 0 ? Keywords(static_cast<double>(period) * 1e-6) : Keywords(nullptr)},
                  {"freeze", std::string(freeze_id(s.freeze_state()))}};
}

Keywords safety_json(const host::Server& s) {
  const auto reason = s.safety().reason();
  return Keywords{{"fault", std::string(fault_id(reason))},
                  {"fault_text", std::string(host::to_string(reason))},
                  {"latched", reason != host::FaultReason::none},
                  {"obeyed", s.safety().obeyed()}};
}

Keywords latency_json(const core::LatencyHistogram& h) {
  return Keywords{{"count", h.count()},
                  {"p50_s", static_cast<double>(h.percentile(50)) * 1e-9},
                  {"p99_s", static_cast<double>(h.percentile(99)) * 1e-9},
                  {"max_s", static_cast<double>(h.max()) * 1e-9}};
}

Keywords timing_json(const apps::ServeTiming& t) {
  auto relative = [&t](const Keywords& v) { return t.nominal_known ? v : Keywords(nullptr); };
  return Keywords{{"cycles", t.cycles},
                  {"nominal_period_s", relative(t.nominal_period_s)},
                  {"cycle_time_p50_s", t.cycle_time_p50_s},
                  {"cycle_time_p99_s", t.cycle_time_p99_s},
                  {"cycle_time_p999_s", t.cycle_time_p999_s},
                  {"cycle_time_max_s", t.cycle_time_max_s},
                  {"inter_packet_period_s", Keywords::array({t.inter_packet_min_s, t.inter_packet_max_s})},
                  {"inter_step_p50_s", t.inter_step_p50_s},
                  {"jitter_s", relative(Keywords::array({t.jitter_min_s, t.jitter_max_s}))},
                  {"jitter_percent", relative(Keywords::array({t.jitter_min_percent, t.jitter_max_percent}))},
                  {"missed_deadlines", t.missed_deadlines},
                  {"deadline_s", t.deadline_s}};
}

Keywords stats_json(const host::Server& s) {
  const auto st = apps::serve_stats(s);
  return Keywords{{"packets", st.packets},
                  {"init_packets", st.init_packets},
                  {"cyclic_packets", st.cyclic_packets},
                  {"protocol_errors", st.protocol_errors},
                  {"safe_replies", st.safe_replies},
                  {"refused_mode_changes", st.refused_mode_changes},
                  {"controller_late", st.controller_late},
                  {"foreign", st.foreign},
                  {"sessions", st.sessions},
                  {"freezes", st.freezes},
                  {"currents_clamped", st.currents_clamped},
                  {"controller_errors", st.controller_errors},
                  {"safety_fault", st.safety_fault},
                  {"timing", timing_json(st.timing)},
                  {"wakeup_latency", latency_json(s.cycle().wakeup_latency())},
                  {"reply_latency", latency_json(s.cycle().reply_latency())}};
}

// One mode change as the watcher broadcasts it.
Keywords mode_change_json(const apps::Event& e, const std::optional<std::pair<protocol::InitPacket, protocol::AxisMap>>& init) {
  const auto i = static_cast<std::size_t>(e.axis);
  const auto ref = init ? init->second.logical(i) : protocol::AxisRef{};
  return Keywords{{"axis", i + 1},
                  {"arm", ref.arm != 0 ? Keywords(ref.arm) : Keywords(nullptr)},
                  {"arm_axis", ref.axis != 0 ? Keywords(ref.axis) : Keywords(nullptr)},
                  {"from", e.value},
                  {"to", e.aux},
                  {"from_label", mode_label(e.value)},
                  {"to_label", mode_label(e.aux)},
                  {"cycle", e.cycle}};
}

std::string_view kind_name(apps::EventKind k) {
  switch (k) {
    case apps::EventKind::init: return "init";
    case apps::EventKind::mode_change: return "mode_change";
    case apps::EventKind::drives: return "drives";
    case apps::EventKind::exit_sent: return "exit_sent";
    case apps::EventKind::note: return "note";
    case apps::EventKind::silence: return "silence";
  }
  return "note";
}

SteadyClock::duration c4g_after(double s) {
  return std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(s));
}

}  // namespace axon::actor::c4g_keywords

namespace axon::actor {

namespace c4g_kw = c4g_keywords;

struct C4gActor::Impl {
  ActorCore& core;
  c4g::apps::AppSwitch& sw;
  c4g::host::Server& server;
  C4gActorOptions options;

  std::mutex state;  // what follows (the watcher's memory of what it already broadcast)
  std::optional<c4g::apps::AppEnded> last_ended;  // the last one broadcast
  c4g::host::FaultReason shown_fault = c4g::host::FaultReason::none;
  bool shown_obeyed = false;
  c4g::host::ServerState shown_state = c4g::host::ServerState::waiting;
  std::uint64_t shown_missed = 0, shown_late = 0;
  c4g_kw::SteadyClock::time_point next_late{};

  std::mutex wake_mutex;
  std::condition_variable wake;
  bool stopping = false;
  std::thread watcher;
  std::once_flag shut;

  Impl(ActorCore& c, c4g::apps::AppSwitch& s, c4g::host::Server& sv, C4gActorOptions o)
      : core(c), sw(s), server(sv), options(o) {}

  Keywords counters_json() const {
    const auto c = core.counters();
    return Keywords{{"received", c.received}, {"accepted", c.accepted}, {"not_json", c.not_json},
                    {"malformed", c.malformed}, {"unknown", c.unknown},   {"refused", c.refused},
                    {"failed", c.failed},       {"oversized", c.oversized}, {"busy", c.busy}};
  }

  Keywords status_keywords() {
    Keywords kw{{"server", c4g_kw::server_json(server)}, {"axes", c4g_kw::axes_json(sw)},
                {"drives", c4g_kw::drives_json(sw)},    {"app", c4g_kw::app_json(sw.in_force())},
                {"safety", c4g_kw::safety_json(server)}, {"commands", counters_json()}};
    std::lock_guard s(state);
    kw["last_app"] = last_ended ? c4g_kw::ended_json(*last_ended) : Keywords(nullptr);
    return kw;
  }

  // An app's end, to every listener, once (the watcher and a stop may both see it): info when it
  // finished or stopped cleanly, a warning when it took a drive off, an error when it refused.
  void broadcast_end(const c4g::apps::AppEnded& e) {
    {
      std::lock_guard s(state);
      if (last_ended && last_ended->serial == e.serial) return;
      last_ended = e;
    }
    const auto code = !e.error.empty() ? MessageCode::error : e.drive_off ? MessageCode::warning : MessageCode::info;
    core.broadcast(code, {{"app_ended", c4g_kw::ended_json(e)}});
  }

  void no_arguments(const Command& c) const {
    if (!c.args().empty()) throw c4g_kw::c4g_bad(fmt::format("{} takes no argument", c.verb()));
  }

  void status(Command& c) {
    no_arguments(c);
    c.finish(status_keywords());
  }

  void stats(Command& c) {
    no_arguments(c);
    c.finish({{"stats", c4g_kw::stats_json(server)}});
  }

  void start(Command& c) {
    auto config = c4g_kw::app_config(c.args());
    if (server.safety().faulted())
      throw c4g_kw::c4g_bad(fmt::format("a safety fault is latched ({}): reset it first",
                                        c4g::host::to_string(server.safety().reason())));
    std::vector<std::string> notices;
    auto app = c4g::apps::make_app(config, [&notices](const std::string& line) { notices.push_back(line); });
    value_or_throw(sw.install(std::move(app)));
    Keywords kw{{"app", c4g_kw::app_json(sw.in_force())}};
    std::string text;
    for (const auto& n : notices) text += (text.empty() ? "" : "; ") + n;
    if (!text.empty()) kw["text"] = text;
    c.finish(std::move(kw));
  }

  void stop(Command& c) {
    no_arguments(c);
    const auto ended = sw.stop(server);
    if (!ended) return c.finish({{"text", "no application in force: the monitor answers"}});
    broadcast_end(*ended);
    if (ended->drive_off) c.write(MessageCode::warning, {{"text", "the controller did not leave the open mode: drive off"}});
    c.finish({{"app_ended", c4g_kw::ended_json(*ended)}, {"safety", c4g_kw::safety_json(server)}});
  }

  // Drive off now (505 on every axis until the controller shows it obeyed).
  void drive_off(Command& c) {
    no_arguments(c);
    server.safety().trip(c4g::host::FaultReason::user_request);
    const auto until = c4g_kw::SteadyClock::now() + c4g_kw::c4g_after(options.drive_off_wait_s);
    while (!server.safety().obeyed() && c4g_kw::SteadyClock::now() < until &&
           server.state() == c4g::host::ServerState::running)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    Keywords kw{{"safety", c4g_kw::safety_json(server)}};
    if (server.safety().obeyed() || server.state() != c4g::host::ServerState::running) return c.finish(std::move(kw));
    c.fail(fmt::format("the controller has not shown the drive off within {} s (505 goes on)", options.drive_off_wait_s),
           std::move(kw));
  }

  // Active freezing (500): from the next packet with every axis in mode 0 the controller stops
  // checking the replies, until release.
  void freeze(Command& c) {
    no_arguments(c);
    server.request_freeze();
    const bool frozen = server.wait_frozen(std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double>(options.drive_off_wait_s)));
    Keywords kw{{"server", c4g_kw::server_json(server)}};
    if (frozen) return c.finish(std::move(kw));
    c.fail(fmt::format("the controller has not shown 500 within {} s (it freezes once every axis is in mode 0); the "
                       "request stands until release",
                       options.drive_off_wait_s),
           std::move(kw));
  }

  void release(Command& c) {
    no_arguments(c);
    server.release_freeze();
    const auto until = c4g_kw::SteadyClock::now() + c4g_kw::c4g_after(options.drive_off_wait_s);
    while (server.freeze_state() != c4g::host::FreezeState::off && c4g_kw::SteadyClock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    Keywords kw{{"server", c4g_kw::server_json(server)}};
    if (server.freeze_state() == c4g::host::FreezeState::off) return c.finish(std::move(kw));
    c.fail(fmt::format("the controller has not left the freezing within {} s (exit from open goes on)", options.drive_off_wait_s),
           std::move(kw));
  }

  void reset(Command& c) {
    no_arguments(c);
    auto& safety = server.safety();
    if (!safety.faulted()) return c.finish({{"safety", c4g_kw::safety_json(server)}, {"text", "no fault latched"}});
    if (!safety.obeyed())
      throw c4g_kw::c4g_bad(fmt::format("the fault ({}) is not obeyed yet: the controller still shows an axis outside "
                                        "mode 0 or its drives on",
                                        c4g::host::to_string(safety.reason())));
    safety.reset();  // applied at the next cycle
    const auto until = c4g_kw::SteadyClock::now() + std::chrono::milliseconds(500);
    while (safety.faulted() && c4g_kw::SteadyClock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    Keywords kw{{"safety", c4g_kw::safety_json(server)}};
    if (safety.faulted()) kw["text"] = "reset asked: it takes effect at the controller's next packet";
    c.finish(std::move(kw));
  }

  // ---- the watcher's thread ----

  void report_events() {
    const auto events = sw.drain();
    if (events.empty()) return;
    const auto init = sw.init_packet();
    Keywords changes = Keywords::array(), drives = Keywords::array(), others = Keywords::array();
    bool drives_off = false;
    for (const auto& d : events) {
      const auto& e = d.event;
      if (options.on_event) options.on_event(e, d.text);
      if (e.kind == c4g::apps::EventKind::mode_change) {
        changes.push_back(c4g_kw::mode_change_json(e, init));
      } else if (e.kind == c4g::apps::EventKind::drives) {
        drives.push_back({{"arm", e.axis}, {"on", e.value != 0}});
        drives_off = drives_off || e.value == 0;
      } else {
        others.push_back({{"source", d.app}, {"kind", std::string(c4g_kw::kind_name(e.kind))}, {"text", d.text}, {"cycle", e.cycle}});
      }
    }
    if (!changes.empty()) core.broadcast(MessageCode::info, {{"mode_changes", changes}});
    if (!drives.empty()) core.broadcast(drives_off ? MessageCode::warning : MessageCode::info, {{"drives_changed", drives}});
    if (!others.empty()) core.broadcast(MessageCode::info, {{"app_events", others}});
  }

  void report_safety() {
    const auto reason = server.safety().reason();
    const bool obeyed = server.safety().obeyed();
    {
      std::lock_guard s(state);
      if (reason == shown_fault && obeyed == shown_obeyed) return;
      shown_fault = reason;
      shown_obeyed = obeyed;
    }
    Keywords kw{{"safety", c4g_kw::safety_json(server)}};
    if (reason == c4g::host::FaultReason::none) return core.broadcast(MessageCode::info, kw);
    kw["drive_off"] = {{"reason", std::string(c4g_kw::fault_id(reason))}, {"text", std::string(c4g::host::to_string(reason))},
                       {"obeyed", obeyed}};
    const bool ours = reason == c4g::host::FaultReason::user_request;
    core.broadcast(obeyed ? MessageCode::info : ours ? MessageCode::warning : MessageCode::error, kw);
  }

  void report_session() {
    const auto st = server.state();
    {
      std::lock_guard s(state);
      if (st == shown_state) return;
      shown_state = st;
    }
    core.broadcast(st == c4g::host::ServerState::silent ? MessageCode::warning : MessageCode::info,
                   {{"server", c4g_kw::server_json(server)}});
  }

  // Late cycles: the server's cycle time over its deadline, or the app over its budget; one
  // broadcast per late_period_s at most while either count rises.
  void report_late() {
    const auto missed = server.cycle().timing().missed_deadlines();
    const auto late = server.counters().controller_late.load(std::memory_order_relaxed);
    const auto now = c4g_kw::SteadyClock::now();
    std::uint64_t new_missed = 0, new_late = 0;
    {
      std::lock_guard s(state);
      if ((missed == shown_missed && late == shown_late) || now < next_late) return;
      new_missed = missed - shown_missed;
      new_late = late - shown_late;
      shown_missed = missed;
      shown_late = late;
      next_late = now + c4g_kw::c4g_after(options.late_period_s);
    }
    const auto& t = server.cycle().timing();
    core.broadcast(MessageCode::warning,
                   {{"late", {{"missed_deadlines", missed}, {"new_missed_deadlines", new_missed},
                              {"controller_late", late}, {"new_controller_late", new_late},
                              {"worst_cycle_time_s", static_cast<double>(t.worst_cycle_time_ns()) * 1e-9},
                              {"deadline_s", static_cast<double>(t.config().deadline_ns) * 1e-9}}}});
  }

  void watch_once(c4g_kw::SteadyClock::time_point& next_status) {
    if (const auto ended = sw.poll(server)) broadcast_end(*ended);
    report_events();
    report_safety();
    report_session();
    report_late();
    const auto now = c4g_kw::SteadyClock::now();
    if (options.status_period_s > 0 && now >= next_status) {
      core.broadcast(MessageCode::info, status_keywords());
      next_status = now + c4g_kw::c4g_after(options.status_period_s);
    }
  }

  void watch() noexcept {
    const auto period = std::chrono::duration<double>(options.watch_period_s);
    auto next_status = c4g_kw::SteadyClock::now() + c4g_kw::c4g_after(options.status_period_s);
    std::unique_lock lock(wake_mutex);
    while (!wake.wait_for(lock, period, [this] { return stopping; })) {
      lock.unlock();
      try {
        watch_once(next_status);
      } catch (const std::exception& e) {
        spdlog::warn("c4g actor: {}", e.what());
      }
      lock.lock();
    }
  }

  void shutdown() noexcept {
    std::call_once(shut, [this] {
      core.close();  // no command reaches the switch after this
      {
        std::lock_guard lock(wake_mutex);
        stopping = true;
      }
      wake.notify_all();
      if (watcher.joinable()) watcher.join();
      try {
        if (const auto ended = sw.stop(server)) {
          spdlog::info("c4g actor: {} {} at shutdown", ended->app, ended->reason);
          broadcast_end(*ended);
        }
        report_events();
      } catch (const std::exception& e) {
        spdlog::warn("c4g actor: stopping the app: {}", e.what());
      }
    });
  }
};

C4gActor::C4gActor(ActorCore& core, c4g::apps::AppSwitch& apps, c4g::host::Server& server, C4gActorOptions options)
    : impl_(std::make_unique<Impl>(core, apps, server, options)) {
  auto* i = impl_.get();
  core.set_schema(std::string(schemas::c4g));
  core.add({"status", "status", false, [i](Command& c) { i->status(c); }});
  core.add({"stats", "stats (counters and timing of the server)", false, [i](Command& c) { i->stats(c); }});
  core.add({"start", "start APP [OPTION ...] (monitor, echo, stream, correct, pid, handover, contribute; options as axon c4g serve)",
            true, [i](Command& c) { i->start(c); }});
  core.add({"stop", "stop (the app leaves its open modes; drive off if the controller does not)", true,
            [i](Command& c) { i->stop(c); }});
  core.add({"driveoff", "driveoff (505 now, until the controller shows it)", true, [i](Command& c) { i->drive_off(c); }});
  core.add({"reset", "reset (clears a latched safety fault once obeyed)", true, [i](Command& c) { i->reset(c); }});
  core.add({"freeze", "freeze (active freezing, 500, once every axis is in mode 0)", true, [i](Command& c) { i->freeze(c); }});
  core.add({"release", "release (ends the active freezing)", true, [i](Command& c) { i->release(c); }});
  impl_->watcher = std::thread([i] { i->watch(); });
}

C4gActor::~C4gActor() { impl_->shutdown(); }

void C4gActor::shutdown() noexcept { impl_->shutdown(); }

}  // namespace axon::actor
