// `axon fps plc ...`: the instrument electronics box's PLC over Modbus TCP (docs/fps-plc.md):
// relays for sextant power, gateway power and the sync line; temperatures, humidity, pressure,
// coolant flow; the cold-temperature policy those temperatures call for.
#include "commands.hpp"
#include "axon/core/config.hpp"
#include "axon/fps/plc/client.hpp"
#include "axon/fps/plc/cold_policy.hpp"
#include "axon/fps/plc/plc_json.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace axon::app {
namespace {

using json = nlohmann::json;
namespace plc = fps::plc;

inline constexpr std::uint16_t kModbusPort = 502;

struct PlcArgs {
  std::string host;
  std::string map_file;
  std::string cold_file;
  double timeout_s = 1.0;
  bool json = false;
  int sextant = 0;
  std::string state;
  std::string sync_action;
  double hold_s = 0.5;
};

plc::PlcClient client(const PlcArgs& a) {
  if (a.host.empty()) throw Exception(Error(CoreErrc::invalid_argument, "give the PLC with --host HOST:PORT"));
  plc::RegisterMap map;
  if (!a.map_file.empty()) map = need(plc::RegisterMap::from_config(need(core::ConfigNode::load_file(a.map_file))));
  plc::PlcClientOptions o;
  o.timeout = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a.timeout_s));
  return plc::PlcClient(need(net::parse_endpoint(a.host, kModbusPort)), map, o);
}

bool parse_on_off(const std::string& s) {
  if (s == "on") return true;
  if (s == "off") return false;
  throw Exception(Error(CoreErrc::invalid_argument, fmt::format("expected on or off, got '{}'", s)));
}

int status(const PlcArgs& a) {
  auto c = client(a);
  const auto s = need(c.status());
  if (!a.json) {
    std::fputs(s.to_text().c_str(), stdout);
    return 0;
  }
  const json j = plc::to_json(s);
  std::puts(j.dump(2).c_str());
  return 0;
}

int power(const PlcArgs& a, plc::RelayKind kind) {
  auto c = client(a);
  const bool on = parse_on_off(a.state);
  const plc::Relay r{kind, a.sextant};
  need(c.set_relay(r, on));
  const bool now = need(c.relay(r));
  std::printf("%s %s\n", r.to_string().c_str(), now ? "on" : "off");
  return now == on ? 0 : 1;
}

int sync(const PlcArgs& a) {
  auto c = client(a);
  if (a.sync_action == "pulse") {
    need(c.pulse_sync_line(std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a.hold_s))));
  } else if (a.sync_action == "high" || a.sync_action == "low") {
    need(c.set_sync_line(a.sync_action == "high"));
  } else {
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("sync: expected pulse, high or low, got '{}'", a.sync_action)));
  }
  const bool now = need(c.relay({plc::RelayKind::sync_line, 0}));
  std::printf("sync line %s\n", now ? "high" : "low");
  return 0;
}

int cold(const PlcArgs& a) {
  auto c = client(a);
  plc::ColdPolicyConfig config;
  if (!a.cold_file.empty()) config = need(plc::ColdPolicyConfig::from_config(need(core::ConfigNode::load_file(a.cold_file))));
  const auto temps = need(c.temperatures());
  const auto d = plc::cold_policy(temps, config);
  if (!a.json) {
    std::fputs(d.report().c_str(), stdout);
    return 0;
  }
  json j{{"motor_rpm", d.settings.motor_rpm},
         {"alpha_holding_pct", d.settings.alpha_holding_pct},
         {"beta_holding_pct", d.settings.beta_holding_pct},
         {"speed_limited", d.settings.speed_limited},
         {"heating", d.settings.heating},
         {"coldest_c", d.coldest_c ? json(*d.coldest_c) : json(nullptr)},
         {"coldest_sensor", d.coldest_sensor},
         {"notes", d.notes}};
  std::puts(j.dump(2).c_str());
  return 0;
}

}  // namespace

void add_fps_plc_commands(CLI::App& app, GlobalOptions& global) {
  CLI::App* fps_cmd = app.get_subcommand("fps");
  const auto args = std::make_shared<PlcArgs>();  // shared with the callbacks
  auto& a = *args;
  auto* p = fps_cmd->add_subcommand("plc", "the PLC of the electronics box (Modbus TCP): power, sync line, sensors");
  p->require_subcommand(1);
  p->fallthrough();  // `axon fps plc status --host ...` as well as `axon fps plc --host ... status`
  p->add_option("--host", a.host, "PLC (or `axon sim plc`) at HOST[:PORT] (default port 502)")->required();
  p->add_option("--map", a.map_file, "register map YAML (default: docs/fps-plc.md)");
  p->add_option("--plc-timeout", a.timeout_s, "seconds to wait for each answer (default 1)");
  p->add_flag("--json", a.json, "machine-readable output");
  auto json_flag = [fps_cmd, args] { args->json = args->json || fps_cmd->get_option("--json")->as<bool>(); };
  p->add_subcommand("status", "every relay and sensor")->callback([json_flag, args, &global] {
    json_flag();
    global.exit_code = status(*args);
  });
  auto* pw = p->add_subcommand("power", "24 V to the positioners of one sextant");
  pw->add_option("sextant", a.sextant, "sextant 1..6")->required()->check(CLI::Range(1, 6));
  pw->add_option("state", a.state, "on or off")->required()->check(CLI::IsMember({"on", "off"}));
  pw->callback([args, &global] { global.exit_code = power(*args, plc::RelayKind::positioner_power); });
  auto* gw = p->add_subcommand("gateway", "power of one sextant's Ethernet-CAN gateway");
  gw->add_option("sextant", a.sextant, "sextant 1..6")->required()->check(CLI::Range(1, 6));
  gw->add_option("state", a.state, "on or off")->required()->check(CLI::IsMember({"on", "off"}));
  gw->callback([args, &global] { global.exit_code = power(*args, plc::RelayKind::gateway_power); });
  auto* sy = p->add_subcommand("sync", "the sync line: pulse (high, hold, low), high or low");
  sy->add_option("action", a.sync_action, "pulse, high or low")->required()->check(CLI::IsMember({"pulse", "high", "low"}));
  sy->add_option("--hold", a.hold_s, "seconds a pulse stays high (default 0.5)");
  sy->callback([args, &global] { global.exit_code = sync(*args); });
  auto* co = p->add_subcommand("cold", "the cold-temperature settings the current temperatures call for");
  co->add_option("--policy", a.cold_file, "cold policy YAML (thresholds, speeds, holding currents, sensors)");
  co->callback([json_flag, args, &global] {
    json_flag();
    global.exit_code = cold(*args);
  });
}

}  // namespace axon::app
