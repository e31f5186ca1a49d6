#include "axon/blmc/host/control_loop.hpp"

#include "axon/blmc/host/error.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <ctime>
#include <poll.h>

namespace axon::blmc::host {

namespace {

// Sleeps until `t` on CLOCK_MONOTONIC (what std::chrono::steady_clock reads on Linux).
void sleep_until(core::TimePoint t) noexcept {
  const auto ns = t.time_since_epoch().count();
  timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

ControlLoop::ControlLoop(std::vector<CyclicPort*> ports, Controller& controller, std::vector<SafetyLimits> limits,
                         LoopOptions options, const core::Clock& clock)
    : ports_(std::move(ports)),
      controller_(&controller),
      options_(std::move(options)),
      clock_(&clock),
      timing_(options_.period),
      records_(std::max<std::size_t>(options_.record_capacity, 2)) {
  if (ports_.empty() || ports_.size() > kMaxBoards)
    throw Exception(Error(HostErrc::invalid_argument, fmt::format("control loop: {} boards (1..{})", ports_.size(), kMaxBoards)));
  if (limits.size() == 1) limits.resize(ports_.size(), limits.front());
  if (limits.size() != ports_.size())
    throw Exception(Error(HostErrc::invalid_argument,
                          fmt::format("control loop: {} safety limits for {} boards", limits.size(), ports_.size())));
  if (options_.period <= core::Duration{0})
    throw Exception(Error(HostErrc::invalid_argument, "control loop: period must be positive"));
  for (auto& l : limits) {
    if (auto v = l.validate(); !v) throw Exception(v.error());
    safety_.emplace_back(l);
  }
  inputs_.resize(ports_.size());
  requests_.resize(ports_.size());
  trigger_seen_.resize(ports_.size());
}

ControlLoop::~ControlLoop() { stop(); }

std::optional<LoopFault> ControlLoop::fault() const noexcept {
  if (!faulted() || running()) return std::nullopt;
  return fault_;
}

Result<void> ControlLoop::start() {
  if (thread_.joinable()) return Error(HostErrc::invalid_argument, "control loop already started");
  stop_.store(false);
  std::atomic<bool> ready{false};
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this, &ready] {
    if (options_.realtime) {
      core::RealtimeRequest req;
      req.fifo_priority = options_.fifo_priority;
      req.lock_memory = options_.lock_memory;
      req.cpus = options_.cpus;
      rt_report_ = core::apply_realtime(req);
    }
    ready.store(true);
    ready.notify_one();
    run();
  });
  ready.wait(false);
  return ok();
}

void ControlLoop::stop() noexcept {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void ControlLoop::step(core::TimePoint deadline, core::TimePoint now) noexcept {
  timing_.cycle_started(deadline, now);
  const core::Duration dt = prev_start_ == core::TimePoint{} ? options_.period : now - prev_start_;
  prev_start_ = now;
  const auto n = ports_.size();
  for (std::size_t i = 0; i < n; ++i) {
    ports_[i]->poll(now);
    inputs_[i] = ports_[i]->latest();
    requests_[i] = {};
  }
  const std::uint64_t cycle = timing_.cycles() - 1;
  const ControlInput in{cycle, now, dt, std::span<const Measurements>(inputs_)};
  if (!started_controller_) {
    for (auto& s : safety_) s.arm(now);
    controller_->start(in);
    started_controller_ = true;
  }
  if (!halted_) controller_->update(in, std::span<MotorPair>(requests_));

  bool trip = false;
  for (std::size_t i = 0; i < n; ++i) {
    requests_[i] = safety_[i].apply(inputs_[i], halted_ ? MotorPair{} : requests_[i], now);
    if (safety_[i].newly_tripped() && !halted_ && !trip) {
      fault_ = LoopFault{i, safety_[i].fault()};
      trip = true;
    }
  }
  if (halted_ && !trip) learn_board_reason();
  if (trip) {
    // Stop everything: zero current and disable the motors of every board, then publish.
    for (std::size_t i = 0; i < n; ++i) disable_queued_[i] = ports_[i]->send_disable();
    halted_ = true;
    status_at_trip_ = inputs_[fault_.board].status_byte.count;
    faulted_.store(true, std::memory_order_release);
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      // A disable that found the link full is queued again until it goes in whole.
      if (halted_ && !disable_queued_[i]) disable_queued_[i] = ports_[i]->send_disable();
      else ports_[i]->send_currents(halted_ ? MotorPair{} : requests_[i]);
    }
  }

  CycleRecord rec;
  rec.cycle = cycle;
  rec.start = now;
  rec.period = timing_.last_period();
  rec.boards = static_cast<std::uint8_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& m = inputs_[i];
    auto& b = rec.board[i];
    b.current = m.current.value;
    b.position = m.position.value;
    b.velocity = m.velocity.value;
    b.adc = m.adc.value;
    b.command = halted_ ? MotorPair{} : requests_[i];
    b.status = m.status.value.to_byte();
    b.tripped = safety_[i].tripped();
  }
  const auto end = clock_->now();
  rec.compute = end - now;
  timing_.cycle_finished(end, deadline + options_.period);
  rec.overruns = timing_.overruns();
  if (!records_.push(rec)) dropped_.fetch_add(1, std::memory_order_relaxed);
  cycles_.store(timing_.cycles(), std::memory_order_relaxed);
  overruns_.store(timing_.overruns(), std::memory_order_relaxed);
}

void ControlLoop::learn_board_reason() noexcept {
  auto& f = fault_.fault;
  if (f.board_error != protocol::ErrorCode::none || f.undocumented_code != 0) return;
  // The board's own reason, from a status (decodable or not) that came after the trip.
  const auto& m = inputs_[fault_.board];
  if (m.status_byte.count <= status_at_trip_) return;
  if (m.undocumented_error()) f.undocumented_code = protocol::error_bits(m.status_byte.value);
  else f.board_error = m.status.value.error;
}

bool ControlLoop::wait_for_trigger(core::TimePoint deadline) noexcept {
  std::array<pollfd, kMaxBoards> fds{};
  const auto n = ports_.size();
  for (;;) {
    bool all = true;
    const auto now = clock_->now();
    for (std::size_t i = 0; i < n; ++i) {
      ports_[i]->poll(now);
      if (ports_[i]->latest().count(options_.trigger) <= trigger_seen_[i]) all = false;
    }
    if (all) {
      for (std::size_t i = 0; i < n; ++i) trigger_seen_[i] = ports_[i]->latest().count(options_.trigger);
      return true;
    }
    if (now >= deadline || stop_.load(std::memory_order_relaxed)) return false;
    for (std::size_t i = 0; i < n; ++i) fds[i] = pollfd{ports_[i]->link().rx_doorbell(), POLLIN, 0};
    const auto left = std::min<core::Duration>(deadline - now, std::chrono::milliseconds(10));
    timespec ts{0, static_cast<long>(left.count())};
    if (::ppoll(fds.data(), n, &ts, nullptr) > 0)
      for (std::size_t i = 0; i < n; ++i)
        if (fds[i].revents & POLLIN) ports_[i]->link().clear_rx_doorbell();
  }
}

void ControlLoop::run() noexcept {
  const auto period = options_.period;
  core::TimePoint next = clock_->now() + period;
  for (std::size_t i = 0; i < ports_.size(); ++i) trigger_seen_[i] = ports_[i]->latest().count(options_.trigger);
  while (!stop_.load(std::memory_order_acquire)) {
    if (options_.pacing == Pacing::clock) {
      sleep_until(next);
    } else {
      wait_for_trigger(next + period / 2);
      if (stop_.load(std::memory_order_acquire)) break;
    }
    const auto now = clock_->now();
    const auto due = options_.pacing == Pacing::clock ? next : std::min(next, now);
    step(due, now);
    if (options_.pacing == Pacing::measurements) {
      next = now + period;
    } else {
      next += period;
      const auto end = clock_->now();
      if (end > next) {
        // Too late for one or more deadlines: skip them instead of running a burst of cycles.
        const auto k = (end - next) / period + 1;
        next += k * period;
        timing_.skipped(static_cast<std::uint64_t>(k));
      }
    }
    if (halted_ && options_.stop_on_fault) {
      const auto& st = ports_[fault_.board]->latest().status_byte;
      const bool answered = st.count > status_at_trip_ || fault_.fault.kind == FaultKind::board_error ||
                            fault_.fault.kind == FaultKind::undocumented_error;
      if (answered || now - fault_.fault.at >= options_.fault_grace) break;
    }
  }
  // Stopped on request: the last reference every board gets from this loop is zero current (the
  // caller disables next; until then the board must not keep the controller's last value).
  if (!halted_)
    for (auto* p : ports_) p->send_currents({});
  running_.store(false, std::memory_order_release);
}

}  // namespace axon::blmc::host
