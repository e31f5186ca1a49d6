// `axon can ...`: dump, send, bridge and replay, on any transport (can/bus_spec.hpp).
#include "axon/can/bus_spec.hpp"
#include "axon/can/candump_log.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/open.hpp"
#include "axon/can/relay.hpp"
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "checks.hpp"
#include "rotation_options.hpp"
#include "commands.hpp"
#include "axon/core/clock.hpp"
#include "run.hpp"

#include <boost/asio/detached.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <optional>

namespace axon::app {
namespace {

using namespace std::chrono_literals;
using can::Bus;
using can::Frame;

core::WallTime now_wall() { return core::SteadyClock::instance().wall(); }

void print_stats(const Bus& bus) {
  const auto& s = bus.stats();
  spdlog::info("{}: {} frames in, {} out, {} filtered, {} rx dropped, {} tx dropped, {} protocol errors, "
               "{} error frames, load {:.1f}%",
               bus.name(), s.frames_in, s.frames_out, s.rx_filtered, s.rx_dropped, s.tx_dropped, s.protocol_errors,
               s.error_frames, 100.0 * s.load(core::SteadyClock::instance().now(), bus.options().bitrate));
}

// ---- dump -------------------------------------------------------------------------------------

struct DumpOptions {
  std::string bus;
  std::string log;
  std::vector<std::string> filters;
  std::uint64_t count = 0;
  double timeout_s = 0;
  bool quiet_frames = false;
  RotationArgs rotation;
};

int run_dump(const DumpOptions& o) {
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const auto spec = need(can::parse_bus_spec(o.bus));
    std::vector<can::Filter> filters;
    for (const auto& f : o.filters) filters.push_back(need(can::Filter::parse(f)));
    const asio::any_io_executor ex = io.get_executor();
    auto r1 = co_await can::open_bus(ex, spec);
    auto bus = need(std::move(r1));
    bus->set_filters(filters);
    std::optional<can::CandumpWriter> log;
    if (!o.log.empty()) log.emplace(need(can::CandumpWriter::create(o.log, o.rotation.limits())));
    set_on_signal([&, set_on_signal] {
      set_on_signal.signal_ends_normally();  // a dump runs until Ctrl-C: that is its normal end
      bus->close();
    });
    spdlog::info("dump: receiving on {}{}", spec.to_string(), o.log.empty() ? "" : " (logging to " + o.log + ")");

    const auto name = spec.short_name();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<core::Duration>(
                                                                    std::chrono::duration<double>(o.timeout_s));
    std::uint64_t n = 0;
    int rc = 0;
    while (o.count == 0 || n < o.count) {
      const core::Duration left = deadline - std::chrono::steady_clock::now();
      Result<Frame> f = Error(can::CanErrc::closed);
      if (o.timeout_s > 0) f = co_await bus->receive(left);
      else f = co_await bus->receive();
      if (!f) {
        if (f.error() == can::CanErrc::timeout && o.count > 0) {
          spdlog::error("dump: {} of {} frames within {} s", n, o.count, o.timeout_s);
          rc = exit_code_value::failed;
        } else if (f.error() != can::CanErrc::timeout && f.error() != can::CanErrc::closed) {
          spdlog::error("dump: {}", f.error().message());
          rc = 1;
        }
        break;
      }
      Frame frame = f.value();
      if (frame.timestamp().count() == 0) frame.set_timestamp(now_wall());
      const std::string line = can::format_candump_line(frame, name);
      if (!o.quiet_frames) {
        std::fputs(line.c_str(), stdout);
        std::fputc('\n', stdout);
        std::fflush(stdout);
      }
      if (log) need(log->write(frame, name));
      ++n;
    }
    if (log) need(log->flush());
    print_stats(*bus);
    bus->close();
    co_return rc;
  });
}

// ---- send -------------------------------------------------------------------------------------

struct SendOptions {
  std::string bus;
  std::vector<std::string> frames;
  unsigned repeat = 1;
  double interval_ms = 0;
};

int run_send(const SendOptions& o) {
  std::vector<Frame> frames;
  for (const auto& t : o.frames) frames.push_back(need(Frame::parse(t)));
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const auto spec = need(can::parse_bus_spec(o.bus));
    const asio::any_io_executor ex = io.get_executor();
    auto r2 = co_await can::open_bus(ex, spec);
    auto bus = need(std::move(r2));
    bool stop = false;
    set_on_signal([&] { stop = true; });
    asio::steady_timer timer(io);
    std::uint64_t sent = 0;
    for (unsigned r = 0; r < o.repeat && !stop; ++r) {
      for (const auto& f : frames) {
        if (stop) break;
        auto r3 = co_await bus->send(f);
        need(std::move(r3));
        ++sent;
        if (o.interval_ms > 0) {
          timer.expires_after(std::chrono::duration_cast<core::Duration>(std::chrono::duration<double, std::milli>(o.interval_ms)));
          co_await timer.async_wait(asio::use_awaitable);
        }
      }
    }
    auto r4 = co_await bus->flush(5s);
    need(std::move(r4));
    spdlog::info("send: {} frames to {}", sent, spec.to_string());
    bus->close();
    co_return 0;
  });
}

// ---- bridge -----------------------------------------------------------------------------------

struct BridgeOptions {
  std::vector<std::string> listen;
  std::vector<std::string> buses;
  bool wire_model = false;
  bool pace = false;
  std::uint32_t bitrate = can::kDefaultBitrate;
  double duration_s = 0;
  std::string fault_plan;
};

int run_bridge(const BridgeOptions& o) {
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const asio::any_io_executor ex = io.get_executor();
    can::WireModel wire{o.wire_model || o.pace, o.bitrate, o.pace};
    std::optional<can::FaultPlan> faults;
    if (!o.fault_plan.empty()) {
      const auto node = need(core::ConfigNode::load_file(o.fault_plan));
      faults = need(can::FaultPlan::from_config(node));
      spdlog::info("bridge: fault plan {} ({} rules) on every virtual bus", o.fault_plan, faults->rules.size());
    }
    can::VirtualBusRegistry registry(ex);
    std::vector<std::unique_ptr<Bus>> upstreams, pumps;
    std::vector<std::unique_ptr<can::RelayStats>> relay_stats;
    if (o.buses.empty()) need(registry.add("vcan0", wire));
    for (const auto& text : o.buses) {
      const auto spec = need(can::parse_bus_spec(text));
      if (spec.kind == can::BusSpec::Kind::virtual_bus) {
        need(registry.add(spec.channel, wire));
        continue;
      }
      // A real (or remote) bus: bridge it into a local virtual bus that every client shares.
      auto r5 = co_await can::open_bus(ex, spec);
      auto upstream = need(std::move(r5));
      need(registry.add(spec.short_name(), wire));
      auto pump = need(registry.open(spec.short_name()));
      for (int dir = 0; dir < 2; ++dir) {
        relay_stats.push_back(std::make_unique<can::RelayStats>());
        Bus& from = dir == 0 ? *upstream : *pump;
        Bus& to = dir == 0 ? *pump : *upstream;
        asio::co_spawn(ex, can::relay(from, to, *relay_stats.back()), asio::detached);
      }
      spdlog::info("bridge: {} served as channel {}", spec.to_string(), spec.short_name());
      upstreams.push_back(std::move(upstream));
      pumps.push_back(std::move(pump));
    }

    if (faults)
      for (const auto& c : registry.channels()) registry.find(c)->set_fault_plan(*faults);

    std::vector<std::unique_ptr<can::SocketcandServer>> scd;
    std::vector<std::unique_ptr<can::CanNetGatewayEmulator>> gateways;
    const auto channels = registry.channels();
    for (const auto& l : o.listen) {
      std::string_view text = l;
      const bool cannet = text.substr(0, 9) == "cannet://";
      if (cannet) text.remove_prefix(9);
      else if (text.substr(0, 13) == "socketcand://") text.remove_prefix(13);
      const auto ep = need(net::parse_endpoint(text, cannet ? can::kCanNetPort : can::kSocketcandPort));
      if (cannet) {
        std::vector<std::string> served(channels.begin(), channels.begin() + std::min<std::size_t>(4, channels.size()));
        can::CanNetEmulatorOptions eo;
        eo.bind_address = ep.host;
        eo.port = ep.port;
        auto gw = std::make_unique<can::CanNetGatewayEmulator>(ex, registry, served, eo);
        need(gw->start());
        std::printf("listening cannet %s\n", gw->local_endpoint().to_string().c_str());
        gateways.push_back(std::move(gw));
      } else {
        auto srv = need(can::SocketcandServer::create(ex, registry, ep));
        std::printf("listening socketcand %s\n", srv->local_endpoint().to_string().c_str());
        scd.push_back(std::move(srv));
      }
    }
    std::fflush(stdout);
    std::string names;
    for (const auto& c : channels) names += (names.empty() ? "" : ", ") + c;
    spdlog::info("bridge: serving {} (Ctrl-C to stop)", names);

    co_await wait_for_stop(io, o.duration_s, set_on_signal);

    for (auto& s : scd) s->stop();
    for (auto& g : gateways) g->stop();
    for (const auto& c : channels) {
      const auto& vs = registry.find(c)->stats();
      spdlog::info("bridge: {}: {} frames on the bus", c, vs.frames);
    }
    for (auto& u : upstreams) {
      print_stats(*u);
      u->close();
    }
    for (auto& p : pumps) p->close();
    co_return 0;
  });
}

// ---- replay -----------------------------------------------------------------------------------

struct ReplayOptions {
  std::string bus;
  std::string file;
  double speed = 1.0;
  bool no_timing = false;
  unsigned loops = 1;
  std::string only_iface;
  bool skip_bad = false;
};

// Gaps in a log at least this long (after --speed) are announced before the wait.
constexpr double kAnnouncedGap_s = 2.0;

int run_replay(const ReplayOptions& o) {
  if (o.speed <= 0) throw Exception(Error(CoreErrc::invalid_argument, "--speed must be positive"));
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const auto spec = need(can::parse_bus_spec(o.bus));
    const asio::any_io_executor ex = io.get_executor();
    auto r6 = co_await can::open_bus(ex, spec);
    auto bus = need(std::move(r6));
    bool stop = false;
    asio::steady_timer timer(io);
    set_on_signal([&] {
      stop = true;
      timer.cancel();  // a long gap in the log must not hold the stop back
    });
    std::uint64_t sent = 0, skipped = 0;
    const auto t_start = std::chrono::steady_clock::now();
    auto next_progress = t_start + 2s;
    for (unsigned loop = 0; loop < o.loops && !stop; ++loop) {
      auto reader = need(can::CandumpReader::open(o.file, can::CandumpReadOptions{o.skip_bad}));
      std::optional<core::WallTime> first;
      const auto loop_start = std::chrono::steady_clock::now();
      while (!stop) {
        auto entry = need(reader.next());
        if (!entry) break;
        if (entry->error_frame || (!o.only_iface.empty() && entry->iface != o.only_iface)) {
          ++skipped;  // error reports cannot be sent; other interfaces were not asked for
          continue;
        }
        if (!o.no_timing) {
          if (!first) first = entry->frame.timestamp();
          const auto offset = std::chrono::duration_cast<core::Duration>((entry->frame.timestamp() - *first) / o.speed);
          timer.expires_at(loop_start + offset);
          const auto gap = std::chrono::duration<double>(timer.expiry() - std::chrono::steady_clock::now()).count();
          if (gap >= kAnnouncedGap_s)
            spdlog::info("replay: waiting {:.1f} s for the next frame (line {})", gap, reader.lines_read());
          boost::system::error_code ec;
          co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
          if (stop) break;
        }
        auto r7 = co_await bus->send(entry->frame);
        need(std::move(r7));
        ++sent;
        if (std::chrono::steady_clock::now() >= next_progress) {
          spdlog::info("replay: {} frames sent, {:.1f} s", sent, std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
          next_progress += 2s;
        }
      }
      if (reader.lines_skipped() > 0)
        spdlog::warn("replay: {} malformed lines skipped in {} (first: {})", reader.lines_skipped(), o.file,
                     reader.first_skipped() ? reader.first_skipped()->message() : std::string("?"));
    }
    auto r8 = co_await bus->flush(5s);
    need(std::move(r8));
    if (stop) spdlog::warn("replay: stopped by {} before the end of {}", signal_name(received_stop_signal().load()), o.file);
    spdlog::info("replay: {} frames sent to {} in {:.3f} s ({} error frames or other interfaces skipped)", sent,
                 spec.to_string(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count(),
                 skipped);
    bus->close();
    co_return 0;
  });
}

const char* const kBusHelp =
    "bus: virtual:NAME | socketcand://HOST[:PORT]/CHANNEL | cannet://HOST[:PORT]/N | socketcan:IFACE";

}  // namespace

void add_can_commands(CLI::App& app, GlobalOptions& global) {
  auto* can_cmd = app.add_subcommand("can", "CAN buses: dump, send, bridge, replay");
  can_cmd->require_subcommand(1);

  auto dump = std::make_shared<DumpOptions>();
  auto* d = can_cmd->add_subcommand("dump", "print frames from a bus (candump -L format), optionally log them");
  d->add_option("-b,--bus", dump->bus, kBusHelp)->required();
  d->add_option("-l,--log", dump->log, "also write a candump log file");
  d->add_option("-f,--filter", dump->filters, "receive filter ID:MASK in hex (repeatable; any match passes)");
  d->add_option("-n,--count", dump->count, "stop after this many frames");
  d->add_option("-t,--timeout", dump->timeout_s, "seconds; with --count: fail (exit 1) if not reached, else run this long");
  d->add_flag("--no-print", dump->quiet_frames, "do not print frames (log only)");
  add_rotation_options(d, dump->rotation, "log", "--log");
  d->callback([dump, &global] { global.exit_code = run_dump(*dump); });

  auto send = std::make_shared<SendOptions>();
  auto* s = can_cmd->add_subcommand("send", "send frames given as ID#DATA (cansend notation)");
  s->add_option("-b,--bus", send->bus, kBusHelp)->required();
  s->add_option("frames", send->frames, "frames: 123#DEADBEEF, 12345678#00.11, 123#R, 123#R4")->required();
  s->add_option("-r,--repeat", send->repeat, "send the list this many times")->check(positive());
  s->add_option("-i,--interval", send->interval_ms, "milliseconds between frames")->check(non_negative());
  s->callback([send, &global] { global.exit_code = run_send(*send); });

  auto bridge = std::make_shared<BridgeOptions>();
  auto* b = can_cmd->add_subcommand("bridge", "serve buses over socketcand and/or as a CAN@net gateway emulator");
  b->add_option("-L,--listen", bridge->listen, "[socketcand://]HOST:PORT or cannet://HOST:PORT (port 0: any)")->required();
  b->add_option("-b,--bus", bridge->buses, std::string(kBusHelp) + " (repeatable; default: one virtual bus vcan0)");
  b->add_flag("--wire-model", bridge->wire_model, "account exact bit times on the virtual buses");
  b->add_flag("--pace", bridge->pace, "deliver frames at the real bus speed (implies --wire-model)");
  b->add_option("--bitrate", bridge->bitrate, "bit rate of the virtual buses")->check(CLI::Range(10'000u, 1'000'000u));
  b->add_option("--duration", bridge->duration_s, "stop after this many seconds (default: until Ctrl-C)");
  b->add_option("--fault-plan", bridge->fault_plan, "YAML fault plan applied to every virtual bus (docs/can-virtual.md)");
  b->callback([bridge, &global] { global.exit_code = run_bridge(*bridge); });

  auto replay = std::make_shared<ReplayOptions>();
  auto* r = can_cmd->add_subcommand("replay", "play a candump log onto a bus, keeping its timing");
  r->add_option("-b,--bus", replay->bus, kBusHelp)->required();
  r->add_option("file", replay->file, "candump log file")->required();
  r->add_option("--speed", replay->speed, "time scale: 2 plays twice as fast");
  r->add_flag("--no-timing", replay->no_timing, "send as fast as the bus takes them");
  r->add_option("--loop", replay->loops, "play the file this many times")->check(positive());
  r->add_option("--only", replay->only_iface, "only frames logged on this interface");
  r->add_flag("--skip-bad", replay->skip_bad, "skip malformed lines (counted) instead of stopping at the first");
  r->callback([replay, &global] { global.exit_code = run_replay(*replay); });
}

}  // namespace axon::app
