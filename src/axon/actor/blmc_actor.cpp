#include "axon/actor/blmc_actor.hpp"
#include "axon/actor/schemas.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/core/error.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

// The keywords' JSON and the verbs' argument parsing, in a namespace of their own: the actor
// library is a unity build, and fps_actor.cpp's helpers live in an anonymous namespace beside these.
namespace axon::actor::blmc_keywords {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }
double micros(core::Duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

[[noreturn]] void bad_argument(const std::string& text) { throw Exception(Error(CoreErrc::invalid_argument, text)); }

// A finite number, the whole word.
std::optional<double> finite_value(const std::string& s) {
  double v = 0;
  const auto* end = s.data() + s.size();
  const auto [p, ec] = std::from_chars(s.data(), end, v);
  if (ec != std::errc() || p != end || !std::isfinite(v)) return std::nullopt;
  return v;
}

double argument(const std::string& s, std::string_view verb, std::string_view what) {
  const auto v = finite_value(s);
  if (!v) bad_argument(fmt::format("{}: {:?} is not a number ({})", verb, s, what));
  return *v;
}

// What each error code of the status byte means (the board's specification, bits 5..7).
const char* error_meaning(std::uint8_t raw) noexcept {
  switch (raw) {
    case 0: return "no error";
    case 1: return "encoder error";
    case 2: return "CAN receive timeout: no current reference within the board's receive timeout (the host stopped sending)";
    case 3: return "critical motor temperature (reserved: the boards have no temperature sensing)";
    case 4: return "position converter module failure";
    case 5: return "position rollover: a position counter passed +-100 rev (only with the rollover error on)";
    case 6: return "undocumented error code 6 (a newer firmware or a corrupted byte): treated as an error";
    case 7: return "other error (the firmware reports a transmit failure with it)";
    default: return "not an error code";
  }
}

json board_error_json(std::uint8_t raw) {
  std::string name = raw == blmc::protocol::kUndocumentedErrorCode ? "UNDOCUMENTED" : "";
  if (name.empty()) {
    const auto code = blmc::protocol::error_code_from_raw(raw);
    name = code ? std::string(blmc::protocol::name(code.value())) : "UNKNOWN";
  }
  return json{{"code", raw}, {"name", name}, {"meaning", error_meaning(raw)}};
}

// The error field as the board sent it (6 included), 0 when no status arrived.
std::uint8_t error_bits_of(const blmc::host::Measurements& m) noexcept {
  if (m.status_byte.received()) return blmc::protocol::error_bits(m.status_byte.value);
  if (m.status.received()) return static_cast<std::uint8_t>(m.status.value.error);
  return 0;
}

// The board's flags and each motor's measurements. Outside the loop the frames carry their arrival
// times (status_age_s); the loop's own record has none (null).
json board_json(const blmc::host::Measurements& m, bool enabled) {
  const auto& st = m.status.value;
  const bool stamped = m.status.received() && m.status.at != core::TimePoint{};
  json motors = json::array();
  const std::array<bool, 2> on{st.motor1_enabled, st.motor2_enabled}, ready{st.motor1_ready, st.motor2_ready};
  const std::array<double, 2> current{m.current.value.motor1, m.current.value.motor2},
      position{m.position.value.motor1, m.position.value.motor2},
      velocity{m.velocity.value.motor1, m.velocity.value.motor2}, adc{m.adc.value.motor1, m.adc.value.motor2};
  for (std::size_t k = 0; k < 2; ++k)
    motors.push_back({{"motor", k + 1}, {"enabled", on[k]}, {"ready", ready[k]}, {"current_a", current[k]},
                      {"position_rev", position[k]}, {"velocity_rev_s", blmc::host::krpm_to_rev_per_s(velocity[k])},
                      {"adc", adc[k]}});
  return json{{"enabled", enabled},
              {"system_enabled", st.system_enabled},
              {"status_received", m.status.received() || m.status_byte.received()},
              {"status_age_s", stamped ? json(seconds(core::steady_now() - m.status.at)) : json(nullptr)},
              {"motors", std::move(motors)}};
}

json action_stats_json(const blmc::ActionStats& a) {
  return json{{"cycles", a.cycles},
              {"actions", a.actions},
              {"idle_cycles", a.idle_cycles},
              {"stale_cycles", a.stale_cycles},
              {"stale_episodes", a.stale_episodes},
              {"first_action_s", a.first_action_s < 0 ? json(nullptr) : json(a.first_action_s)}};
}

// A finished run: how it ended and the loop's exact timing figures.
json run_report_json(const blmc::ControlReport& r, double duration_s) {
  const auto& s = r.stats;
  std::string text = r.fault_text;
  if (text.empty() && r.end == blmc::ControlEnd::no_first_action) text = "no first action in time: the motors were disabled";
  return json{{"end", blmc::to_string(r.end)},
              {"fault", r.fault ? blmc::host::to_string(r.fault->kind) : ""},
              {"text", text},
              {"duration_s", duration_s},
              {"cycles", s.cycles},
              {"overruns", s.overruns},
              {"missed", s.missed},
              {"period_mean_us", micros(s.period_mean)},
              {"jitter_p50_us", micros(s.jitter_p50)},
              {"jitter_p99_us", micros(s.jitter_p99)},
              {"jitter_max_us", micros(s.jitter_max)},
              {"late_max_us", micros(s.late_max)},
              {"compute_max_us", micros(s.compute_max)},
              {"back_end", action_stats_json(r.actions)}};
}

json limits_json(const blmc::ControlSettings& s, const blmc::FrontEndOptions& fe, std::uint32_t recv_timeout_ms) {
  const auto& l = s.limits;
  json position = json::array();
  for (const auto& p : l.position)
    position.push_back(p.enabled ? json{{"min_rev", p.min_rev}, {"max_rev", p.max_rev}} : json(nullptr));
  return json{{"max_current_a", l.max_current_a},
              {"max_velocity_krpm", l.max_velocity_krpm},
              {"stale_after_ms", std::chrono::duration<double, std::milli>(l.stale_after).count()},
              {"status_stale_after_ms", std::chrono::duration<double, std::milli>(l.status_stale_after).count()},
              {"position", std::move(position)},
              {"period_us", static_cast<double>(s.period.count())},
              {"action_stale_after_ms", static_cast<double>(fe.stale_after.count())},
              {"recv_timeout_ms", recv_timeout_ms}};
}

json homing_json(const blmc::HomingReport& r) {
  json motors = json::array();
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& m = r.motors[k];
    const bool found = m.state == blmc::host::MotorHoming::State::found;
    motors.push_back({{"motor", k + 1}, {"state", blmc::host::to_string(m.state)}, {"start_rev", m.start_rev},
                      {"index_rev", found ? json(m.index_rev) : json(nullptr)}});
  }
  return json{{"all_found", r.all_found}, {"motors", std::move(motors)}};
}

json counters_json(const CoreCounters& c) {
  return json{{"received", c.received}, {"accepted", c.accepted}, {"not_json", c.not_json}, {"malformed", c.malformed},
              {"unknown", c.unknown},   {"refused", c.refused},   {"failed", c.failed},
              {"oversized", c.oversized}, {"busy", c.busy}};
}

// start's options: each may only lower the actor's own limit.
blmc::ControlSettings start_settings(const std::vector<std::string>& args, blmc::ControlSettings s) {
  for (std::size_t i = 0; i < args.size(); i += 2) {
    const auto& name = args[i];
    if ((name != "--max-current" && name != "--max-velocity") || i + 1 >= args.size())
      bad_argument("start takes [--max-current A] [--max-velocity KRPM]");
    const double v = argument(args[i + 1], "start", name);
    double& limit = name == "--max-current" ? s.limits.max_current_a : s.limits.max_velocity_krpm;
    if (v <= 0 || v > limit)
      bad_argument(fmt::format("start: {} {:g} is not in (0, {:g}], the actor's limit", name, v, limit));
    limit = v;
  }
  return s;
}

}  // namespace axon::actor::blmc_keywords

namespace axon::actor {

namespace bk = blmc_keywords;
using bk::Clock;
using bk::json;

struct BlmcActor::Impl {
  // The action in force, per motor: what the actor hands the loop every watch period.
  struct Action {
    blmc::Command command{};                       // zeros: the idle action
    std::array<std::string, 2> mode{"idle", "idle"};  // idle, current, pd
    Clock::time_point set_at = Clock::now();
    std::string by = "start";  // the command id that set it, or what the actor did
  };
  struct FaultSeen {
    Clock::time_point at;
    std::string source;  // safety_stop, board, broker
    std::string text;
  };
  static constexpr std::size_t kFaultHistory = 32;

  ActorCore& core;
  blmc::MotorBoard& board;
  BlmcActorOptions options;
  std::uint32_t recv_timeout_ms = 0;
  std::mutex device;  // one MotorBoard call at a time (the library asks for one thread at a time)
  // A disable came while an enable was accepted: that enable must not turn the motors on after it,
  // even when it had not reached the board's wait yet (the interrupt would then be cleared unseen).
  std::atomic<bool> disable_over_enable{false};

  std::mutex state;  // what follows
  std::optional<blmc::FrontEnd> front_end;  // while a loop runs
  Clock::time_point started{};
  blmc::ControlSettings in_force;           // the running loop's settings (the defaults otherwise)
  Action action;
  std::optional<json> last_run;
  std::deque<FaultSeen> faults;
  json last_board = json(nullptr);          // the last read of the board (for answers while it is busy)
  std::uint8_t last_error = 0;
  bool status_stale = false;
  std::uint64_t stale_episodes_seen = 0;
  std::uint64_t last_cycle = 0;
  Clock::time_point last_cycle_change{};
  bool loop_stalled = false;
  bool broker_down = false, broker_announce = false;
  Clock::time_point broker_lost_at{}, broker_back_at{};
  json action_at_loss = json(nullptr);

  std::mutex wake_mutex;
  std::condition_variable wake;
  bool stopping = false;
  std::thread watcher;

  Impl(ActorCore& c, blmc::MotorBoard& b, BlmcActorOptions o)
      : core(c), board(b), options(std::move(o)), recv_timeout_ms(options.recv_timeout_ms), in_force(options.control) {}

  [[nodiscard]] bool running() const { return front_end.has_value(); }  // state held

  json action_json() const {  // state held
    json motors = json::array();
    for (std::size_t k = 0; k < 2; ++k) {
      const auto& m = action.command[k];
      motors.push_back({{"motor", k + 1}, {"mode", action.mode[k]}, {"current_a", m.current_a},
                        {"position_rev", m.position_rev}, {"velocity_rev_s", m.velocity_rev_s}, {"kp", m.kp}, {"kd", m.kd}});
    }
    json j{{"motors", std::move(motors)}, {"age_s", bk::seconds(Clock::now() - action.set_at)}, {"by", action.by}};
    j["applied"] = front_end ? blmc::to_string(front_end->applied().source) : "none";
    return j;
  }

  json loop_json() const {  // state held
    if (!front_end) return json{{"running", false}};
    return json{{"running", true},
                {"elapsed_s", bk::seconds(Clock::now() - started)},
                {"period_us", static_cast<double>(in_force.period.count())},
                {"back_end", bk::action_stats_json(front_end->stats())}};
  }

  void record_fault(std::string source, std::string text) {  // state held
    faults.push_back({Clock::now(), std::move(source), std::move(text)});
    if (faults.size() > kFaultHistory) faults.pop_front();
  }

  // ---- the board (device held) ----

  // Reads the board; remembers it; returns the broadcasts its changes call for.
  std::vector<std::pair<MessageCode, json>> read_board_locked() {
    const auto m = board.measurements();
    if (options.on_board_read) options.on_board_read(m);
    const bool enabled = board.enabled();
    const auto code = bk::error_bits_of(m);
    std::vector<std::pair<MessageCode, json>> out;
    std::lock_guard s(state);
    last_board = bk::board_json(m, enabled);
    if (code != last_error) {
      last_error = code;
      const auto e = bk::board_error_json(code);
      if (code != 0) record_fault("board", fmt::format("board error {} ({})", e["name"].get<std::string>(), e["meaning"].get<std::string>()));
      out.emplace_back(code != 0 ? MessageCode::error : MessageCode::info, json{{"board_error", e}, {"board", last_board}});
    }
    const auto& age = last_board["status_age_s"];
    const bool stale = !running() && age.is_number() && age.get<double>() > options.status_stale_s;
    if (stale != status_stale) {
      status_stale = stale;
      out.emplace_back(stale ? MessageCode::warning : MessageCode::info,
                       json{{"stale_data", {{"quantity", "status"}, {"stale", stale}, {"age_s", age}}}});
    }
    return out;
  }

  // The loop ended: its report kept; an end the actor did not ask for is a safety stop for every
  // listener. Returns the report's keywords.
  json finish_run_locked(const blmc::ControlReport& r, bool requested) {
    std::optional<json> alert;
    json report;
    {
      std::lock_guard s(state);
      report = bk::run_report_json(r, bk::seconds(Clock::now() - started));
      front_end.reset();
      action = Action{};
      action.by = requested ? "stop" : "safety stop";
      in_force = options.control;
      last_run = report;
      if (r.end != blmc::ControlEnd::requested || !requested) {
        record_fault("safety_stop", report["text"].get<std::string>());
        const auto why = report["text"].get<std::string>();
        alert = json{{"safety_stop", report},
                     {"text", fmt::format("the control loop stopped by itself: {}", why.empty() ? report["end"].get<std::string>() : why)}};
      }
    }
    if (alert) core.broadcast(MessageCode::error, *alert);
    return report;
  }

  // MotorBoard::stop_control, whose failure (the loop did not stop, its thread failed) also ends the
  // actor's run: the next start begins afresh, and every listener hears of it.
  json collect_run_locked(bool requested) {
    std::optional<blmc::ControlReport> report;
    std::string failure;
    try {
      report = board.stop_control();
    } catch (const std::exception& e) {
      failure = e.what();
    }
    if (report) return finish_run_locked(*report, requested);
    {
      std::lock_guard s(state);
      front_end.reset();
      action = Action{};
      action.by = "loop failure";
      in_force = options.control;
      record_fault("safety_stop", failure);
    }
    core.broadcast(MessageCode::error, {{"text", fmt::format("the control loop ended badly: {}", failure)}, {"loop", {{"running", false}}}});
    bk::bad_argument(fmt::format("the control loop ended badly: {}", failure));
  }

  // A loop that ended by itself (a safety stop) is collected here, by whoever looks first.
  void reap_locked() {
    {
      std::lock_guard s(state);
      if (!running()) return;
    }
    if (board.control_running()) return;
    collect_run_locked(false);
  }

  std::optional<json> stop_loop_locked() {
    {
      std::lock_guard s(state);
      if (!running()) return std::nullopt;
    }
    const bool by_itself = !board.control_running();
    return collect_run_locked(!by_itself);
  }

  void publish(const std::vector<std::pair<MessageCode, json>>& messages) {
    for (const auto& [code, kw] : messages) core.broadcast(code, kw);
  }

  // ---- status ----

  json status_keywords() {
    std::unique_lock lock(device, std::try_to_lock);
    const bool fresh = lock.owns_lock();
    if (fresh) {
      reap_locked();
      publish(read_board_locked());
      lock.unlock();
    }
    return assemble(fresh);
  }

  json assemble(bool fresh) {
    std::lock_guard s(state);
    json j{{"stale", !fresh}, {"board", last_board}, {"board_error", bk::board_error_json(last_error)},
           {"loop", loop_json()}, {"limits", bk::limits_json(in_force, options.front_end, recv_timeout_ms)},
           {"commands", bk::counters_json(core.counters())}};
    if (running()) j["action"] = action_json();
    j["last_run"] = last_run ? *last_run : json(nullptr);
    return j;
  }

  void status(Command& c) { c.finish(status_keywords()); }

  // ---- enable, disable, recover ----

  void enable(Command& c) {
    std::lock_guard lock(device);
    // Whatever way this enable ends, a disable it met is used up with it.
    const struct Spent {
      std::atomic<bool>& flag;
      ~Spent() { flag.store(false); }
    } spent{disable_over_enable};
    if (disable_over_enable.exchange(false)) bk::bad_argument("enable: stopped on request: a disable came after it, the motors stay off");
    reap_locked();
    {
      std::lock_guard s(state);
      if (running()) bk::bad_argument("enable: the control loop runs, the motors are enabled");
    }
    board.enable();
    publish(read_board_locked());
    c.finish(assemble(true));
  }

  // Never refused: an enable or recover waiting for the board ends now, then the motors go off.
  // Ends the wait of an enable, home or recover in progress (not a running loop's: that would read
  // as its safety stop).
  void interrupt_waits() {
    const auto busy = core.busy_with();
    if (busy == "enable") disable_over_enable.store(true);
    if (busy == "enable" || busy == "recover" || busy == "home") board.interrupt();
  }

  void disable(Command& c) {
    interrupt_waits();
    std::lock_guard lock(device);
    board.clear_interrupt();
    const auto report = stop_loop_locked();
    board.disable();
    publish(read_board_locked());
    json kw = assemble(true);
    if (report) kw["stopped"] = *report;
    c.finish(std::move(kw));
  }

  void recover(Command& c) {
    std::lock_guard lock(device);
    reap_locked();
    {
      std::lock_guard s(state);
      if (running()) bk::bad_argument("recover: the control loop runs (stop it first)");
    }
    board.recover();
    publish(read_board_locked());
    json kw = assemble(true);
    kw["text"] = "the board recovered: enabled and ready";
    c.finish(std::move(kw));
  }

  // home [SPEED_REV_S]: each motor turns slowly until its encoder index (MotorBoard::home, under
  // the same safety limits); refused while the loop runs.
  void home(Command& c) {
    const auto& args = c.args();
    if (args.size() > 1) bk::bad_argument("home takes [SPEED_REV_S] (the sign gives the direction; default 0.5)");
    blmc::host::HomingOptions h;
    if (args.size() == 1) h.speed_rev_s = bk::argument(args[0], "home", "motor rev/s");
    if (h.speed_rev_s == 0 || std::abs(h.speed_rev_s) > 5) bk::bad_argument("home: the speed must be in [-5, 5] rev/s and not 0");
    std::lock_guard lock(device);
    reap_locked();
    {
      std::lock_guard s(state);
      if (running()) bk::bad_argument("home: the control loop runs (stop it first)");
    }
    if (!board.enabled()) bk::bad_argument("home: the motors are not enabled (enable first)");
    const auto t0 = Clock::now();
    const auto r = board.home(h, options.control);
    json kw{{"homing", bk::homing_json(r)}, {"stopped", bk::run_report_json(r.control, bk::seconds(Clock::now() - t0))}};
    if (r.control.fault) {
      std::lock_guard s(state);
      record_fault("safety_stop", r.control.fault_text);
    }
    publish(read_board_locked());
    if (r.all_found && !r.control.fault) return c.finish(std::move(kw));
    c.fail(r.control.fault ? r.control.fault_text : "not every motor found its index", std::move(kw));
  }

  // ---- the loop ----

  void start(Command& c) {
    const auto settings = bk::start_settings(c.args(), options.control);
    std::lock_guard lock(device);
    reap_locked();
    {
      std::lock_guard s(state);
      if (running()) bk::bad_argument("start: the control loop already runs (stop it first)");
    }
    if (!board.enabled()) bk::bad_argument("start: the motors are not enabled (enable first)");
    blmc::FrontEnd fe(options.front_end);
    fe.set_currents({0.0, 0.0});  // idle until a commander sets an action
    board.start_control(fe, settings);
    json kw;
    {
      std::lock_guard s(state);
      front_end = fe;
      started = Clock::now();
      in_force = settings;
      action = Action{};
      action.by = c.id().command_id;
      stale_episodes_seen = 0;
      last_cycle = 0;
      last_cycle_change = started;
      loop_stalled = false;
      kw = json{{"loop", loop_json()}, {"action", action_json()},
                {"limits", bk::limits_json(in_force, options.front_end, recv_timeout_ms)}};
    }
    c.finish(std::move(kw));
  }

  void stop(Command& c) {
    std::lock_guard lock(device);
    const auto report = stop_loop_locked();
    publish(read_board_locked());
    if (!report) return c.finish({{"text", "no control loop was running"}, {"board", last_board_copy()}});
    c.finish({{"stopped", *report}, {"board", last_board_copy()}});
  }

  json last_board_copy() {
    std::lock_guard s(state);
    return last_board;
  }

  // Sets the action in force (currents, current, pd, idle): refused while no loop runs.
  template <class Change>
  void set_action(Command& c, Change change) {
    {
      std::unique_lock lock(device, std::try_to_lock);
      if (lock.owns_lock()) reap_locked();
    }
    std::lock_guard s(state);
    if (!running()) {
      const std::string last = last_run && last_run->value("end", "") != "requested"
                                   ? fmt::format(" (the last run ended: {})", last_run->value("text", ""))
                                   : "";
      bk::bad_argument(fmt::format("{}: no control loop runs (start it first){}", c.verb(), last));
    }
    Action a = action;
    change(a);
    a.set_at = Clock::now();
    a.by = c.id().command_id;
    front_end->set(a.command);
    action = a;
    c.finish({{"action", action_json()}});
  }

  double checked_current(const std::string& arg, std::string_view verb) {
    const double a = bk::argument(arg, verb, "amperes");
    const double limit = [this] {
      std::lock_guard s(state);
      return in_force.limits.max_current_a;
    }();
    if (std::abs(a) > limit) bk::bad_argument(fmt::format("{}: {:g} A is beyond the current limit in force ({:g} A)", verb, a, limit));
    return a;
  }

  void currents(Command& c) {
    if (c.args().size() != 2) bk::bad_argument("currents takes A1 A2 (amperes, motor 1 and motor 2)");
    const std::array<double, 2> a{checked_current(c.args()[0], "currents"), checked_current(c.args()[1], "currents")};
    set_action(c, [&a](Action& x) {
      for (std::size_t k = 0; k < 2; ++k) {
        x.command[k] = blmc::MotorCommand::current(a[k]);
        x.mode[k] = "current";
      }
    });
  }

  void current(Command& c) {
    const auto& args = c.args();
    if (args.size() != 2 || (args[0] != "1" && args[0] != "2")) bk::bad_argument("current takes MOTOR (1 or 2) and A (amperes)");
    const std::size_t k = args[0] == "1" ? 0 : 1;
    const double a = checked_current(args[1], "current");
    set_action(c, [k, a](Action& x) {
      x.command[k] = blmc::MotorCommand::current(a);
      x.mode[k] = "current";
    });
  }

  void pd(Command& c) {
    const auto& args = c.args();
    if (args.size() != 2 && args.size() != 4)
      bk::bad_argument("pd takes P1 P2 [KP KD] (positions in motor rev; gains A/rev and A/(rev/s))");
    const std::array<double, 2> p{bk::argument(args[0], "pd", "position, rev"), bk::argument(args[1], "pd", "position, rev")};
    const double kp = args.size() == 4 ? bk::argument(args[2], "pd", "KP, A/rev") : options.pd_kp;
    const double kd = args.size() == 4 ? bk::argument(args[3], "pd", "KD, A/(rev/s)") : options.pd_kd;
    if (kp < 0 || kd < 0) bk::bad_argument("pd: the gains must not be negative");
    set_action(c, [&p, kp, kd](Action& x) {
      for (std::size_t k = 0; k < 2; ++k) {
        x.command[k] = blmc::MotorCommand::pd(p[k], 0.0, kp, kd);
        x.mode[k] = "pd";
      }
    });
  }

  void idle(Command& c) {
    if (!c.args().empty()) bk::bad_argument("idle takes no argument");
    set_action(c, [](Action& x) {
      x.command = {};
      x.mode = {"idle", "idle"};
    });
  }

  void errors(Command& c) {
    const auto kw = status_keywords();
    json seen = json::array();
    {
      std::lock_guard s(state);
      for (const auto& f : faults)
        seen.push_back({{"age_s", bk::seconds(Clock::now() - f.at)}, {"source", f.source}, {"text", f.text}});
    }
    c.finish({{"board_error", kw.at("board_error")}, {"faults", std::move(seen)}, {"last_run", kw.at("last_run")},
              {"stale", kw.at("stale")}});
  }

  // ---- the watcher's thread ----

  // Hands the action in force to the loop again (it never goes stale while the actor lives), and
  // notes the back end's stale episodes and a loop that stopped cycling.
  std::vector<std::pair<MessageCode, json>> refresh() {
    std::vector<std::pair<MessageCode, json>> out;
    std::lock_guard s(state);
    if (!front_end) return out;
    front_end->set(action.command);
    const auto st = front_end->stats();
    if (st.stale_episodes > stale_episodes_seen) {
      stale_episodes_seen = st.stale_episodes;
      out.emplace_back(MessageCode::warning,
                       json{{"stale_action", {{"episodes", st.stale_episodes}, {"stale_cycles", st.stale_cycles},
                                              {"stale_after_ms", static_cast<double>(options.front_end.stale_after.count())}}}});
    }
    const auto now = Clock::now();
    if (st.cycles != last_cycle) {
      last_cycle = st.cycles;
      last_cycle_change = now;
      if (loop_stalled) out.emplace_back(MessageCode::info, json{{"stale_data", {{"quantity", "loop"}, {"stale", false}, {"age_s", 0.0}}}});
      loop_stalled = false;
    } else if (!loop_stalled && bk::seconds(now - last_cycle_change) > options.status_stale_s) {
      loop_stalled = true;
      out.emplace_back(MessageCode::warning, json{{"stale_data", {{"quantity", "loop"}, {"stale", true},
                                                                 {"age_s", bk::seconds(now - last_cycle_change)}}}});
    }
    return out;
  }

  void announce_broker() {
    json kw;
    {
      std::lock_guard s(state);
      if (!broker_announce) return;
      broker_announce = false;
      kw = json{{"broker_lost", {{"lost_s", bk::seconds(broker_back_at - broker_lost_at)}, {"action_before", action_at_loss},
                                 {"idle_set", !action_at_loss.is_null()}}},
                {"text", action_at_loss.is_null() ? "the broker connection was lost; no control loop was running"
                                                  : "the broker connection was lost: the motors were set to the idle action (zero current)"}};
    }
    core.broadcast(MessageCode::warning, kw);
  }

  void tick(Clock::time_point& next_status) {
    publish(refresh());
    {
      std::unique_lock lock(device, std::try_to_lock);
      if (lock.owns_lock()) {
        reap_locked();
        publish(read_board_locked());
      }
    }
    announce_broker();
    const auto now = Clock::now();
    if (options.status_period_s > 0 && now >= next_status) {
      core.broadcast(MessageCode::info, status_keywords());
      next_status = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.status_period_s));
    }
  }

  void watch() noexcept {
    const auto period = std::chrono::duration<double>(options.watch_period_s);
    auto next_status = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.status_period_s));
    std::unique_lock lock(wake_mutex);
    while (!wake.wait_for(lock, period, [this] { return stopping; })) {
      lock.unlock();
      try {
        tick(next_status);
      } catch (const std::exception& e) {
        spdlog::warn("blmc actor: {}", e.what());
      }
      lock.lock();
    }
  }

  void broker_state(bool connected) noexcept {
    try {
      std::lock_guard s(state);
      if (!connected) {
        if (broker_down) return;
        broker_down = true;
        broker_lost_at = Clock::now();
        action_at_loss = front_end ? action_json() : json(nullptr);
        if (!front_end) return;
        action = Action{};
        action.by = "broker lost";
        front_end->set(action.command);
        spdlog::warn("blmc actor: the broker connection was lost: idle action (zero current)");
      } else if (broker_down) {
        broker_down = false;
        broker_back_at = Clock::now();
        broker_announce = true;
        record_fault("broker", fmt::format("the broker connection was lost for {:.1f} s{}", bk::seconds(broker_back_at - broker_lost_at),
                                           action_at_loss.is_null() ? "" : ": the idle action was set (zero current)"));
      }
    } catch (const std::exception& e) {
      spdlog::error("blmc actor: broker state: {}", e.what());
    }
  }

  void shut_down() noexcept {
    try {
      std::lock_guard lock(device);
      board.clear_interrupt();
      if (auto r = stop_loop_locked()) spdlog::info("blmc actor: control loop stopped ({} cycles)", (*r)["cycles"].get<std::uint64_t>());
      board.disable();
    } catch (const std::exception& e) {
      spdlog::error("blmc actor: stopping the board: {}", e.what());
    }
  }
};

BlmcActor::BlmcActor(ActorCore& core, blmc::MotorBoard& board, BlmcActorOptions options)
    : impl_(std::make_unique<Impl>(core, board, std::move(options))) {
  auto* i = impl_.get();
  core.set_schema(std::string(schemas::blmc));
  core.add({"status", "status", false, [i](Command& c) { i->status(c); }});
  core.add({"enable", "enable (the motors on, aligned and ready)", true, [i](Command& c) { i->enable(c); }});
  core.add({"disable", "disable (stops the loop, zero current, motors off; never refused)", false,
            [i](Command& c) { i->disable(c); }});
  core.add({"start", "start [--max-current A] [--max-velocity KRPM] (the 1 kHz loop, idle until told)", true,
            [i](Command& c) { i->start(c); }});
  core.add({"stop", "stop (ends the loop; the motors stay enabled at zero current)", true, [i](Command& c) { i->stop(c); }});
  core.add({"currents", "currents A1 A2 (amperes, both motors)", false, [i](Command& c) { i->currents(c); }});
  core.add({"current", "current MOTOR A (1 or 2; the other motor keeps its action)", false, [i](Command& c) { i->current(c); }});
  core.add({"pd", "pd P1 P2 [KP KD] (positions in motor rev; gains A/rev, A/(rev/s))", false, [i](Command& c) { i->pd(c); }});
  core.add({"idle", "idle (zero current on both motors; the loop runs on)", false, [i](Command& c) { i->idle(c); }});
  core.add({"errors", "errors (the board's error code, the faults seen)", false, [i](Command& c) { i->errors(c); }});
  core.add({"home", "home [SPEED_REV_S] (finds each motor's encoder index; no loop may run)", true,
            [i](Command& c) { i->home(c); }});
  core.add({"recover", "recover (after a board error: the board's recovery, enabled and ready)", true,
            [i](Command& c) { i->recover(c); }});
  {
    std::lock_guard lock(i->device);
    i->publish(i->read_board_locked());
  }
  impl_->watcher = std::thread([i] { i->watch(); });
}

BlmcActor::~BlmcActor() {
  try {
    impl_->interrupt_waits();  // a stop signal does not wait for an alignment to finish
  } catch (const std::exception& e) {
    spdlog::error("blmc actor: {}", e.what());
  }
  impl_->core.close();  // no command reaches the board after this
  {
    std::lock_guard lock(impl_->wake_mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  if (impl_->watcher.joinable()) impl_->watcher.join();
  impl_->shut_down();
}

void BlmcActor::broker_state(bool connected) noexcept { impl_->broker_state(connected); }

}  // namespace axon::actor
