#include "axon/blmc/sim/runner.hpp"

#include "axon/can/error.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>

#include <deque>
#include <functional>
#include <vector>

namespace axon::blmc::sim {

struct Slot {
  Slot(Board b, std::unique_ptr<can::Bus> e, core::TimePoint powered)
      : board(std::move(b)), bus(std::move(e)), power_up(powered) {}
  Board board;
  std::unique_ptr<can::Bus> bus;
  core::TimePoint power_up;
  std::deque<can::Frame> outq;
  bool sending = false;
};

struct Runner::State : std::enable_shared_from_this<State> {
  State(asio::any_io_executor ex, RunnerOptions o)
      : executor(std::move(ex)), options(o), clock(o.clock ? o.clock : &core::SteadyClock::instance()), timer(executor) {
    scratch.reserve(64);
  }

  asio::any_io_executor executor;
  RunnerOptions options;
  const core::Clock* clock;
  asio::steady_timer timer;
  std::vector<std::unique_ptr<Slot>> slots;
  std::vector<can::Frame> scratch;
  RunnerStats stats;
  bool running = false;
  bool stopped = false;

  [[nodiscard]] BoardTime board_time(const Slot& s) const { return clock->now() - s.power_up; }

  Result<Board*> add(BoardConfig config, BoardFaultPlan faults,
                     const std::function<Result<std::unique_ptr<can::Bus>>(const can::BusOptions&)>& open) {
    if (stopped) return make_error(CoreErrc::closed, "blmc sim: runner stopped, cannot add boards");
    AXON_TRY(config.validate());
    AXON_TRY(faults.validate());
    can::BusOptions bo;
    bo.rx_capacity = 4096;
    AXON_TRY(bus, open(bo));
    auto slot = std::make_unique<Slot>(Board(std::move(config), std::move(faults)), std::move(bus), clock->now());
    Slot* s = slot.get();
    slots.push_back(std::move(slot));
    if (running) spawn(*s);
    return &s->board;
  }

  void spawn(Slot& s) { asio::co_spawn(executor, serve(shared_from_this(), &s), asio::detached); }

  static asio::awaitable<void> serve(std::shared_ptr<State> self, Slot* s) {
    while (!self->stopped) {
      auto frame = co_await s->bus->receive();
      if (self->stopped) break;
      if (!frame) {
        if (frame.error() == can::CanErrc::closed) break;
        continue;
      }
      const auto r = s->board.receive(frame.value(), self->board_time(*s));
      if (!r) ++self->stats.receive_errors;
    }
  }

  void step() {
    const auto max_data = static_cast<std::size_t>(options.max_catch_up / kCycle) + 1;
    for (auto& s : slots) {
      scratch.clear();
      s->board.advance(board_time(*s), scratch, max_data);
      if (scratch.empty() || stopped) continue;
      s->outq.insert(s->outq.end(), scratch.begin(), scratch.end());
      if (!s->sending) {
        s->sending = true;
        asio::co_spawn(executor, drain(shared_from_this(), s.get()), asio::detached);
      }
    }
  }

  static asio::awaitable<void> drain(std::shared_ptr<State> self, Slot* s) {
    while (!s->outq.empty() && !self->stopped) {
      const can::Frame f = s->outq.front();
      s->outq.pop_front();
      auto r = co_await s->bus->send(f);
      if (!r) ++self->stats.send_errors;
    }
    s->sending = false;
  }

  static asio::awaitable<void> tick(std::shared_ptr<State> self) {
    auto next = std::chrono::steady_clock::now() + self->options.tick;
    while (!self->stopped) {
      self->timer.expires_at(next);
      boost::system::error_code ec;
      co_await self->timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
      if (self->stopped) break;
      ++self->stats.ticks;
      self->step();
      next += self->options.tick;
      const auto now = std::chrono::steady_clock::now();
      if (now - next > self->options.max_catch_up) {
        next = now + self->options.tick;
        ++self->stats.schedule_restarts;
      }
    }
  }
};

Runner::Runner(asio::any_io_executor executor, RunnerOptions options)
    : state_(std::make_shared<State>(std::move(executor), options)) {
  if (options.tick < core::Duration::zero() || options.max_catch_up < core::Duration::zero())
    throw Exception(make_error(CoreErrc::invalid_argument, "blmc sim: tick and max_catch_up must not be negative"));
}

Runner::~Runner() { stop(); }

Result<Board*> Runner::add(BoardConfig config, BoardFaultPlan faults, can::BusProvider& provider, std::string_view channel) {
  return state_->add(std::move(config), std::move(faults), [&](const can::BusOptions& bo) {
    return provider.open(channel, bo);
  });
}

Result<Board*> Runner::add(BoardConfig config, BoardFaultPlan faults, can::VirtualBus& medium) {
  return state_->add(std::move(config), std::move(faults), [&](const can::BusOptions& bo) -> Result<std::unique_ptr<can::Bus>> {
    return medium.attach(fmt::format("blmc{}", state_->slots.size()), bo);
  });
}

void Runner::start() {
  auto& s = *state_;
  if (s.running || s.stopped) return;
  s.running = true;
  for (auto& slot : s.slots) s.spawn(*slot);
  if (s.options.tick > core::Duration::zero()) asio::co_spawn(s.executor, State::tick(state_), asio::detached);
}

void Runner::stop() {
  auto& s = *state_;
  if (s.stopped) return;
  s.stopped = true;
  s.running = false;
  s.timer.cancel();
  for (auto& slot : s.slots) slot->bus->close();
}

bool Runner::running() const noexcept { return state_->running; }
void Runner::step() { state_->step(); }
std::size_t Runner::size() const noexcept { return state_->slots.size(); }
Board& Runner::board(std::size_t i) { return state_->slots.at(i)->board; }
const can::Bus& Runner::endpoint(std::size_t i) const { return *state_->slots.at(i)->bus; }
BoardTime Runner::now(std::size_t i) const { return state_->board_time(*state_->slots.at(i)); }
const RunnerStats& Runner::stats() const noexcept { return state_->stats; }

}  // namespace axon::blmc::sim
