// `axon sim fps`: simulated fiber positioners served on virtual buses in this process, exposed as a
// CAN@net gateway emulator and/or a socketcand server so that other processes (axon fps, python-can,
// the host software in service) can drive them.
// `axon sim blmc` (apps/axon/sim_blmc.cpp) and `axon sim c4g` (sim_c4g.cpp) register under `sim` here.
#include "axon/can/bus_spec.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "axon/core/config.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"
#include "axon/fps/sim/simulator_config.hpp"
#include "id_list.hpp"
#include "layout_name.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/web/fps_sim_view.hpp"
#include "axon/web/server.hpp"
#include "run.hpp"

#include <boost/asio/detached.hpp>
#include <boost/asio/this_coro.hpp>

#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>

namespace axon::app {
namespace {

namespace sim = fps::sim;

struct SimFpsOptions {
  std::string robots = "1-20";
  std::string config;
  std::string gateway;
  std::string socketcand;
  unsigned buses = 1;
  double time_scale = 1.0;
  double duration_s = 0;
  // --layout mode
  std::string layout;
  std::string scenario;
  std::string plc = "127.0.0.1:0";
  std::string bind = "127.0.0.1";
  std::uint16_t port = 0;
  std::uint16_t base_port = 0;
  std::uint64_t seed = 1;
  bool folded = false;
  std::string write_layout;
  std::string http;  // with --layout: the web page of the plane on HOST:PORT
  // Every robot (both modes; over the config file's own settings when given).
  std::string firmware;
  std::string firmware_history;
  std::string start_without_trajectory;
};

// The firmware settings of the command line, applied to one robot's configuration.
void apply_firmware_options(const SimFpsOptions& o, sim::PositionerConfig& c) {
  if (!o.firmware.empty()) {
    c.firmware = need(fps::protocol::FirmwareVersion::parse(o.firmware));
    need(c.validate());
  }
  if (!o.firmware_history.empty())
    c.firmware_history = o.firmware_history == "field" ? sim::FirmwareHistory::field : sim::FirmwareHistory::document;
  if (!o.start_without_trajectory.empty())
    c.start_without_trajectory = o.start_without_trajectory == "refuse" ? sim::EmptyStart::refuse : sim::EmptyStart::accept;
}

// The simulator configuration the options describe: a file, or a hexagonal grid of the listed ids
// spread over can0..canN-1 in consecutive blocks (like daisy chains).
sim::SimulatorConfig build_config(const SimFpsOptions& o) {
  if (!o.config.empty()) {
    const auto node = need(core::ConfigNode::load_file(o.config));
    auto config = need(sim::SimulatorConfig::from_config(node));
    if (o.time_scale != 1.0) config.options.time_scale = o.time_scale;
    for (auto& r : config.robots) apply_firmware_options(o, r.config);
    return config;
  }
  const auto ids = need(parse_id_list(o.robots));
  std::vector<std::string> channels;
  for (unsigned i = 0; i < o.buses; ++i) channels.push_back(fmt::format("can{}", i));
  auto config = need(sim::SimulatorConfig::grid(ids.size(), channels));
  for (std::size_t i = 0; i < ids.size(); ++i) {
    config.robots[i].config.id = ids[i];
    apply_firmware_options(o, config.robots[i].config);
  }
  config.options.time_scale = o.time_scale;
  return config;
}

// How often the simulator's loop hands its state to the web page (the server pushes at this rate too).
constexpr auto kWebPublishPeriod = std::chrono::milliseconds(100);

asio::awaitable<void> publish_plane(std::shared_ptr<web::FpsSimView> view, std::shared_ptr<web::Source> source,
                                    std::shared_ptr<const bool> alive) {
  asio::steady_timer timer(co_await asio::this_coro::executor);
  while (*alive) {
    view->publish(*source);
    timer.expires_after(kWebPublishPeriod);
    boost::system::error_code ec;
    co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
  }
}

// --http: the plane's page on a web server of its own thread (docs/dashboard.md), its state read on
// the simulator's loop while *alive.
std::unique_ptr<web::Server> serve_plane_page(asio::io_context& io, const std::string& address, const fps::FocalPlane& plane,
                                              sim::FocalPlaneSimulator& fp, std::shared_ptr<const bool> alive) {
  const auto ep = need(net::parse_endpoint(address));
  web::ServerOptions so;
  so.address = ep.host;
  so.port = ep.port;
  so.push_period = kWebPublishPeriod;
  auto server = std::make_unique<web::Server>(so);
  auto source = std::make_shared<web::Source>("fps", fmt::format("fps: simulated focal plane '{}'", plane.name()), "fps");
  auto view = std::make_shared<web::FpsSimView>(plane, fp);
  source->set_info(view->info_json());
  server->add(source);
  asio::co_spawn(io, publish_plane(std::move(view), std::move(source), std::move(alive)), asio::detached);
  std::printf("listening http %s:%u\n", server->address().c_str(), unsigned{server->port()});
  return server;
}

// `axon sim fps --layout ...`: every robot of a layout behind one CAN@net emulator per gateway,
// plus the PLC emulator whose relays act on them.
int run_sim_layout(const SimFpsOptions& o) {
  if (o.time_scale <= 0) throw Exception(Error(CoreErrc::invalid_argument, "--time-scale must be positive"));
  const auto plane = need(resolve_layout(o.layout));
  sim::FocalPlaneSimOptions fo;
  fo.simulator.time_scale = o.time_scale;
  fo.seed = o.seed;
  fo.random_start = !o.folded;
  apply_firmware_options(o, fo.defaults);
  fo.binding.address = o.bind;
  fo.binding.port = o.port;
  if (o.base_port != 0) {
    std::uint16_t port = o.base_port;
    for (const auto& g : plane.gateways()) fo.binding.ports[g.id] = port++;
  }
  if (!o.scenario.empty()) fo.scenario = need(sim::Scenario::from_config(need(core::ConfigNode::load_file(o.scenario))));
  fo.plc = !o.plc.empty() && o.plc != "off";
  if (fo.plc) {
    const auto ep = need(net::parse_endpoint(o.plc, 502));
    fo.plc_options.bind_address = ep.host;
    fo.plc_options.port = ep.port;
  }
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    auto fp = need(sim::FocalPlaneSimulator::start(io.get_executor(), plane, fo));
    // Ready lines: one per gateway, then the PLC (tests parse them).
    for (const auto& g : fp->gateways()) {
      std::string chans;
      for (const auto& [ch, name] : g.channels) chans += fmt::format("{}{}", chans.empty() ? "" : ",", ch);
      std::printf("listening gateway %u %s channels %s robots %zu sextant %d\n", unsigned{g.id},
                  g.endpoint.to_string().c_str(), chans.c_str(), g.robots, g.sextant);
    }
    if (auto* p = fp->plc()) std::printf("listening plc %s\n", p->endpoint().to_string().c_str());
    // The page's publishing reads *fp: it stops when this scope ends, however it ends.
    const auto web_alive = std::make_shared<bool>(true);
    const std::unique_ptr<bool, void (*)(bool*)> stop_publishing(web_alive.get(), [](bool* alive) { *alive = false; });
    const auto web = o.http.empty() ? nullptr : serve_plane_page(io, o.http, plane, *fp, web_alive);
    if (!o.write_layout.empty()) {
      std::ofstream out(o.write_layout);
      std::map<std::uint16_t, std::string> addresses;
      for (const auto& g : fp->gateways()) addresses[g.id] = g.endpoint.to_string();
      out << fps::to_yaml(need(fps::with_gateway_addresses(plane, addresses)));
      out.close();
      if (!out) throw Exception(Error(CoreErrc::io, fmt::format("cannot write '{}'", o.write_layout)));
      std::printf("wrote layout %s\n", o.write_layout.c_str());
    }
    std::printf("ready\n");
    std::fflush(stdout);
    spdlog::info("sim: layout '{}': {} positioners on {} buses behind {} gateways, time scale {} (Ctrl-C to stop)",
                 plane.name(), fp->simulator().size(), plane.buses().size(), fp->gateways().size(), o.time_scale);

    co_await wait_for_stop(io, o.duration_s, set_on_signal);
    const auto& s = fp->simulator().stats();
    const auto& c = fp->counters();
    spdlog::info("sim: {} frames processed, {} sent ({} unsolicited), {} receive overflows, {} collisions "
                 "({} neighbour, {} obstacle), {} sync edges, {} sextant and {} gateway power changes",
                 s.frames_processed, s.frames_sent, s.unsolicited, fp->simulator().receive_overflows(),
                 s.neighbour_collisions + s.obstacle_collisions, s.neighbour_collisions, s.obstacle_collisions,
                 c.sync_edges, c.sextant_power_changes, c.gateway_power_changes);
    fp->stop();
    co_return 0;
  });
}

int run_sim_fps(const SimFpsOptions& o) {
  if (!o.layout.empty()) return run_sim_layout(o);
  if (o.gateway.empty() && o.socketcand.empty())
    throw Exception(Error(CoreErrc::invalid_argument, "give --gateway HOST:PORT and/or --socketcand HOST:PORT"));
  if (o.time_scale <= 0) throw Exception(Error(CoreErrc::invalid_argument, "--time-scale must be positive"));
  const auto config = build_config(o);
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const asio::any_io_executor ex = io.get_executor();
    can::VirtualBusRegistry registry(ex);
    // Channels in the order robots name them (can0, can1, ... for generated robots).
    std::vector<std::string> channels;
    for (const auto& r : config.robots)
      if (std::find(channels.begin(), channels.end(), r.channel) == channels.end()) channels.push_back(r.channel);
    std::sort(channels.begin(), channels.end());
    for (const auto& c : channels) need(registry.add(c));
    auto simulator = need(sim::make_simulator(ex, config, registry));

    std::unique_ptr<can::CanNetGatewayEmulator> gateway;
    std::unique_ptr<can::SocketcandServer> scd;
    if (!o.gateway.empty()) {
      const auto ep = need(net::parse_endpoint(o.gateway, can::kCanNetPort));
      if (channels.size() > 4) spdlog::warn("sim: a CAN@net NT 420 has 4 channels; serving the first 4 of {}", channels.size());
      std::vector<std::string> served(channels.begin(), channels.begin() + std::min<std::size_t>(4, channels.size()));
      can::CanNetEmulatorOptions eo;
      eo.bind_address = ep.host;
      eo.port = ep.port;
      gateway = std::make_unique<can::CanNetGatewayEmulator>(ex, registry, served, eo);
      need(gateway->start());
      std::printf("listening cannet %s\n", gateway->local_endpoint().to_string().c_str());
    }
    if (!o.socketcand.empty()) {
      const auto ep = need(net::parse_endpoint(o.socketcand, can::kSocketcandPort));
      scd = need(can::SocketcandServer::create(ex, registry, ep));
      std::printf("listening socketcand %s\n", scd->local_endpoint().to_string().c_str());
    }
    std::fflush(stdout);
    std::string where;
    for (std::size_t i = 0; i < channels.size(); ++i) {
      std::size_t n = 0;
      for (const auto& r : config.robots) n += r.channel == channels[i] ? 1 : 0;
      where += fmt::format("{}{} ({} robots{})", where.empty() ? "" : ", ", channels[i], n,
                           gateway && i < 4 ? fmt::format(", cannet channel {}", i + 1) : "");
    }
    spdlog::info("sim: {} positioners at time scale {} on {} (Ctrl-C to stop)", simulator->size(),
                 config.options.time_scale, where);

    co_await wait_for_stop(io, o.duration_s, set_on_signal);

    if (scd) scd->stop();
    if (gateway) gateway->stop();
    const auto& s = simulator->stats();
    spdlog::info("sim: {} frames processed, {} sent ({} unsolicited), {} receive overflows, {} collisions "
                 "({} neighbour, {} obstacle), {} send errors",
                 s.frames_processed, s.frames_sent, s.unsolicited, simulator->receive_overflows(),
                 s.neighbour_collisions + s.obstacle_collisions, s.neighbour_collisions, s.obstacle_collisions,
                 s.send_errors);
    simulator->stop();
    co_return 0;
  });
}

}  // namespace

void add_sim_commands(CLI::App& app, GlobalOptions& global) {
  auto* sim_cmd = app.add_subcommand("sim", "device simulators served over CAN@net / socketcand");
  sim_cmd->require_subcommand(1);
  const auto fps_args = std::make_shared<SimFpsOptions>();  // shared with the callback
  auto& fps = *fps_args;
  auto* f = sim_cmd->add_subcommand("fps", "simulated fiber positioners (calibrated, datums initialised, folded)");
  f->add_option("--robots", fps.robots, "robot ids: ranges and lists, e.g. 1-20 or 1,3,10-12 (default 1-20)");
  f->add_option("--config", fps.config, "simulator YAML (docs/fps-simulator.md) instead of --robots/--buses");
  f->add_option("--gateway", fps.gateway, "serve a CAN@net NT emulator on HOST:PORT (port 0: any)");
  f->add_option("--socketcand", fps.socketcand, "serve socketcand on HOST:PORT (channels can0..canN-1)");
  f->add_option("--buses", fps.buses, "spread the robots over this many buses (CAN@net channels 1..N)")
      ->check(CLI::Range(1u, 24u));
  f->add_option("--time-scale", fps.time_scale, "simulated seconds per real second (default 1)");
  f->add_option("--duration", fps.duration_s, "stop after this many seconds (default: until Ctrl-C)");
  f->add_option("--layout", fps.layout, "every robot of a layout (default, benchtop or FILE) behind one CAN@net "
                                     "emulator per gateway, with the PLC emulator");
  f->add_option("--scenario", fps.scenario, "with --layout: robots datum lost, uncalibrated, collided, ... (YAML)");
  f->add_option("--seed", fps.seed, "with --layout: seed of the random start positions (default 1)");
  f->add_flag("--folded", fps.folded, "with --layout: every robot at alpha 0, beta 180 (default: random alpha, beta folded)");
  f->add_option("--plc", fps.plc, "with --layout: PLC emulator on HOST:PORT (default 127.0.0.1:0; `off`: none)");
  f->add_option("--bind", fps.bind, "with --layout: address of the first gateway emulator, the next gateways on the "
                                 "next addresses (default 127.0.0.1: 127.0.0.1..127.0.0.6), or `layout`: each at "
                                 "the HOST:PORT of its layout entry");
  f->add_option("--port", fps.port, "with --layout: every gateway on this port, each at its own address (default: any free port)");
  f->add_option("--base-port", fps.base_port, "with --layout: gateway N listens on base + N - 1 (default: any free port)");
  f->add_option("--firmware", fps.firmware, "application firmware version of every robot, XX.YY.ZZ (default 04.01.13; "
                                         "04.01.00 and later are modelled)");
  f->add_option("--firmware-history", fps.firmware_history,
                "which commands a version takes: document (every command of the document's table, default) or "
                "field (precise-move switches 128..131 from 04.01.17 on)")
      ->check(CLI::IsMember({"document", "field"}));
  f->add_option("--start-without-trajectory", fps.start_without_trajectory,
                "START_TRAJECTORY while nothing is loaded: accept (code 0, the robot stays; robots in service, "
                "default) or refuse (code 2, INVALID_TRAJECTORY)")
      ->check(CLI::IsMember({"accept", "refuse"}));
  f->add_option("--write-layout", fps.write_layout, "with --layout: write the layout with the emulators' addresses to FILE");
  f->add_option("--http", fps.http, "with --layout: serve the plane's live page, /api/state and /metrics on HOST:PORT "
                                 "(port 0: any free one; docs/dashboard.md)")->needs("--layout");
  f->get_option("--config")->excludes("--robots")->excludes("--buses");
  f->get_option("--port")->excludes("--base-port");
  f->get_option("--layout")->excludes("--robots")->excludes("--buses")->excludes("--config")->excludes("--gateway")->excludes("--socketcand");
  f->callback([fps_args, &global] { global.exit_code = run_sim_fps(*fps_args); });

  add_sim_blmc_command(*sim_cmd, global);
  add_sim_c4g_command(*sim_cmd, global);
}

}  // namespace axon::app
