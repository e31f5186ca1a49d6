#include "axon/blmc/sim/simulated_board.hpp"

#include "axon/blmc/sim/runner.hpp"
#include "axon/can/bus_spec.hpp"
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/loop_thread.hpp"
#include "axon/net/endpoint.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace axon::blmc::sim {

struct SimulatedBoard::Impl {
  core::LoopThread loop;  // first in, last out: everything below lives on it
  std::unique_ptr<can::VirtualBusRegistry> registry;
  std::unique_ptr<Runner> runner;
  std::unique_ptr<can::SocketcandServer> server;
  std::vector<std::string> channels;
  std::string endpoint;
  bool stopped = false;

  ~Impl() {
    // Everything that lives on the loop goes on the loop's thread, then the thread stops.
    try {
      loop.call([this] {
        if (server) server->stop();
        server.reset();
        runner.reset();
        registry.reset();
      });
    } catch (...) {
    }
    loop.stop();
  }

  void start(const SimulatedBoardOptions& o);
  void check(unsigned board) const {
    if (board >= channels.size())
      throw std::out_of_range(fmt::format("simulated board {}: there are {}", board, channels.size()));
  }
};

// On the loop's thread.
void SimulatedBoard::Impl::start(const SimulatedBoardOptions& o) {
  if (o.boards == 0) throw Exception(Error(CoreErrc::invalid_argument, "a simulation needs at least one board"));
  const auto ex = loop.executor();
  registry = std::make_unique<can::VirtualBusRegistry>(ex);
  runner = std::make_unique<Runner>(ex);
  for (unsigned i = 0; i < o.boards; ++i) {
    channels.push_back(fmt::format("can{}", i));
    can::WireModel wire;
    wire.enabled = o.bus_load;
    registry->add(channels.back(), wire).value();
    runner->add(o.config, i < o.faults.size() ? o.faults[i] : BoardFaultPlan{}, *registry, channels.back()).value();
  }
  runner->start();
  const auto where = net::parse_endpoint(o.socketcand, can::kSocketcandPort).value();
  server = can::SocketcandServer::create(ex, *registry, where).value();
  endpoint = server->local_endpoint().to_string();
}

SimulatedBoard::SimulatedBoard(SimulatedBoardOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->loop.call([&] {
    core::apply_realtime(options.realtime);  // each step only when asked for: nothing by default
    impl_->start(options);  // on failure ~Impl takes down what started
  });
}

SimulatedBoard::~SimulatedBoard() { stop(); }

void SimulatedBoard::stop() {
  if (impl_->stopped) return;
  impl_->stopped = true;
  try {
    impl_->loop.call([i = impl_.get()] {
      if (i->server) i->server->stop();
      if (i->runner) i->runner->stop();
    });
  } catch (...) {
  }
}

std::string SimulatedBoard::bus_spec(unsigned board) const {
  impl_->check(board);
  return fmt::format("socketcand://{}/{}", impl_->endpoint, impl_->channels[board]);
}

std::string SimulatedBoard::endpoint() const { return impl_->endpoint; }
unsigned SimulatedBoard::boards() const noexcept { return static_cast<unsigned>(impl_->channels.size()); }

void SimulatedBoard::inject(FaultKind kind, unsigned board, core::Duration duration) {
  impl_->check(board);
  impl_->loop.call([i = impl_.get(), kind, board, duration] { i->runner->board(board).inject(kind, duration); });
}

void SimulatedBoard::power_cycle(unsigned board) {
  impl_->check(board);
  impl_->loop.call([i = impl_.get(), board] { i->runner->board(board).power_cycle(); });
}

SimulatedBoardReport SimulatedBoard::report(unsigned board) const {
  impl_->check(board);
  return impl_->loop.call([i = impl_.get(), board] {
    const auto& b = i->runner->board(board);
    SimulatedBoardReport r;
    r.status = b.status();
    r.status_byte = b.status_byte();
    r.motors = {b.motor_state(0), b.motor_state(1)};
    r.position_rev = {b.motor(0).position_rev(), b.motor(1).position_rev()};
    r.velocity_krpm = {b.motor(0).velocity_krpm(), b.motor(1).velocity_krpm()};
    r.current_a = {b.motor(0).current_a(), b.motor(1).current_a()};
    r.stats = b.stats();
    r.bus_load = i->registry->find(i->channels[board])->load(std::chrono::steady_clock::now());
    return r;
  });
}

RunnerStats SimulatedBoard::runner_stats() const {
  return impl_->loop.call([i = impl_.get()] { return i->runner->stats(); });
}

}  // namespace axon::blmc::sim
