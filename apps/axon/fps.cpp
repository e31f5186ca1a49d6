// `axon fps ...`: fiber positioners on one or more CAN buses, through the host driver
// (docs/fps-host.md). Every subcommand opens the buses, discovers the robots, does its job and
// closes; data goes to stdout (text or --json), progress and logs to stderr.
#include "axon/can/bus_spec.hpp"
#include "axon/can/cannet_client.hpp"
#include "axon/can/open.hpp"
#include "commands.hpp"
#include "fps_array.hpp"
#include "fps_stop.hpp"
#include "checks.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/host/bus_selection.hpp"
#include "axon/fps/host/trajectory_build.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/response.hpp"
#include "axon/fps/protocol/trajectory.hpp"
#include "id_list.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <cctype>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>

namespace axon::app {
namespace {

using json = nlohmann::json;
namespace host = fps::host;
namespace protocol = fps::protocol;

// The group's options: the buses (given, or from the --config file), output style.
struct FpsOptions {
  std::string config;
  host::BusSelection buses;
  bool json = false;
  bool no_color = false;
};

// What a subcommand does once the robots are known. Returns the exit code.
using Job = std::function<asio::awaitable<int>(host::Array&, const host::DiscoveryReport&)>;


void print_json(const json& j) {
  std::fputs(j.dump(2).c_str(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

json angles_json(const host::ArmAngles& a) { return json{{"alpha", a.alpha}, {"beta", a.beta}}; }

json row_json(const host::StatusRow& r) {
  json j{{"id", r.id}, {"bus", r.bus_name}, {"state", r.state()}, {"ready", r.ready()}};
  j["firmware"] = r.firmware ? json(r.firmware->to_string()) : json(nullptr);
  if (r.status) {
    j["status"] = fmt::format("0x{:016x}", r.status->raw());
    j["flags"] = r.status->names();
  }
  if (r.bootloader_status) j["bootloader_status"] = r.bootloader_status->to_string();
  j["position"] = r.position ? angles_json(*r.position) : json(nullptr);
  if (!r.error.empty()) j["error"] = r.error;
  return j;
}

// Buses where the discovery broadcast failed: the command cannot vouch for those robots.
std::size_t failed_buses(const host::DiscoveryReport& report) {
  return report.failed_buses.size();
}

// Opens the selected buses (channels of one gateway on one connection), discovers, runs `job`,
// closes everything. With `moves`, a stop signal stops every robot (fps_stop.hpp). A bus whose
// discovery failed makes the exit code at least 1.
int with_array(const FpsOptions& given, const Job& job, bool moves = false) {
  host::BusSelection selection = given.buses;
  if (!given.config.empty()) need(selection.apply_file(given.config));
  selection.apply_defaults();
  const auto specs = need(selection.specs());
  const double timeout_s = selection.timeout_s;
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const asio::any_io_executor ex = io.get_executor();
    const auto timeout = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(timeout_s));
    auto opened = co_await can::open_buses(ex, specs);
    auto buses = need(std::move(opened));
    std::vector<can::Bus*> raw;
    for (auto& b : buses) raw.push_back(b.get());
    host::ArrayOptions ao;
    ao.client.timeout = timeout;
    auto array = std::make_unique<host::Array>(raw, ao);
    if (moves) stop_robots_on_signal(set_on_signal, *array);

    int rc = 0;
    std::exception_ptr failure;
    try {
      auto r = co_await array->discover();
      const auto report = need(std::move(r));
      for (const auto& p : report.problems) spdlog::warn("discover: {}", p);
      spdlog::debug("discover: {} robots on {} buses", report.table.rows.size(), buses.size());
      rc = co_await job(*array, report);
      if (failed_buses(report) > 0 && rc == 0) {
        spdlog::error("discovery failed on {} of {} buses (above)", failed_buses(report), buses.size());
        rc = exit_code_value::failed;
      }
    } catch (...) {
      failure = std::current_exception();
    }
    co_await array->close();
    set_on_signal([] {});
    report_signal_stop(*array);
    array.reset();
    for (auto& b : buses) b->close();
    if (failure) std::rethrow_exception(failure);
    co_return rc;
  });
}

// The robot's handle, or an error naming the robots that were found.
host::Positioner* robot(host::Array& array, std::uint16_t id) {
  if (auto* p = array.find(id)) return p;
  const auto ids = array.ids();
  throw Exception(Error(host::HostErrc::unknown_positioner,
                        fmt::format("robot {} did not answer discovery on any bus (found: {})", id,
                                    ids.empty() ? std::string("none") : fmt::format("{}", fmt::join(ids, " ")))));
}

// ---- discover / status / position ---------------------------------------------------------------

// Robots that did not answer their status reads (a status report that lacks them failed).
std::size_t silent_robots(const host::StatusTable& t) {
  std::size_t n = 0;
  for (const auto& r : t.rows) n += r.error.empty() ? 0 : 1;
  if (n > 0) spdlog::error("{} of {} robots did not answer", n, t.rows.size());
  return n;
}

asio::awaitable<int> job_discover(const FpsOptions& o, host::Array& array, const host::DiscoveryReport& report) {
  if (o.json) {
    json j{{"buses", json::array()}, {"robots", json::array()}, {"problems", report.problems}};
    for (std::size_t b = 0; b < array.bus_count(); ++b)
      j["buses"].push_back(json{{"name", array.bus_name(b)}, {"robots", array.ids_on(b)}});
    for (const auto& r : report.table.rows) j["robots"].push_back(row_json(r));
    print_json(j);
  } else {
    for (std::size_t b = 0; b < array.bus_count(); ++b) {
      std::string list;
      for (auto id : array.ids_on(b)) list += fmt::format("{}{}", list.empty() ? "" : " ", id);
      fmt::print("{}: {} robots: {}\n", array.bus_name(b), array.ids_on(b).size(), list);
    }
    for (const auto& r : report.table.rows)
      fmt::print("  {:>4}  firmware {}\n", r.id, r.firmware ? r.firmware->to_string() : std::string("?"));
    for (const auto& p : report.problems) fmt::print("problem: {}\n", p);
    std::fflush(stdout);
  }
  co_return array.ids().empty() || silent_robots(report.table) > 0 ? 1 : 0;
}

// The status table with each robot's line coloured by its state (ANSI): ready green, moving or
// calibrating yellow, anything else (collision, no datum, no reply, bootloader) red.
std::string colored(const host::StatusTable& t) {
  const std::string text = t.to_text();
  std::string out;
  std::size_t pos = 0;
  for (std::size_t line = 0; pos < text.size(); ++line) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view l(text.data() + pos, end - pos);
    const char* code = nullptr;
    if (line > 0 && line - 1 < t.rows.size()) {
      const auto state = t.rows[line - 1].state();
      code = state == "ready" ? "32" : (state == "moving" || state == "calibrating") ? "33" : "31";
    }
    if (code) {
      out += fmt::format("\x1b[{}m{}\x1b[0m\n", code, l);
    } else {
      out += fmt::format("{}\n", l);
    }
    pos = end + 1;
  }
  return out;
}

asio::awaitable<int> job_status(const FpsOptions& o, host::Array&, const host::DiscoveryReport& report) {
  const auto& t = report.table;
  if (o.json) {
    json j{{"robots", json::array()}, {"ready", t.count_ready()}, {"problems", report.problems}};
    for (const auto& r : t.rows) j["robots"].push_back(row_json(r));
    print_json(j);
  } else {
    const bool color = !o.no_color && ::isatty(STDOUT_FILENO) != 0;
    fmt::print("{}", color ? colored(t) : t.to_text());
    fmt::print("{} robots, {} ready\n", t.rows.size(), t.count_ready());
    for (const auto& r : t.rows)
      if (r.status && !r.ready()) fmt::print("  {}: {}\n", r.id, r.status->to_string());
    std::fflush(stdout);
  }
  co_return silent_robots(t) == 0 && !t.rows.empty() ? 0 : 1;
}

asio::awaitable<int> job_position(const FpsOptions& o, const std::vector<std::string>& id_text, host::Array& array,
                                  const host::DiscoveryReport&) {
  std::vector<std::uint16_t> ids = id_text.empty() ? array.ids() : need(parse_id_lists(id_text));
  json j = json::object();
  for (auto id : ids) {
    auto* p = robot(array, id);
    auto r = co_await p->read_position();
    const auto pos = need(std::move(r));
    if (o.json) j[std::to_string(id)] = angles_json(pos);
    else fmt::print("{:>4}  alpha {:9.3f}  beta {:9.3f}\n", id, pos.alpha, pos.beta);
  }
  if (o.json) print_json(j);
  std::fflush(stdout);
  co_return 0;
}

// ---- motion -------------------------------------------------------------------------------------

struct GotoArgs {
  std::uint16_t id = 0;
  double alpha = 0, beta = 0;
  bool relative = false;
};

asio::awaitable<int> job_goto(const FpsOptions& o, const GotoArgs& g, host::Array& array, const host::DiscoveryReport&) {
  auto* p = robot(array, g.id);
  const host::ArmAngles value{g.alpha, g.beta};
  spdlog::info("goto: robot {} {} alpha {} beta {}", g.id, g.relative ? "by" : "to", g.alpha, g.beta);
  (void)p;
  std::map<std::uint16_t, host::ArmAngles> one{{g.id, value}};
  Result<host::Array::MoveResults> r = Error(CoreErrc::invalid_argument);
  if (g.relative) r = co_await array.goto_relative(std::move(one));
  else r = co_await array.goto_absolute(std::move(one));
  auto results = need(std::move(r));
  auto& moved = results.at(g.id);
  if (!moved && array.locked()) {  // a collision or a lost link stopped everything: a safety stop
    std::fprintf(stderr, "axon: error: %s\n", moved.error().message().c_str());
    co_return motion_exit_code(false, array);
  }
  if (!moved) throw Exception(moved.error());
  const auto m = std::move(moved).value();
  if (o.json) print_json(json{{"id", g.id}, {"target", angles_json(m.target)}, {"reached", angles_json(m.reached)}});
  else fmt::print("robot {} at alpha {:.3f} beta {:.3f} (target {:.3f} {:.3f})\n", g.id, m.reached.alpha, m.reached.beta,
                  m.target.alpha, m.target.beta);
  std::fflush(stdout);
  co_return 0;
}

asio::awaitable<int> job_move(const FpsOptions& o, const std::map<std::uint16_t, protocol::Trajectory>& trajectories,
                              bool load_only, host::Array& array, const host::DiscoveryReport&) {
  host::TrajectoryOptions to;
  to.start = !load_only;
  spdlog::info("move: uploading trajectories to {} robots", trajectories.size());
  auto r = co_await array.run_trajectories(trajectories, to);
  const auto report = need(std::move(r));
  if (o.json) {
    json j{{"started", report.started}, {"completed", report.completed}, {"outcome", report.outcome}, {"robots", json::array()}};
    for (const auto& run : report.robots) {
      json rj{{"id", run.id}, {"state", host::to_string(run.state)}, {"detail", run.detail}};
      if (run.reached) rj["reached"] = angles_json(*run.reached);
      if (run.target) rj["target"] = angles_json(*run.target);
      j["robots"].push_back(rj);
    }
    print_json(j);
  } else {
    fmt::print("{}\n", report.summary());
    std::fflush(stdout);
  }
  co_return load_only ? (report.ok(true) ? 0 : 1) : motion_exit_code(report.ok(), array);
}

asio::awaitable<int> job_stop(const FpsOptions& o, bool clear, host::Array& array, const host::DiscoveryReport&) {
  auto r = co_await array.stop_all(clear);
  need(std::move(r));
  const std::string what = clear ? "STOP_TRAJECTORY (collision flags cleared)" : "TRAJECTORY_ABORT";
  if (o.json) print_json(json{{"sent", what}, {"buses", array.bus_count()}});
  else fmt::print("{} sent on {} buses\n", what, array.bus_count());
  std::fflush(stdout);
  co_return 0;
}

asio::awaitable<int> job_unlock(const FpsOptions& o, host::Array& array, const host::DiscoveryReport&) {
  auto r = co_await array.unlock();
  const auto u = need(std::move(r));
  if (o.json) print_json(json{{"acknowledged", u.acknowledged}, {"silent", u.silent}});
  else fmt::print("unlocked: {} robots acknowledged, {} silent{}\n", u.acknowledged.size(), u.silent.size(),
                  u.silent.empty() ? "" : fmt::format(" ({})", fmt::join(u.silent, " ")));
  std::fflush(stdout);
  co_return u.silent.empty() ? 0 : 1;
}

// ---- calibration, datum -------------------------------------------------------------------------

struct CalibrateArgs {
  std::uint16_t id = 0;
  bool motor = false, datum = false, cogging = false, save = false;
};

asio::awaitable<int> job_calibrate(const FpsOptions& o, const CalibrateArgs& c, host::Array& array,
                                   const host::DiscoveryReport&) {
  auto* p = robot(array, c.id);
  host::CalibrationPlan plan;
  if (c.motor || c.datum || c.cogging || c.save) {
    plan.motors = c.motor;
    plan.datums = c.datum;
    plan.cogging = c.cogging;
    plan.save = c.save;
  }
  spdlog::info("calibrate: robot {}:{}{}{}{} (this takes a while; the robot's arms move)", c.id,
               plan.motors ? " motors" : "", plan.datums ? " datums" : "", plan.cogging ? " cogging" : "",
               plan.save ? " save" : "");
  auto r = co_await p->calibrate(plan);
  const auto rep = need(std::move(r));
  json j{{"id", c.id}, {"saved", rep.saved}, {"flags", rep.final_status.names()}};
  if (rep.motor_error) j["motor_error"] = json{{"alpha", rep.motor_error->alpha}, {"beta", rep.motor_error->beta}};
  if (rep.datum_error) j["datum_error"] = json{{"alpha", rep.datum_error->alpha}, {"beta", rep.datum_error->beta}};
  if (o.json) print_json(j);
  else {
    fmt::print("robot {} calibrated{}\n", c.id, rep.saved ? " and saved" : "");
    if (rep.motor_error) fmt::print("  motor calibration error: alpha {} beta {}\n", rep.motor_error->alpha, rep.motor_error->beta);
    if (rep.datum_error) fmt::print("  datum calibration error: alpha {} beta {}\n", rep.datum_error->alpha, rep.datum_error->beta);
    std::fflush(stdout);
  }
  co_return 0;
}

asio::awaitable<int> job_datum(const FpsOptions& o, std::uint16_t id, host::Array& array, const host::DiscoveryReport&) {
  auto* p = robot(array, id);
  spdlog::info("datum: robot {} drives both arms into their hard stops", id);
  auto r = co_await p->go_to_datums(host::Arm::both);
  const auto st = need(std::move(r));
  auto rp = co_await p->read_position();
  const auto pos = need(std::move(rp));
  if (o.json) print_json(json{{"id", id}, {"position", angles_json(pos)}, {"flags", st.names()}});
  else fmt::print("robot {}: datums initialised, at alpha {:.3f} beta {:.3f}\n", id, pos.alpha, pos.beta);
  std::fflush(stdout);
  co_return 0;
}

// ---- firmware -----------------------------------------------------------------------------------

asio::awaitable<int> job_upgrade(const FpsOptions& o, const std::vector<std::uint8_t>& image,
                                 const std::vector<std::uint16_t>& ids, host::Array& array, const host::DiscoveryReport&) {
  host::UpgradeOptions uo;
  uo.progress = [](const host::UpgradeProgress& p) {
    spdlog::info("upgrade: robot {}: {}/{} frames", p.positioner, p.chunks_acked, p.chunks_total);
  };
  auto r = co_await array.upgrade_firmware(ids, image, uo);
  const auto rep = need(std::move(r));
  if (o.json) {
    json j{{"size", rep.size}, {"crc32", fmt::format("0x{:08x}", rep.crc32)}, {"ok", rep.ok()}, {"robots", json::array()}};
    for (const auto& x : rep.robots)
      j["robots"].push_back(json{{"id", x.id}, {"outcome", host::to_string(x.outcome)}, {"reason", x.reason},
                                 {"chunks_acked", x.chunks_acked}, {"chunks_total", x.chunks_total},
                                 {"half_written", x.half_written}});
    print_json(j);
  } else {
    fmt::print("{}\n", rep.summary());
    std::fflush(stdout);
  }
  co_return rep.ok() ? 0 : 1;
}

// ---- raw ----------------------------------------------------------------------------------------

protocol::CommandId parse_command(const std::string& text) {
  unsigned n = 0;
  const auto* end = text.data() + text.size();
  auto [p, ec] = std::from_chars(text.data(), end, n);
  if (ec == std::errc() && p == end) {
    if (n > 255) throw Exception(usage(fmt::format("command {}: expected 0..255", text)));
    const auto name = protocol::command_name(static_cast<std::uint8_t>(n));
    const auto* info = protocol::find_command(name);
    if (!info) throw Exception(usage(fmt::format("command {} is not in either command table", n)));
    return info->id;
  }
  std::string upper = text;
  for (auto& ch : upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  const auto* info = protocol::find_command(upper);
  if (!info) throw Exception(usage(fmt::format("unknown command name '{}'", text)));
  return info->id;
}

std::vector<std::uint8_t> parse_hex(std::string text) {
  std::string digits;
  for (char ch : text)
    if (ch != '.' && ch != ' ' && ch != ':') digits += ch;
  if (digits.size() % 2 != 0) throw Exception(usage("hex data needs an even number of digits"));
  std::vector<std::uint8_t> out;
  for (std::size_t i = 0; i < digits.size(); i += 2) {
    unsigned v = 0;
    auto [p, ec] = std::from_chars(digits.data() + i, digits.data() + i + 2, v, 16);
    if (ec != std::errc() || p != digits.data() + i + 2) throw Exception(usage(fmt::format("bad hex data '{}'", text)));
    out.push_back(static_cast<std::uint8_t>(v));
  }
  return out;
}

std::string hex(std::span<const std::uint8_t> bytes) {
  std::string s;
  for (auto b : bytes) s += fmt::format("{:02X}", b);
  return s;
}

struct RawArgs {
  std::uint16_t id = 0;
  std::string command;
  std::string data;
};

asio::awaitable<int> job_raw(const FpsOptions& o, const RawArgs& a, host::Array& array, const host::DiscoveryReport&) {
  const auto cmd = parse_command(a.command);
  const auto bytes = parse_hex(a.data);
  const auto payload = need(protocol::Payload::from(bytes));
  robot(array, a.id);
  const auto bus = need(array.bus_of(a.id));
  auto r = co_await array.client(bus).request(a.id, cmd, payload);
  const auto reply = need(std::move(r));
  const std::string name(protocol::command_name(cmd));
  if (o.json)
    print_json(json{{"id", reply.positioner}, {"command", reply.command}, {"name", name},
                    {"code", protocol::response_name(reply.code)}, {"data", hex(reply.payload.span())}});
  else
    fmt::print("robot {} {} ({}): {} data {}\n", reply.positioner, name, reply.command, protocol::response_name(reply.code),
               reply.payload.span().empty() ? "-" : hex(reply.payload.span()));
  std::fflush(stdout);
  co_return 0;
}

// A subcommand's callback: runs `job` (a member of the shared options struct `Args`) on the array.
template <class Args, class JobFn>
std::function<void()> on_array(GlobalOptions& global, std::shared_ptr<FpsOptions> o, std::shared_ptr<Args> args, JobFn job, bool moves = false) {
  return [&global, o, args, job, moves] {
    global.exit_code = with_array(*o, [&](host::Array& a, const host::DiscoveryReport& r) { return job(*o, *args, a, r); }, moves);
  };
}

struct NoArgs {};
struct IdsArgs {
  std::vector<std::string> ids;
};
struct MoveArgs {
  std::string file;
  bool load_only = false;
  std::map<std::uint16_t, protocol::Trajectory> trajectories;  // loaded before the buses open
};
struct StopArgs {
  bool clear_flags = false;
};
struct DatumArgs {
  std::uint16_t id = 0;
};
struct UpgradeArgs {
  std::string firmware;
  std::vector<std::string> ids;
};

void add_bus_options(CLI::App& fps, FpsOptions& o) {
  auto& b = o.buses;
  fps.add_option("--config", o.config, "YAML bus selection: gateway, channels, socketcand, channel, buses, timeout_ms")
      ->check(CLI::ExistingFile);
  fps.add_option("--gateway", b.gateway, "CAN@net NT gateway (or `axon sim fps`) at HOST[:PORT]");
  fps.add_option("--channels", b.channels, "gateway channels, e.g. 1,2,3,4 (default 1)")->delimiter(',')->check(CLI::Range(1, 4));
  fps.add_option("--socketcand", b.socketcand, "socketcand server at HOST[:PORT]");
  fps.add_option("--channel", b.scd_channels, "socketcand channel (repeatable; default can0)");
  fps.add_option("--bus", b.buses, "any bus spec (repeatable): cannet://HOST/N, socketcand://HOST/CH, socketcan:IF");
  fps.add_flag("--json", o.json, "machine-readable output");
  fps.add_flag("--no-color", o.no_color, "no colours in the status table (colours only on a terminal anyway)");
  fps.add_option("--timeout", b.timeout_s, "seconds to wait for each reply (default 1)")->check(non_negative());
}

void add_read_commands(CLI::App& fps, GlobalOptions& global, const std::shared_ptr<FpsOptions>& o) {
  const auto none = std::make_shared<NoArgs>();
  fps.add_subcommand("discover", "robots per bus and their firmware")
      ->callback(on_array(global, o, none, [](const FpsOptions& f, NoArgs&, host::Array& a, const host::DiscoveryReport& r) {
        return job_discover(f, a, r);
      }));
  fps.add_subcommand("status", "status table: state, flags, position")
      ->callback(on_array(global, o, none, [](const FpsOptions& f, NoArgs&, host::Array& a, const host::DiscoveryReport& r) {
        return job_status(f, a, r);
      }));
  const auto pos = std::make_shared<IdsArgs>();
  auto* p = fps.add_subcommand("position", "arm angles of the listed robots (default all)");
  p->add_option("ids", pos->ids, "robot ids: 3, 1-6, 1,4,9");
  p->callback(on_array(global, o, pos, [](const FpsOptions& f, IdsArgs& x, host::Array& a, const host::DiscoveryReport& r) {
    return job_position(f, x.ids, a, r);
  }));
}

void add_motion_commands(CLI::App& fps, GlobalOptions& global, const std::shared_ptr<FpsOptions>& o) {
  const auto go = std::make_shared<GotoArgs>();
  auto* g = fps.add_subcommand("goto", "move one robot's arms (degrees) and wait");
  g->add_option("id", go->id, "robot id")->required()->check(CLI::Range(1, 2047));
  g->add_option("alpha", go->alpha, "alpha angle, degrees")->required();
  g->add_option("beta", go->beta, "beta angle, degrees")->required();
  g->add_flag("--relative", go->relative, "move by ALPHA and BETA instead of to them");
  g->callback(on_array(global, o, go, job_goto, true));

  const auto mv = std::make_shared<MoveArgs>();
  auto* m = fps.add_subcommand("move", "run trajectories from a file on several robots at once");
  m->add_option("-t,--trajectory", mv->file, "YAML/JSON: {ID: {alpha: [[deg, s], ...], beta: [...]}}")->required();
  m->add_flag("--load-only", mv->load_only, "upload and validate, do not start");
  const auto run_move = on_array(global, o, mv, [](const FpsOptions& f, MoveArgs& x, host::Array& a, const host::DiscoveryReport& r) {
    return job_move(f, x.trajectories, x.load_only, a, r);
  }, true);
  m->callback([mv, run_move] {
    mv->trajectories = need(host::load_trajectory_file(mv->file));
    run_move();
  });

  const auto st = std::make_shared<StopArgs>();
  auto* s = fps.add_subcommand("stop", "stop every robot on every bus (TRAJECTORY_ABORT broadcast)");
  s->add_flag("--clear-flags", st->clear_flags, "send STOP_TRAJECTORY instead, which also clears collision flags");
  s->callback(on_array(global, o, st, [](const FpsOptions& f, StopArgs& x, host::Array& a, const host::DiscoveryReport& r) {
    return job_stop(f, x.clear_flags, a, r);
  }));
  fps.add_subcommand("unlock", "clear collision flags on every bus (STOP_TRAJECTORY) and report who answered")
      ->callback(on_array(global, o, std::make_shared<NoArgs>(),
                          [](const FpsOptions& f, NoArgs&, host::Array& a, const host::DiscoveryReport& r) {
                            return job_unlock(f, a, r);
                          }));
}

void add_robot_commands(CLI::App& fps, GlobalOptions& global, const std::shared_ptr<FpsOptions>& o) {
  const auto cal = std::make_shared<CalibrateArgs>();
  auto* c = fps.add_subcommand("calibrate", "calibration sequence (default: motors, datums, save)");
  c->add_option("id", cal->id, "robot id")->required()->check(CLI::Range(1, 2047));
  c->add_flag("--motor", cal->motor, "calibrate the motors");
  c->add_flag("--datum", cal->datum, "calibrate the datums");
  c->add_flag("--cogging", cal->cogging, "calibrate cogging (long: up to 40 min)");
  c->add_flag("--save", cal->save, "save the calibration to flash");
  c->callback(on_array(global, o, cal, job_calibrate, true));

  const auto dt = std::make_shared<DatumArgs>();
  auto* d = fps.add_subcommand("datum", "datum search: both arms into their hard stops");
  d->add_option("id", dt->id, "robot id")->required()->check(CLI::Range(1, 2047));
  d->callback(on_array(global, o, dt, [](const FpsOptions& f, DatumArgs& x, host::Array& a, const host::DiscoveryReport& r) {
    return job_datum(f, x.id, a, r);
  }, true));

  const auto up = std::make_shared<UpgradeArgs>();
  auto* u = fps.add_subcommand("upgrade", "firmware upgrade of robots running their bootloader");
  u->add_option("--firmware", up->firmware, "firmware image file")->required()->check(CLI::ExistingFile);
  u->add_option("ids", up->ids, "robot ids: 3, 1-6, 1,4,9")->required();
  u->callback([o, up, &global] {
    const auto ids = need(parse_id_lists(up->ids));
    std::ifstream in(up->firmware, std::ios::binary);
    const std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) throw Exception(usage(fmt::format("cannot read {}", up->firmware)));
    global.exit_code = with_array(*o, [&](host::Array& a, const host::DiscoveryReport& r) { return job_upgrade(*o, image, ids, a, r); });
  });

  const auto raw = std::make_shared<RawArgs>();
  auto* rw = fps.add_subcommand("raw", "send one command and print the reply");
  rw->add_option("id", raw->id, "robot id")->required()->check(CLI::Range(1, 2047));
  rw->add_option("command", raw->command, "command number or name (GET_STATUS, 3, ...)")->required();
  rw->add_option("data", raw->data, "payload in hex, e.g. 0000803F");
  rw->callback(on_array(global, o, raw, job_raw));
}

}  // namespace

void add_fps_commands(CLI::App& app, GlobalOptions& global) {
  const auto o = std::make_shared<FpsOptions>();  // shared with every subcommand's callback
  auto* fps = app.add_subcommand("fps", "fiber positioners: discover, status, moves, trajectories, calibration, firmware");
  fps->require_subcommand(1);
  fps->fallthrough();  // bus options and --json may also follow the subcommand
  add_bus_options(*fps, *o);
  add_read_commands(*fps, global, o);
  add_motion_commands(*fps, global, o);
  add_robot_commands(*fps, global, o);
  add_fps_plan_commands(*fps, global, [o](const FpsArrayJob& job, bool moves) {
    return with_array(*o, [&job](host::Array& a, const host::DiscoveryReport&) { return job(a); }, moves);
  });
}

}  // namespace axon::app
