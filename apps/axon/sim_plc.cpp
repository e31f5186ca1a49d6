// `axon sim plc`: the PLC emulator (Modbus TCP) serving the register map of docs/fps-plc.md, with
// optional scripted sensor values. Relay changes are logged; prints `listening plc HOST:PORT`
// once it accepts connections.
#include "commands.hpp"
#include "axon/core/clock.hpp"
#include "axon/core/config.hpp"
#include "axon/fps/plc/emulator.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"

#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>

namespace axon::app {
namespace {

namespace plc = fps::plc;

struct SimPlcOptions {
  std::string listen = "127.0.0.1:0";
  std::string map_file;
  std::string script_file;
  double time_scale = 1.0;
  double temperature_c = 15.0;
  double duration_s = 0;
};

int run_sim_plc(const SimPlcOptions& o) {
  plc::EmulatorOptions eo;
  const auto ep = need(net::parse_endpoint(o.listen, 502));
  eo.bind_address = ep.host;
  eo.port = ep.port;
  if (!o.map_file.empty()) eo.map = need(plc::RegisterMap::from_config(need(core::ConfigNode::load_file(o.map_file))));
  if (!o.script_file.empty()) eo.script = need(plc::SensorScript::from_config(need(core::ConfigNode::load_file(o.script_file))));
  if (o.time_scale <= 0) throw Exception(Error(CoreErrc::invalid_argument, "--time-scale must be positive"));
  eo.time_scale = o.time_scale;
  eo.initial_temperature_c = o.temperature_c;
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    eo.hook_executor = io.get_executor();
    auto emulator = need(plc::PlcEmulator::start(eo));
    // The emulator logs every relay change with the client that made it.
    std::printf("listening plc %s\n", emulator->endpoint().to_string().c_str());
    std::fflush(stdout);
    spdlog::info("sim: PLC emulator (Ctrl-C to stop)");
    co_await wait_for_stop(io, o.duration_s, set_on_signal);
    const auto c = emulator->counters();
    emulator->stop();
    spdlog::info("sim: PLC served {} connections, {} requests, {} relay changes, {} bad frames", c.connections,
                 c.requests, c.relay_changes, c.bad_requests);
    co_return 0;
  });
}

}  // namespace

void add_sim_plc_command(CLI::App& app, GlobalOptions& global) {
  CLI::App* sim_cmd = app.get_subcommand("sim");
  auto o = std::make_shared<SimPlcOptions>();
  auto* p = sim_cmd->add_subcommand("plc", "PLC emulator (Modbus TCP): power and sync relays, sensors");
  p->add_option("--listen", o->listen, "serve on HOST:PORT (default 127.0.0.1:0, any free port)");
  p->add_option("--map", o->map_file, "register map YAML (default: docs/fps-plc.md)");
  p->add_option("--script", o->script_file, "sensor script YAML: [{t: S, sensor: NAME, value: V}, ...]");
  p->add_option("--time-scale", o->time_scale, "script seconds per real second (default 1)");
  p->add_option("--temperature", o->temperature_c, "initial temperature of every sensor, degC (default 15)");
  p->add_option("--duration", o->duration_s, "stop after this many seconds (default: until Ctrl-C)");
  p->callback([o, &global] { global.exit_code = run_sim_plc(*o); });
}

}  // namespace axon::app
