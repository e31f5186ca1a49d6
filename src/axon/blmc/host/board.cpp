#include "axon/blmc/host/board.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/blmc/protocol/command_code.hpp"
#include "axon/blmc/protocol/q24.hpp"
#include "axon/can/error.hpp"

#include <boost/asio/buffer.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <unistd.h>

namespace axon::blmc::host {

using protocol::Command;
using protocol::CommandCode;

struct Board::Shared {
  Board* board = nullptr;  // null once the Board is gone
  std::optional<asio::posix::stream_descriptor> bell;
};

namespace {

can::Frame must(Result<can::Frame> r) { return std::move(r).value(); }

can::Frame flag_frame(CommandCode code, bool on) {
  auto c = Command::flag(code, on);
  return must(protocol::encode(c.value()));
}

double q24_safe(double v) noexcept {
  if (!std::isfinite(v)) return 0.0;
  return std::clamp(v, protocol::kQ24Min, 127.0);
}

asio::awaitable<void> read_loop(std::shared_ptr<Board::Shared> shared, can::Bus* bus) {
  for (;;) {
    auto r = co_await bus->receive();
    Board* b = shared->board;
    if (!b) co_return;
    if (!r) {
      // Bus closed: wake any waiter so it sees closed().
      b->closed_hook();
      co_return;
    }
    b->frame_hook(r.value());
  }
}

// IqRef=0, ENABLE_MTR1=0, ENABLE_MTR2=0, ENABLE_SYS=0: how every shutdown path leaves a board.
std::vector<can::Frame> disable_frames() {
  return {must(protocol::encode_iq_ref({})), flag_frame(CommandCode::enable_mtr1, false),
          flag_frame(CommandCode::enable_mtr2, false), flag_frame(CommandCode::enable_sys, false)};
}

// Sends `frames` in order; ends early when the bus was destroyed before a frame's turn.
asio::awaitable<void> send_all(can::Bus* bus, std::shared_ptr<const bool> bus_destroyed,
                               std::vector<can::Frame> frames) {
  for (const auto& f : frames) {
    if (*bus_destroyed) co_return;
    auto r = co_await bus->send(f);
    if (!r) co_return;
  }
}

}  // namespace

// ---- CyclicPort ---------------------------------------------------------------------------------

CyclicPort::CyclicPort(std::size_t capacity)
    : link_(capacity),
      disable_frames_{must(protocol::encode_iq_ref({})), flag_frame(CommandCode::enable_mtr1, false),
                      flag_frame(CommandCode::enable_mtr2, false)} {}

std::size_t CyclicPort::poll(core::TimePoint now) noexcept {
  std::size_t n = 0;
  can::Frame f;
  while (link_.receive(f)) {
    apply_frame(state_, f, now);
    ++n;
  }
  return n;
}

bool CyclicPort::send_currents(MotorPair amperes) noexcept {
  // Both values are in the Q24 range, so encoding cannot fail (and builds no error text).
  auto f = protocol::encode_iq_ref({q24_safe(amperes.motor1), q24_safe(amperes.motor2)});
  if (!f) return false;
  const bool ok = link_.send(f.value());
  sent_ += ok ? 1 : 0;
  return ok;
}

bool CyclicPort::send_disable() noexcept {
  bool ok = true;
  for (const auto& f : disable_frames_) ok = link_.send(f) && ok;
  return ok;
}

// ---- Board --------------------------------------------------------------------------------------

Board::Board(can::Bus& bus, BoardOptions options, const core::Clock& clock)
    : bus_(&bus),
      options_(std::move(options)),
      clock_(&clock),
      port_(std::make_unique<CyclicPort>(options_.link_capacity)),
      shared_(std::make_shared<Shared>()),
      wake_(bus.get_executor()),
      pump_done_(bus.get_executor()) {
  shared_->board = this;
  asio::co_spawn(bus.get_executor(), read_loop(shared_, bus_), asio::detached);
}

Board::~Board() {
  shared_->board = nullptr;
  if (shared_->bell) {
    boost::system::error_code ec;
    shared_->bell->cancel(ec);
  }
  if (motors_on_) queue_disable();
}

std::vector<can::Frame> Board::shutdown_frames() const {
  auto frames = disable_frames();
  if (onboard_used_)
    for (const auto& f : onboard_reset_frames()) frames.push_back(f);
  return frames;
}

void Board::queue_disable() {
  if (closed_ || !bus_->is_open()) return;
  asio::co_spawn(bus_->get_executor(), send_all(bus_, bus_->destroyed_flag(), shutdown_frames()), asio::detached);
}

void Board::interrupt() noexcept {
  interrupted_ = true;
  wake_.notify();
}

void Board::frame_hook(const can::Frame& f) {
  if (tap_) tap_(f, false);
  if (cyclic_) {
    port_->link_.deliver(f);
    return;
  }
  apply_frame(state_, f, clock_->now());
  wake_.notify();
}

void Board::closed_hook() {
  closed_ = true;
  wake_.notify();
}

asio::awaitable<Result<void>> Board::send_frame(const can::Frame& f) {
  if (cyclic_) co_return Error(HostErrc::cyclic_active, fmt::format("{}: send {}", options_.name, f.to_string()));
  if (tap_) tap_(f, true);
  auto r = co_await bus_->send(f);
  if (!r) co_return Error(r.error().code, fmt::format("{}: send {}: {}", options_.name, f.to_string(), r.error().detail));
  co_return ok();
}

asio::awaitable<Result<void>> Board::command(const Command& cmd) {
  auto f = protocol::encode(cmd);
  if (!f) co_return f.error();
  const can::Frame frame = f.value();
  auto r = co_await send_frame(frame);
  if (r && cmd.raw_value() != 0 &&
      (cmd.code() == CommandCode::enable_mtr1 || cmd.code() == CommandCode::enable_mtr2))
    motors_on_ = true;
  co_return r;
}

asio::awaitable<Result<void>> Board::send_currents(MotorPair amperes) {
  auto f = protocol::encode_iq_ref(amperes);
  if (!f) co_return f.error();
  const can::Frame frame = f.value();
  auto r = co_await send_frame(frame);
  co_return r;
}

asio::awaitable<Result<void>> Board::wait_until(core::TimePoint deadline, const std::function<bool()>& done) {
  for (;;) {
    if (done()) co_return ok();
    if (closed_) co_return Error(HostErrc::closed, options_.name);
    if (interrupted_) co_return Error(HostErrc::interrupted, options_.name);
    if (clock_->now() >= deadline) co_return Error(HostErrc::timeout, options_.name);
    wake_.reset();
    // The clock may be a test's manual clock: wait on the real timer in short slices.
    const auto left = std::min<core::Duration>(deadline - clock_->now(), 50ms);
    co_await wake_.wait_until(core::SteadyClock::instance().now() + left);
  }
}

asio::awaitable<Result<protocol::Status>> Board::wait_status(core::Duration timeout) {
  if (cyclic_) co_return Error(HostErrc::cyclic_active, options_.name);
  const auto start = state_.status_byte.count;
  auto r = co_await wait_until(clock_->now() + timeout, [&] { return state_.status_byte.count > start; });
  if (!r) {
    auto e = r.error();
    if (e == HostErrc::timeout)
      e.detail = fmt::format("{}: no status frame within {} ms", options_.name,
                             std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count());
    co_return e;
  }
  if (state_.undocumented_error()) co_return status_error();
  co_return state_.status.value;
}

asio::awaitable<Result<void>> Board::wait_data(core::Duration timeout, std::uint64_t n) {
  if (cyclic_) co_return Error(HostErrc::cyclic_active, options_.name);
  auto data = [&] {
    return state_.current.count + state_.position.count + state_.velocity.count + state_.adc.count;
  };
  const auto start = data();
  auto r = co_await wait_until(clock_->now() + timeout, [&] { return data() >= start + n; });
  if (!r && r.error() == HostErrc::timeout)
    co_return Error(HostErrc::timeout, fmt::format("{}: {} measurement frames expected within {} ms", options_.name, n,
                                                   std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count()));
  co_return r;
}

Error Board::status_error() const {
  if (state_.undocumented_error())
    return Error(HostErrc::board_error, fmt::format("{}: board sent undocumented error code {}", options_.name,
                                                    unsigned{protocol::error_bits(state_.status_byte.value)}));
  return Error(HostErrc::board_error,
               fmt::format("{}: board error {}", options_.name, protocol::name(state_.status.value.error)));
}

asio::awaitable<Result<void>> Board::wait_ready(core::Duration timeout) {
  if (cyclic_) co_return Error(HostErrc::cyclic_active, options_.name);
  const auto start = state_.status_byte.count;
  const auto deadline = clock_->now() + timeout;
  auto ready = [&](const protocol::Status& s) {
    return s.system_enabled && (!options_.motors[0] || (s.motor1_enabled && s.motor1_ready)) &&
           (!options_.motors[1] || (s.motor2_enabled && s.motor2_ready));
  };
  // Every status frame after the call until one shows the motors ready or an error.
  for (auto seen = start;; seen = state_.status_byte.count) {
    auto r = co_await wait_until(deadline, [&] { return state_.status_byte.count > seen; });
    if (!r) {
      if (r.error() != HostErrc::timeout) co_return r.error();
      if (state_.status_byte.count > start)
        co_return Error(HostErrc::not_ready, fmt::format("{}: not ready after {} ms: {}", options_.name,
                                                         std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count(),
                                                         state_.status.value.to_string()));
      co_return Error(HostErrc::timeout, fmt::format("{}: no status frame while waiting for ready", options_.name));
    }
    if (state_.undocumented_error() || state_.status.value.error != protocol::ErrorCode::none) co_return status_error();
    if (ready(state_.status.value)) co_return ok();
  }
}

asio::awaitable<Result<void>> Board::set_recv_timeout(std::uint32_t ms) {
  const auto cmd = Command::recv_timeout_ms(ms);
  auto r = co_await command(cmd);
  co_return r;
}

asio::awaitable<Result<void>> Board::enable() {
  if (interrupted_) co_return Error(HostErrc::interrupted, fmt::format("{}: enable", options_.name));
  auto r0 = co_await send_currents({});
  if (!r0) co_return r0;
  const auto sys = Command::flag(CommandCode::enable_sys, true).value();
  auto r1 = co_await command(sys);
  if (!r1) co_return r1;
  if (options_.send_all) {
    const auto all = Command::flag(CommandCode::send_all, true).value();
    auto r2 = co_await command(all);
    if (!r2) co_return r2;
  }
  for (int i = 0; i < 2; ++i) {
    if (!options_.motors[static_cast<std::size_t>(i)]) continue;
    const auto m = Command::flag(i == 0 ? CommandCode::enable_mtr1 : CommandCode::enable_mtr2, true).value();
    auto r3 = co_await command(m);
    if (!r3) co_return r3;
  }
  auto r4 = co_await wait_ready(options_.ready_timeout);
  co_return r4;
}

asio::awaitable<Result<void>> Board::recover() {
  const auto sys = Command::flag(CommandCode::enable_sys, true).value();
  auto r1 = co_await command(sys);
  if (!r1) co_return r1;
  auto r0 = co_await send_currents({});
  if (!r0) co_return r0;
  for (int i = 0; i < 2; ++i) {
    if (!options_.motors[static_cast<std::size_t>(i)]) continue;
    const auto m = Command::flag(i == 0 ? CommandCode::enable_mtr1 : CommandCode::enable_mtr2, true).value();
    auto r3 = co_await command(m);
    if (!r3) co_return r3;
  }
  auto r4 = co_await wait_ready(options_.ready_timeout);
  co_return r4;
}

asio::awaitable<Result<void>> Board::disable() {
  Result<void> first = ok();
  if (cyclic_) {
    auto r = co_await stop_cyclic();
    if (!r) first = r;
  }
  for (const auto& f : shutdown_frames()) {
    auto r = co_await send_frame(f);
    if (!r && first) first = r;
  }
  if (first) motors_on_ = false;
  co_return first;
}

// ---- the board's own controller and switches ---------------------------------------------------

asio::awaitable<Result<void>> Board::send_onboard(Result<std::vector<can::Frame>> frames) {
  if (cyclic_) co_return Error(HostErrc::cyclic_active, fmt::format("{}: on-board controller", options_.name));
  if (!frames) co_return Error(frames.error().code, fmt::format("{}: {}", options_.name, frames.error().detail));
  onboard_used_ = true;
  for (const auto& f : frames.value()) {
    auto r = co_await send_frame(f);
    if (!r) co_return r;
  }
  co_return ok();
}

asio::awaitable<Result<void>> Board::set_onboard_gains(OnboardGains gains) {
  auto r = co_await send_onboard(onboard_frames(gains));
  co_return r;
}

asio::awaitable<Result<void>> Board::set_onboard_references(OnboardReferences refs) {
  auto r = co_await send_onboard(onboard_frames(refs, state_.unwrap));
  co_return r;
}

asio::awaitable<Result<void>> Board::set_onboard_current_limits(OnboardCurrentLimits limits) {
  auto r = co_await send_onboard(onboard_frames(limits));
  co_return r;
}

asio::awaitable<Result<void>> Board::set_virtual_springs(std::array<bool, 2> on) {
  auto r = co_await send_onboard(virtual_spring_frames(on));
  co_return r;
}

asio::awaitable<Result<void>> Board::set_rollover_error(bool on) {
  auto r = co_await send_frame(rollover_error_frame(on));
  co_return r;
}

// ---- cyclic mode --------------------------------------------------------------------------------

asio::awaitable<Result<void>> Board::start_cyclic() {
  if (cyclic_) co_return Error(HostErrc::cyclic_active, options_.name);
  auto r0 = co_await send_currents({});
  if (!r0) co_return r0;
  if (options_.recv_timeout_ms > 0) {
    auto r1 = co_await set_recv_timeout(options_.recv_timeout_ms);
    if (!r1) co_return r1;
  }
  // Drop anything a previous run left in the link, then hand the state over.
  can::Frame stale;
  while (port_->link_.receive(stale)) {
  }
  while (port_->link_.take(stale)) {
  }
  port_->state_ = state_;
  const int fd = ::dup(port_->link_.tx_doorbell());
  if (fd < 0) co_return Error(HostErrc::link_overflow, fmt::format("{}: dup eventfd failed", options_.name));
  shared_->bell.emplace(bus_->get_executor(), fd);
  cyclic_ = true;
  pump_running_ = true;
  pump_done_.reset();
  asio::co_spawn(bus_->get_executor(), tx_pump(shared_), asio::detached);
  co_return ok();
}

asio::awaitable<void> Board::tx_pump(std::shared_ptr<Shared> shared) {
  std::uint64_t counter = 0;
  for (;;) {
    Board* b = shared->board;
    if (!b) co_return;
    can::Frame f;
    while (b->port_->link_.take(f)) {
      if (b->tap_) b->tap_(f, true);
      auto r = co_await b->bus_->send(f);
      b = shared->board;
      if (!b) co_return;
      if (!r && r.error() == can::CanErrc::closed) b->closed_ = true;
    }
    if (!b->cyclic_) break;
    boost::system::error_code ec;
    co_await shared->bell->async_read_some(asio::buffer(&counter, sizeof counter),
                                           asio::redirect_error(asio::use_awaitable, ec));
    if (ec && ec != asio::error::operation_aborted && ec != asio::error::would_block) {
      if (shared->board) spdlog::error("{}: tx doorbell: {}", shared->board->options_.name, ec.message());
      break;
    }
  }
  Board* b = shared->board;
  if (!b) co_return;
  b->pump_running_ = false;
  b->pump_done_.notify();
}

asio::awaitable<Result<void>> Board::stop_cyclic() {
  if (!cyclic_) co_return Error(HostErrc::not_cyclic, options_.name);
  cyclic_ = false;
  if (shared_->bell) {
    boost::system::error_code ec;
    shared_->bell->cancel(ec);
  }
  if (pump_running_) co_await pump_done_.wait_until(core::SteadyClock::instance().now() + 1s);
  shared_->bell.reset();
  state_ = port_->state_;
  const auto now = clock_->now();
  can::Frame f;
  while (port_->link_.receive(f)) apply_frame(state_, f, now);
  // The real-time side sent current references; leave the board at zero current.
  auto r = co_await send_currents({});
  co_return r;
}

}  // namespace axon::blmc::host
