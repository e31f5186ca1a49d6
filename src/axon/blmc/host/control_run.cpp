#include "axon/blmc/host/control_run.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/core/wakeup.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::blmc::host {

namespace {

double seconds_of(core::Duration d) { return std::chrono::duration<double>(d).count(); }

Error invalid(std::string text) { return Error(HostErrc::invalid_argument, std::move(text)); }

// Drains the loop's records into `last` (and the record hook); true when there was at least one.
bool drain(ControlLoop& loop, const ControlHooks& hooks, CycleRecord& last) {
  CycleRecord rec{};
  bool any = false;
  while (loop.pop_record(rec)) {
    if (hooks.record) hooks.record(rec);
    last = rec;
    any = true;
  }
  return any;
}

// Watches the running loop from the bus thread until one of the ends listed in the header.
// Returns true when a request (not time, not done, not a fault) ended it.
asio::awaitable<bool> watch(Board& board, ControlLoop& loop, const ControlOptions& options, const ControlHooks& hooks) {
  const auto& clock = board.clock();
  const auto t0 = clock.now();
  CycleRecord last{};
  bool have = false;
  while (loop.running()) {
    co_await core::sleep_for(options.refresh);
    have = drain(loop, hooks, last) || have;
    const auto elapsed = clock.now() - t0;
    if (hooks.refresh && !hooks.refresh(seconds_of(elapsed), have ? &last : nullptr)) co_return true;
    if (board.interrupted() || (hooks.stop && hooks.stop())) co_return true;
    if (options.duration > core::Duration::zero() && elapsed >= options.duration) co_return false;
    if (hooks.done && hooks.done()) co_return false;
  }
  co_return false;
}

}  // namespace

Result<void> validate(const ControlOptions& o, std::uint32_t recv_timeout_ms) {
  if (o.loop.period <= core::Duration::zero()) return invalid("the loop period must be > 0");
  const double period_s = seconds_of(o.loop.period);
  const double rate = 1.0 / period_s;
  if (rate > kMaxLoopRateHz * (1 + 1e-9))
    return invalid(fmt::format("the loop rate must be at most {:g} Hz (the board runs at 1 kHz), got {:g}", kMaxLoopRateHz,
                               rate));
  if (recv_timeout_ms > 0 && period_s * 1000.0 >= recv_timeout_ms)
    return invalid(fmt::format("a loop at {:g} Hz sends one current reference every {:g} ms, not within the board's "
                               "receive timeout of {} ms: the board would trip",
                               rate, period_s * 1000.0, recv_timeout_ms));
  if (o.refresh <= core::Duration::zero()) return invalid("the refresh interval must be > 0");
  return o.limits.validate();
}

asio::awaitable<Result<ControlOutcome>> run_control(Board& board, Controller& controller, const ControlOptions& options,
                                                    ControlHooks hooks) {
  if (auto v = options.limits.validate(); !v) co_return v.error();
  auto c = co_await board.start_cyclic();
  if (!c) co_return c.error();
  ControlOutcome out;
  {
    ControlLoop loop({&board.port()}, controller, {options.limits}, options.loop, board.clock());
    if (auto s = loop.start(); !s) {
      auto e = s.error();
      auto back = co_await board.stop_cyclic();
      (void)back;  // the start's error is the one to tell
      co_return e;
    }
    out.stopped = co_await watch(board, loop, options, hooks);
    loop.stop();
    CycleRecord last{};
    drain(loop, hooks, last);
    out.stats = loop.stats();
    out.fault = loop.fault();
    out.records_dropped = loop.records_dropped();
  }
  auto s = co_await board.stop_cyclic();
  if (!s) co_return s.error();
  co_return out;
}

Measurements measurements_of(const CycleRecord& record, std::size_t board) {
  Measurements m;
  const auto& b = record.board[board];
  m.current.value = b.current;
  m.position.value = b.position;
  m.velocity.value = b.velocity;
  m.adc.value = b.adc;
  if (auto st = protocol::Status::from_byte(b.status)) m.status = {st.value(), {}, 1};
  return m;
}

asio::awaitable<Result<PdRun>> run_pd(Board& board, PdGains gains, std::array<PdTarget, 2> targets,
                                      const ControlOptions& options, ControlHooks hooks, core::Duration settle) {
  PdController ctl(1, gains, targets, settle);
  auto r = co_await run_control(board, ctl, options, std::move(hooks));
  if (!r) co_return r.error();
  PdRun out;
  out.control = std::move(r).value();
  for (int k = 0; k < 2; ++k) {
    out.tracking[static_cast<std::size_t>(k)] = ctl.tracking(0, k);
    out.start_rev[static_cast<std::size_t>(k)] = ctl.start_position(0, k);
  }
  co_return out;
}

asio::awaitable<Result<HomingRun>> run_homing(Board& board, HomingOptions homing, const ControlOptions& options,
                                              ControlHooks hooks) {
  HomingController ctl(1, homing);
  auto user_done = std::move(hooks.done);
  hooks.done = [&ctl, user_done] { return ctl.done() || (user_done && user_done()); };
  auto r = co_await run_control(board, ctl, options, std::move(hooks));
  if (!r) co_return r.error();
  HomingRun out;
  out.control = std::move(r).value();
  for (int k = 0; k < 2; ++k) out.motors[static_cast<std::size_t>(k)] = ctl.result(0, k);
  out.all_found = ctl.all_found();
  co_return out;
}

}  // namespace axon::blmc::host
