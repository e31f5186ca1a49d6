// `axon fps layout ...`: the focal-plane layout file (docs/fps-layout.md): generate the default,
// summarise one, check one against the robots that answer on the buses.
#include "axon/can/bus_spec.hpp"
#include "axon/can/cannet_client.hpp"
#include "commands.hpp"
#include "fps_json.hpp"
#include "axon/fps/host/command_client.hpp"
#include "axon/fps/layout/layout_check.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_generator.hpp"
#include "axon/fps/host/layout_sweep.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <set>

namespace axon::app {
namespace {

using json = nlohmann::json;

struct LayoutArgs {
  std::string file;
  std::string output;
  fps::LayoutGeneratorOptions generator;
  bool json = false;
  int as_gateway = 0;
  double window_s = 0.5;
};

int generate(const LayoutArgs& a) {
  const auto plane = need(fps::generate_layout(a.generator));
  const std::string text = fps::to_yaml(plane);
  if (a.output.empty() || a.output == "-") {
    std::fputs(text.c_str(), stdout);
    return 0;
  }
  std::ofstream out(a.output);
  out << text;
  out.close();
  if (!out) throw Exception(Error(CoreErrc::io, fmt::format("cannot write '{}'", a.output)));
  std::fprintf(stderr, "wrote %s: %zu robots, %zu fiducials, %zu gateways\n", a.output.c_str(), plane.robots().size(),
               plane.fiducials().size(), plane.gateways().size());
  return 0;
}

int show(const LayoutArgs& a) {
  const auto plane = need(fps::load_layout_file(a.file));
  std::size_t disabled = 0, offline = 0, with_offsets = 0;
  std::map<std::string, std::size_t> fibres;
  std::vector<std::size_t> neighbour_counts;
  for (const auto& r : plane.robots()) {
    disabled += r.disabled ? 1 : 0;
    offline += r.offline ? 1 : 0;
    with_offsets += r.offsets ? 1 : 0;
    for (auto f : r.fibres) ++fibres[std::string(fps::fibre_name(f))];
    neighbour_counts.push_back(plane.neighbours(r.id).robots.size());
  }
  std::sort(neighbour_counts.begin(), neighbour_counts.end());
  const auto by_sextant = plane.by_sextant();
  const auto by_gateway = plane.by_gateway();
  const auto by_bus = plane.by_bus();
  if (a.json) {
    json j{{"name", plane.name()},       {"pitch_mm", plane.pitch_mm()}, {"robots", plane.robots().size()},
           {"fiducials", plane.fiducials().size()}, {"disabled", disabled}, {"offline", offline},
           {"with_offsets", with_offsets}, {"fibres", fibres}};
    for (const auto& [s, ids] : by_sextant) j["sextants"][std::to_string(s)] = ids.size();
    for (const auto& [g, ids] : by_gateway) {
      const auto* gw = plane.gateway(g);
      j["gateways"][std::to_string(g)] = json{{"address", gw ? gw->address : ""}, {"robots", ids.size()}};
    }
    for (const auto& [b, ids] : by_bus) j["buses"][b.to_string()] = ids.size();
    if (!neighbour_counts.empty())
      j["neighbours"] = json{{"min", neighbour_counts.front()},
                             {"median", neighbour_counts[neighbour_counts.size() / 2]},
                             {"max", neighbour_counts.back()}};
    std::puts(j.dump(2).c_str());
    return 0;
  }
  std::string s = fmt::format("layout {} ({}): {} robots, {} fiducials, pitch {} mm\n", plane.name(), a.file,
                              plane.robots().size(), plane.fiducials().size(), plane.pitch_mm());
  s += fmt::format("flags: {} disabled, {} offline, {} with arm offsets\n", disabled, offline, with_offsets);
  s += "fibres:";
  for (const auto& [f, n] : fibres) s += fmt::format(" {} {}", f, n);
  s += "\nrobots per sextant:";
  for (const auto& [sx, ids] : by_sextant) s += fmt::format(" {}:{}", sx, ids.size());
  s += "\nrobots per gateway:\n";
  for (const auto& [g, ids] : by_gateway) {
    const auto* gw = plane.gateway(g);
    s += fmt::format("  gateway {} ({}): {} robots; buses", g, gw && !gw->address.empty() ? gw->address : "no address",
                     ids.size());
    for (const auto& [b, bids] : by_bus)
      if (b.gateway == g) s += fmt::format(" {}:{}", int(b.channel), bids.size());
    s += "\n";
  }
  if (!neighbour_counts.empty())
    s += fmt::format("neighbours per robot: min {}, median {}, max {} (within {} mm)\n", neighbour_counts.front(),
                     neighbour_counts[neighbour_counts.size() / 2], neighbour_counts.back(),
                     plane.neighbour_options().robot_radius_mm);
  std::fputs(s.c_str(), stdout);
  return 0;
}

// Which gateways to open for a check, and as which layout gateway each counts.
struct GatewayTarget {
  std::uint16_t layout_id = 0;
  net::Endpoint endpoint;
  std::vector<int> channels;
};

std::vector<GatewayTarget> targets(const fps::FocalPlane& plane, const LayoutArgs& a, CLI::App& fps_cmd) {
  if (fps_cmd.get_option("--socketcand")->count() || fps_cmd.get_option("--bus")->count())
    throw Exception(Error(CoreErrc::invalid_argument,
                          "layout check talks to gateways: give --gateway HOST:PORT (with --as-gateway) or none to use "
                          "the layout's gateway addresses"));
  auto used_channels = [&](std::uint16_t g) {
    std::set<int> ch;
    for (const auto& b : plane.buses())
      if (b.gateway == g) ch.insert(b.channel);
    return std::vector<int>(ch.begin(), ch.end());
  };
  std::vector<GatewayTarget> out;
  if (fps_cmd.get_option("--gateway")->count()) {
    std::uint16_t id = static_cast<std::uint16_t>(a.as_gateway);
    if (id == 0) {
      if (plane.gateways().size() != 1)
        throw Exception(Error(CoreErrc::invalid_argument,
                              fmt::format("the layout has {} gateways: say which one --gateway is with --as-gateway N",
                                          plane.gateways().size())));
      id = plane.gateways().front().id;
    }
    if (!plane.gateway(id))
      throw Exception(Error(CoreErrc::invalid_argument, fmt::format("the layout has no gateway {}", id)));
    GatewayTarget t{id, need(net::parse_endpoint(fps_cmd.get_option("--gateway")->as<std::string>(), can::kCanNetPort)), {}};
    t.channels = fps_cmd.get_option("--channels")->count() ? fps_cmd.get_option("--channels")->as<std::vector<int>>()
                                                           : used_channels(id);
    out.push_back(std::move(t));
    return out;
  }
  for (const auto& g : plane.gateways()) {
    const auto ch = used_channels(g.id);
    if (ch.empty()) continue;
    if (g.address.empty())
      throw Exception(Error(CoreErrc::invalid_argument,
                            fmt::format("gateway {} has no address in the layout; give --gateway", g.id)));
    out.push_back(GatewayTarget{g.id, need(net::parse_endpoint(g.address, can::kCanNetPort)), ch});
  }
  return out;
}

int check(const LayoutArgs& a, CLI::App& fps_cmd) {
  const auto plane = need(fps::load_layout_file(a.file));
  const auto gateways = targets(plane, a, fps_cmd);
  double timeout_s = 1.0;
  if (fps_cmd.get_option("--timeout")->count()) timeout_s = fps_cmd.get_option("--timeout")->as<double>();
  return run_command([&](asio::io_context& io, auto) -> asio::awaitable<int> {
    const asio::any_io_executor ex = io.get_executor();
    std::vector<std::shared_ptr<can::CanNetGateway>> open;
    std::vector<std::unique_ptr<can::Bus>> buses;
    std::vector<std::unique_ptr<fps::host::CommandClient>> clients;
    fps::LayoutBuses layout_buses;
    fps::BusSweep unreachable;
    for (const auto& g : gateways) {
      std::vector<int> channels = g.channels;
      const can::CanNetOptions cn;
      const net::Endpoint ep = g.endpoint;
      auto r = co_await can::CanNetGateway::connect(ex, ep, channels, cn);
      if (!r) {
        for (int c : g.channels)
          unreachable.failed[fps::BusRef{g.layout_id, static_cast<std::uint8_t>(c)}] = r.error().message();
        continue;
      }
      open.push_back(std::move(r).value());
      for (int c : g.channels) {
        buses.push_back(need(open.back()->bus(c)));
        fps::host::ClientOptions co;
        co.timeout = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(timeout_s));
        clients.push_back(std::make_unique<fps::host::CommandClient>(*buses.back(), co));
        layout_buses.emplace_back(fps::BusRef{g.layout_id, static_cast<std::uint8_t>(c)}, clients.back().get());
      }
    }
    const auto window = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a.window_s));
    auto sweep = co_await fps::sweep_buses(layout_buses, window);
    for (auto& [b, why] : unreachable.failed) sweep.failed[b] = why;
    const auto result = fps::check_layout(plane, sweep);
    for (auto& c : clients) co_await c->stop();
    clients.clear();
    for (auto& b : buses) b->close();
    for (auto& g : open) g->close();
    if (a.json) std::puts(layout_check_json(result).dump(2).c_str());
    else std::fputs(result.to_text().c_str(), stdout);
    std::fflush(stdout);
    co_return result.ok() && sweep.failed.empty() ? 0 : 1;
  });
}

}  // namespace

void add_fps_layout_commands(CLI::App& app, GlobalOptions& global) {
  CLI::App* fps_cmd = app.get_subcommand("fps");
  const auto args = std::make_shared<LayoutArgs>();  // shared with the callbacks
  auto& a = *args;
  auto* layout = fps_cmd->add_subcommand("layout", "focal-plane layout files: generate, show, check against the buses");
  layout->require_subcommand(1);
  auto* gen = layout->add_subcommand("generate", "write the default layout (500 robots, 6 sextants, 24 buses)");
  gen->add_option("-o,--output", a.output, "output file (default stdout)");
  gen->add_option("--robots", a.generator.robots, "number of robots (default 500)");
  gen->add_option("--name", a.generator.name, "layout name (default 'default')");
  gen->add_option("--fiducials-per-sextant", a.generator.fiducials_per_sextant, "fiducials per sextant (default 10, plus the centre)");
  gen->add_option("--gateway-address", a.generator.gateway_address, "gateway address pattern, {} = sextant");
  gen->callback([args, &global] { global.exit_code = generate(*args); });
  auto* sh = layout->add_subcommand("show", "summary: robots per sextant, gateway and bus; fibres; neighbours");
  sh->add_option("file", a.file, "layout YAML")->required();
  sh->add_flag("--json", a.json, "machine-readable output");
  sh->callback([fps_cmd, args, &global] {
    args->json = args->json || fps_cmd->get_option("--json")->as<bool>();
    global.exit_code = show(*args);
  });
  auto* ck = layout->add_subcommand(
      "check", "GET_ID broadcast on every bus of the layout; report missing, unexpected, wrong-bus robots (exit 1 if any)");
  ck->add_option("file", a.file, "layout YAML")->required();
  ck->add_option("--as-gateway", a.as_gateway, "the layout gateway that `axon fps --gateway` is (default: the only one)");
  ck->add_option("--window", a.window_s, "seconds each broadcast collects replies (default 0.5)");
  ck->add_flag("--json", a.json, "machine-readable output");
  ck->callback([fps_cmd, args, &global] {
    args->json = args->json || fps_cmd->get_option("--json")->as<bool>();
    global.exit_code = check(*args, *fps_cmd);
  });
}

}  // namespace axon::app
