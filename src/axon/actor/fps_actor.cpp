#include "axon/actor/fps_actor.hpp"
#include "axon/core/clock.hpp"
#include "axon/actor/schemas.hpp"
#include "axon/fps/plan/arm_name.hpp"

#include "axon/fps/host/client_json.hpp"
#include "axon/fps/host/troubleshoot_json.hpp"
#include "axon/fps/layout/layout_check_json.hpp"
#include "axon/fps/plc/client.hpp"
#include "axon/fps/plc/plc_json.hpp"
#include "axon/net/endpoint.hpp"

#include "axon/core/error.hpp"
#include "axon/fps/host/client.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

namespace axon::actor {
namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

std::optional<double> number(const std::string& s) {
  double v = 0;
  const auto* end = s.data() + s.size();
  const auto [p, ec] = std::from_chars(s.data(), end, v);
  if (ec != std::errc() || p != end) return std::nullopt;
  return v;
}

// `ID ALPHA BETA` triplets; ID `all` stands for every known robot.
// A robot id argument of `verb`, one of the robots found on the buses.
std::uint16_t robot_id(const std::string& arg, const std::vector<std::uint16_t>& known, std::string_view verb) {
  const auto id = number(arg);
  const bool whole = id && *id >= 0 && *id <= 65535 && *id == static_cast<double>(static_cast<std::uint16_t>(*id));
  if (!whole) throw Exception(Error(CoreErrc::invalid_argument, fmt::format("{}: {:?} is not a robot id", verb, arg)));
  const auto robot = static_cast<std::uint16_t>(*id);
  if (std::find(known.begin(), known.end(), robot) == known.end())
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("{}: robot {} is not on the buses", verb, robot)));
  return robot;
}

std::map<std::uint16_t, fps::Angles> parse_targets(const std::vector<std::string>& args,
                                                   const std::vector<std::uint16_t>& known) {
  if (args.empty() || args.size() % 3 != 0)
    throw Exception(Error(CoreErrc::invalid_argument, "goto takes ID ALPHA BETA triplets (ID: a robot or all)"));
  std::map<std::uint16_t, fps::Angles> targets;
  for (std::size_t i = 0; i < args.size(); i += 3) {
    const auto alpha = number(args[i + 1]), beta = number(args[i + 2]);
    if (!alpha || !beta)
      throw Exception(Error(CoreErrc::invalid_argument, fmt::format("goto: {:?} {:?} are not angles in degrees",
                                                                    args[i + 1], args[i + 2])));
    if (args[i] == "all") {
      for (auto id : known) targets[id] = {*alpha, *beta};
      continue;
    }
    targets[robot_id(args[i], known, "goto")] = {*alpha, *beta};
  }
  return targets;
}

// `SEXTANT on|off` of the power verbs.
std::pair<int, bool> sextant_and_state(const std::vector<std::string>& args, std::string_view verb) {
  const auto n = args.size() == 2 ? number(args[0]) : std::nullopt;
  if (!n || (*n != 1 && *n != 2 && *n != 3 && *n != 4 && *n != 5 && *n != 6) || (args[1] != "on" && args[1] != "off"))
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("{} takes SEXTANT (1..6) and on or off", verb)));
  return {static_cast<int>(*n), args[1] == "on"};
}

}  // namespace

struct FpsActor::Impl {
  ActorCore& core;
  fps::Client& client;
  FpsActorOptions options;
  std::mutex device;  // one client call at a time (the watcher's locked() excepted: it only reads)

  struct Move {
    Command* command = nullptr;
    std::size_t robots = 0;
    Clock::time_point started;
  };
  std::mutex state;  // what follows
  json last_robots = json::array();
  std::optional<Move> move;
  bool was_locked = false;
  std::string lock_reason;

  std::mutex plc_mutex;  // one PLC call at a time (libmodbus contexts are not thread-safe)
  std::unique_ptr<fps::plc::PlcClient> plc;

  std::mutex wake_mutex;
  std::condition_variable wake;
  bool stopping = false;
  std::thread watcher;

  Impl(ActorCore& c, fps::Client& cl, FpsActorOptions o) : core(c), client(cl), options(o) {}

  void remember(const std::vector<fps::RobotStatus>& rows) {
    json robots = json::array();
    for (const auto& r : rows) robots.push_back(fps::to_json(r));
    std::lock_guard lock(state);
    last_robots = std::move(robots);
  }

  json counters_json() const {
    const auto c = core.counters();
    return json{{"received", c.received}, {"accepted", c.accepted}, {"not_json", c.not_json}, {"malformed", c.malformed},
                {"unknown", c.unknown},   {"refused", c.refused},   {"failed", c.failed},
                {"oversized", c.oversized}, {"busy", c.busy}};
  }

  // The status keywords; read from the robots when the client is free, else from the last read.
  json status_keywords() {
    std::unique_lock lock(device, std::try_to_lock);
    const bool fresh = lock.owns_lock();
    json j;
    if (fresh) {
      remember(client.status());
      j["locked"] = client.locked();
      j["locked_by"] = client.lock_reason();
      lock.unlock();
    }
    std::lock_guard s(state);
    if (!fresh) {
      j["locked"] = was_locked;
      j["locked_by"] = lock_reason;
    }
    j["robots"] = last_robots;
    std::size_t ready = 0;
    for (const auto& r : last_robots) ready += r.value("ready", false) ? 1 : 0;
    j["ready"] = ready;
    j["stale"] = !fresh;
    j["moving"] = move.has_value();
    if (move) j["move_progress"] = progress_json(*move);
    j["commands"] = counters_json();
    return j;
  }

  static json progress_json(const Move& m) {
    return json{{"command_id", m.command->id().command_id}, {"robots", m.robots}, {"elapsed_s", core::seconds_since(m.started)}};
  }

  // What a command does with the buses, told to FpsActorOptions::on_bus_use for as long as the
  // guard lives (then shared again).
  struct BusUseGuard {
    const std::function<void(fps::BusUse)>& hook;
    BusUseGuard(const std::function<void(fps::BusUse)>& h, fps::BusUse use) : hook(h) {
      if (hook) hook(use);
    }
    BusUseGuard(const BusUseGuard&) = delete;
    BusUseGuard& operator=(const BusUseGuard&) = delete;
    ~BusUseGuard() {
      try {
        if (hook) hook(fps::BusUse::shared);
      } catch (const std::exception& e) {
        spdlog::warn("fps actor: bus use: {}", e.what());
      }
    }
  };
  [[nodiscard]] BusUseGuard use_buses(fps::BusUse use) const { return BusUseGuard(options.on_bus_use, use); }

  void status(Command& c) { c.finish(status_keywords()); }

  void go(Command& c) {
    std::unique_lock lock(device);
    const auto targets = parse_targets(c.args(), client.robots());
    if (client.locked())
      throw Exception(Error(CoreErrc::invalid_argument, fmt::format("locked ({}): unlock first", client.lock_reason())));
    const auto tracking = start_move(c, targets);
    const auto buses = use_buses(fps::BusUse::moving);
    const auto out = client.goto_absolute(targets);
    remember(client.status());
    json kw{{"move_result", fps::to_json(out)}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (out.completed) c.finish(std::move(kw));
    else c.fail(out.summary.empty() ? "not every robot reached its target" : out.summary, std::move(kw));
  }

  // A running move as status and move_progress show it, from move_started until the guard ends.
  struct EndMove {
    Impl& impl;
    ~EndMove() {
      std::lock_guard s(impl.state);
      impl.move.reset();
    }
  };
  [[nodiscard]] EndMove start_move(Command& c, const std::map<std::uint16_t, fps::Angles>& targets) {
    json started = json::array();
    for (const auto& [id, a] : targets) started.push_back(json{{"id", id}, {"alpha", a.alpha}, {"beta", a.beta}});
    c.write(MessageCode::running, {{"move_started", {{"robots", targets.size()}, {"targets", started}}}});
    std::lock_guard s(state);
    move = Move{&c, targets.size(), Clock::now()};
    return EndMove{*this};
  }

  // plan ID ALPHA BETA [...] | plan FILE: collision-free moves from where every robot stands (robots
  // not listed fold), verified, then run (fps::Client::plan_and_move).
  void plan(Command& c) {
    std::unique_lock lock(device);
    const auto& args = c.args();
    if (args.empty()) throw Exception(Error(CoreErrc::invalid_argument, "plan takes ID ALPHA BETA triplets or a target FILE"));
    const bool file = args.size() == 1;
    const auto targets = file ? std::map<std::uint16_t, fps::Angles>{} : parse_targets(args, client.robots());
    if (client.locked())
      throw Exception(Error(CoreErrc::invalid_argument, fmt::format("locked ({}): unlock first", client.lock_reason())));
    const auto tracking = start_move(c, targets);
    const auto buses = use_buses(fps::BusUse::exclusive);  // the plan's upload comes first
    const auto out = file ? client.plan_and_move(args[0]) : client.plan_and_move(targets);
    remember(client.status());
    json kw{{"plan_result", fps::plan_result_json(out)}, {"move_result", fps::to_json(out.move)},
            {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (!out.moved || out.move.completed) c.finish(std::move(kw));
    else c.fail(out.move.summary.empty() ? "not every robot reached its target" : out.move.summary, std::move(kw));
  }

  // GET_ID on every bus again, then every robot's firmware and status (robots found since start-up
  // join).
  void discover(Command& c) {
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    const auto rows = client.discover();
    remember(rows);
    std::size_t ready = 0;
    for (const auto& r : rows) ready += r.ready ? 1 : 0;
    std::lock_guard s(state);
    c.finish({{"robots", last_robots}, {"ready", ready}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}});
  }

  // check: GET_ID on every bus, compared with the layout.
  void check(Command& c) {
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    const auto r = client.check_layout();
    json kw{{"layout_check", fps::to_json(r)}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (r.ok()) c.finish(std::move(kw));
    else c.fail(r.to_text(), std::move(kw));
  }

  // cold: the cold-temperature policy once, from the PLC's temperatures to every robot.
  void cold(Command& c) {
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    const auto r = client.apply_cold_policy();
    json kw{{"cold", fps::to_json(r)}};
    if (r.failed.empty()) c.finish(std::move(kw));
    else c.fail(r.text, std::move(kw));
  }

  void stop(Command& c) {
    bool moving = false;
    {
      std::lock_guard s(state);
      moving = move.has_value();
    }
    if (moving) {  // the move holds the client: interrupt() is the call any thread may make
      client.interrupt(fmt::format("{} command ({})", c.verb(), c.id().command_id));
      c.finish({{"stopped", {{"while_moving", true}}}, {"locked", true}});
      return;
    }
    std::lock_guard lock(device);
    client.stop();
    c.finish({{"stopped", {{"while_moving", false}}}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}});
  }

  void back_off(Command& c) {
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    std::vector<std::uint16_t> ids;
    for (const auto& a : c.args()) ids.push_back(robot_id(a, client.robots(), "backoff"));
    const auto out = client.back_off(ids);
    remember(client.status());
    json kw{{"back_off", fps::to_json(out)}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (out.ok) c.finish(std::move(kw));
    else c.fail(out.summary, std::move(kw));
  }

  void friction(Command& c) {
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    std::vector<std::uint16_t> ids;
    for (const auto& a : c.args()) ids.push_back(robot_id(a, client.robots(), "friction"));
    const auto report = client.friction_survey(ids, {}, options.friction_history);
    json kw{{"friction", fps::host::to_json(report)}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (report.ok()) c.finish(std::move(kw));
    else c.fail(report.summary(), std::move(kw));
  }

  void hall_test(Command& c) {
    const auto& args = c.args();
    const auto arm = args.size() == 2 ? fps::arm_from_name(args[1]) : std::nullopt;
    if (args.empty() || args.size() > 2 || (args.size() == 2 && !arm))
      throw Exception(Error(CoreErrc::invalid_argument, "halltest takes ID [alpha|beta]"));
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    fps::host::HallTestOptions o;
    o.alpha = !arm || *arm == 'a';
    o.beta = !arm || *arm == 'b';
    const auto report = client.hall_test(robot_id(args[0], client.robots(), "halltest"), o);
    json kw{{"hall_test", fps::host::to_json(report)}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (report.ok()) c.finish(std::move(kw));
    else c.fail(report.summary(), std::move(kw));
  }

  // upgrade FILE [XX.YY.ZZ]: the firmware of every robot through the PLC; `>` upgrade_progress
  // about once a second per sextant, then the outcome.
  void upgrade(Command& c) {
    const auto& args = c.args();
    if (args.empty() || args.size() > 2)
      throw Exception(Error(CoreErrc::invalid_argument, "upgrade takes FILE [XX.YY.ZZ] (the version the robots must run)"));
    std::ifstream in(args[0], std::ios::binary);
    if (!in) throw Exception(Error(CoreErrc::invalid_argument, fmt::format("upgrade: cannot open {}", args[0])));
    const std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    fps::UpgradeSettings s;
    if (args.size() == 2) s.expected_version = args[1];
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    const auto out = client.upgrade_firmware(image, s, [&c](const fps::SextantUpgrade& p) {
      c.write(MessageCode::running, {{"upgrade_progress", fps::to_json(p)}});
    });
    remember(client.status());
    json kw{{"upgrade_result", fps::to_json(out)}, {"locked", client.locked()}, {"locked_by", client.lock_reason()}};
    if (out.ok) c.finish(std::move(kw));
    else c.fail(out.summary, std::move(kw));
  }

  void unlock(Command& c) {
    std::lock_guard lock(device);
    const auto buses = use_buses(fps::BusUse::exclusive);
    const auto out = client.unlock();
    c.finish({{"unlocked", {{"acknowledged", out.acknowledged}, {"silent", out.silent}}},
              {"locked", client.locked()},
              {"locked_by", client.lock_reason()}});
  }

  // ---- the PLC: power and the sync line (docs/fps-plc.md) ----

  // The PLC client, connected on first use; plc_mutex held.
  fps::plc::PlcClient& plc_client() {
    if (options.plc_address.empty())
      throw Exception(Error(CoreErrc::invalid_argument, "no PLC: start the actor with --plc HOST[:PORT]"));
    if (!plc) plc = std::make_unique<fps::plc::PlcClient>(value_or_throw(net::parse_endpoint(options.plc_address, 502)));
    return *plc;
  }

  void plc_status(Command& c) {
    if (!c.args().empty()) throw Exception(Error(CoreErrc::invalid_argument, "plc takes no argument"));
    std::lock_guard lock(plc_mutex);
    c.finish({{"plc", fps::plc::to_json(value_or_throw(plc_client().status()))}});
  }

  // Sets a relay and reads it back: `relay` {name, on}; 'f' when the PLC shows another state.
  void set_relay(Command& c, const fps::plc::Relay& r, bool on) {
    std::lock_guard lock(plc_mutex);
    auto& p = plc_client();
    value_or_throw(p.set_relay(r, on));
    const bool now = value_or_throw(p.relay(r));
    json kw{{"relay", {{"name", r.to_string()}, {"on", now}}}};
    if (now == on) c.finish(std::move(kw));
    else c.fail(fmt::format("{} reads {} after it was set {}", r.to_string(), now ? "on" : "off", on ? "on" : "off"), std::move(kw));
  }

  // power|gateway SEXTANT on|off. Off is taken at any time (cutting power stops the robots); on is
  // refused while a command that drives the robots runs.
  void power(Command& c, fps::plc::RelayKind kind) {
    const auto [sextant, on] = sextant_and_state(c.args(), c.verb());
    const auto busy = core.busy_with();
    if (on && !busy.empty())
      throw Exception(Error(CoreErrc::invalid_argument, fmt::format("{} on refused: {:?} is running", c.verb(), busy)));
    set_relay(c, {kind, sextant}, on);
  }

  // sync pulse [HOLD_S] | high | low: the line that starts loaded trajectories on every robot.
  void sync(Command& c) {
    const auto& args = c.args();
    const bool pulse = !args.empty() && args[0] == "pulse";
    const auto hold = pulse && args.size() == 2 ? number(args[1]) : std::optional<double>(0.5);
    const bool level = args.size() == 1 && (args[0] == "high" || args[0] == "low");
    if (!(level || (pulse && args.size() <= 2 && hold && *hold > 0 && *hold <= 10)))
      throw Exception(Error(CoreErrc::invalid_argument, "sync takes pulse [HOLD_S, 0..10], high or low"));
    const fps::plc::Relay line{fps::plc::RelayKind::sync_line, 0};
    if (level) return set_relay(c, line, args[0] == "high");
    std::lock_guard lock(plc_mutex);
    auto& p = plc_client();
    value_or_throw(p.pulse_sync_line(std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(*hold))));
    c.finish({{"relay", {{"name", line.to_string()}, {"on", value_or_throw(p.relay(line))}}}});
  }

  // ---- the watcher's thread ----

  void check_lock() {
    bool locked = false;
    std::string reason;
    try {
      locked = client.locked();
      if (locked) reason = client.lock_reason();
    } catch (const std::exception& e) {
      spdlog::debug("fps actor: lock state: {}", e.what());
      return;
    }
    {
      std::lock_guard s(state);
      if (locked == was_locked) return;
      was_locked = locked;
      lock_reason = reason;
    }
    if (!locked) return core.broadcast(MessageCode::info, {{"locked", false}, {"locked_by", ""}});
    json kw{{"locked", true}, {"locked_by", reason}};
    const bool collision = reason.find("collision") != std::string::npos;
    if (collision) kw["collision_alert"] = {{"reason", reason}};
    core.broadcast(collision ? MessageCode::error : MessageCode::warning, kw);
  }

  void report_progress() {
    std::lock_guard s(state);
    if (move) move->command->write(MessageCode::running, {{"move_progress", progress_json(*move)}});
  }

  void watch() noexcept {
    const auto period = std::chrono::duration<double>(options.watch_period_s);
    auto next_status = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.status_period_s));
    auto next_progress = Clock::now();
    std::unique_lock lock(wake_mutex);
    while (!wake.wait_for(lock, period, [this] { return stopping; })) {
      lock.unlock();
      try {
        check_lock();
        const auto now = Clock::now();
        if (now >= next_progress) {
          report_progress();
          next_progress = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.progress_period_s));
        }
        if (options.status_period_s > 0 && now >= next_status) {
          core.broadcast(MessageCode::info, status_keywords());
          next_status = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.status_period_s));
        }
      } catch (const std::exception& e) {
        spdlog::warn("fps actor: {}", e.what());
      }
      lock.lock();
    }
  }
};

FpsActor::FpsActor(ActorCore& core, fps::Client& client, FpsActorOptions options)
    : impl_(std::make_unique<Impl>(core, client, options)) {
  impl_->remember(client.discover());
  auto* i = impl_.get();
  core.set_schema(std::string(schemas::fps));
  core.add({"status", "status", false, [i](Command& c) { i->status(c); }});
  core.add({"goto", "goto ID ALPHA BETA [ID ALPHA BETA ...] (ID: a robot or all)", true, [i](Command& c) { i->go(c); }});
  core.add({"plan", "plan ID ALPHA BETA [...] | plan FILE (collision-free, the others fold)", true,
            [i](Command& c) { i->plan(c); }});
  core.add({"discover", "discover", true, [i](Command& c) { i->discover(c); }});
  core.add({"check", "check (GET_ID on every bus against the layout)", true, [i](Command& c) { i->check(c); }});
  core.add({"cold", "cold (the cold-temperature policy once, from the PLC)", true, [i](Command& c) { i->cold(c); }});
  core.add({"stop", "stop", false, [i](Command& c) { i->stop(c); }});
  core.add({"abort", "abort", false, [i](Command& c) { i->stop(c); }});
  core.add({"unlock", "unlock", true, [i](Command& c) { i->unlock(c); }});
  core.add({"backoff", "backoff [ID ...] (no ID: every robot in contact)", true, [i](Command& c) { i->back_off(c); }});
  core.add({"upgrade", "upgrade FILE [XX.YY.ZZ] (firmware of every robot through the PLC)", true,
            [i](Command& c) { i->upgrade(c); }});
  core.add({"friction", "friction [ID ...] (no ID: every robot; the friction trend, 9.4.2)", true,
            [i](Command& c) { i->friction(c); }});
  core.add({"halltest", "halltest ID [alpha|beta] (hall sensor and motor test, 9.4.3)", true,
            [i](Command& c) { i->hall_test(c); }});
  core.add({"plc", "plc (relays and sensors of the PLC)", false, [i](Command& c) { i->plc_status(c); }});
  core.add({"power", "power SEXTANT on|off (the positioners' 24 V; off at any time)", false,
            [i](Command& c) { i->power(c, fps::plc::RelayKind::positioner_power); }});
  core.add({"gateway", "gateway SEXTANT on|off (the sextant's Ethernet-CAN gateway)", false,
            [i](Command& c) { i->power(c, fps::plc::RelayKind::gateway_power); }});
  core.add({"sync", "sync pulse [HOLD_S] | high | low (the sync line)", true, [i](Command& c) { i->sync(c); }});
  impl_->watcher = std::thread([i] { i->watch(); });
}

FpsActor::~FpsActor() {
  impl_->core.close();  // no command may reach the client after this
  {
    std::lock_guard lock(impl_->wake_mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  impl_->watcher.join();
}

}  // namespace axon::actor
