#include "axon/blmc/host/front_end.hpp"

#include "axon/blmc/host/error.hpp"

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <type_traits>

namespace axon::blmc {

namespace {

using host::HostErrc;

// The latest value from one producer to one consumer, neither ever waiting: three copies, one
// being written, one being read and one in the middle, handed over by exchanging indices (the
// "fresh" bit says the middle one is newer than the reader's). Each side's calls must come from
// one thread at a time; the two sides may run at once.
template <class T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  void write(const T& value) noexcept {
    slots_[back_] = value;
    back_ = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel) & kIndex;
  }
  // The latest value into `out` (the previous one again, or T{} before any write); true when it
  // is new since the last read.
  bool read(T& out) noexcept {
    const bool fresh = (middle_.load(std::memory_order_relaxed) & kFresh) != 0;
    if (fresh) front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    out = slots_[front_];
    return fresh;
  }

 private:
  static constexpr std::uint8_t kIndex = 3, kFresh = 4;
  std::array<T, 3> slots_{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // the producer's
  std::uint8_t front_ = 2;  // the consumer's
};

struct Action {
  Command command{};
  std::uint64_t number = 0;
};

// What the back end publishes every cycle.
struct Mirror {
  AppliedAction applied;
  ControlState state;
  ActionStats stats;
};

Error invalid(std::string text) { return Error(HostErrc::invalid_argument, std::move(text)); }

void check(const Command& c) {
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& m = c[k];
    const std::array<std::pair<const char*, double>, 5> values{{{"current_a (A)", m.current_a},
                                                                 {"position_rev (rev)", m.position_rev},
                                                                 {"velocity_rev_s (rev/s)", m.velocity_rev_s},
                                                                 {"kp (A/rev)", m.kp},
                                                                 {"kd (A per rev/s)", m.kd}}};
    for (const auto& [name, v] : values)
      if (!std::isfinite(v)) throw Exception(invalid(fmt::format("front end: motor {}: {} must be finite, got {}", k + 1, name, v)));
    if (m.kp < 0 || m.kd < 0)
      throw Exception(invalid(fmt::format("front end: motor {}: the gains must be >= 0 (a negative gain pushes away from "
                                          "the target), got kp {} and kd {}", k + 1, m.kp, m.kd)));
  }
}

}  // namespace

const char* to_string(ActionSource s) noexcept {
  switch (s) {
    case ActionSource::waiting: return "waiting";
    case ActionSource::action: return "action";
    case ActionSource::stale: return "stale";
    case ActionSource::gave_up: return "gave_up";
  }
  return "?";
}

struct FrontEnd::Shared {
  FrontEndOptions options;
  std::mutex writers;  // serialises set(): the slot has one producer
  std::uint64_t numbered = 0;
  std::atomic<std::uint64_t> set_count{0};
  TripleBuffer<Action> slot;  // front end -> back end
  mutable std::mutex readers;  // serialises the mirror's consumer side
  mutable TripleBuffer<Mirror> mirror;  // back end -> front end
  mutable Mirror last{};
  std::atomic<bool> gave_up{false};

  Mirror latest() const {
    const std::lock_guard lock(readers);
    mirror.read(last);
    return last;
  }
};

namespace {

// One run of the back end: the ControlLaw. Everything here is fixed-size; nothing waits.
class BackEnd {
 public:
  explicit BackEnd(std::shared_ptr<FrontEnd::Shared> shared)
      : s_(std::move(shared)),
        first_timeout_s_(std::chrono::duration<double>(s_->options.first_action_timeout).count()),
        stale_s_(std::chrono::duration<double>(s_->options.stale_after).count()) {}

  Command operator()(const ControlState& state) noexcept {
    take(state.time_s);
    AppliedAction a;
    a.cycle = state.cycle;
    a.time_s = state.time_s;
    a.source = source(state.time_s);
    if (a.source == ActionSource::action) a.command = current_.command;
    if (have_) {
      a.action = current_.number;
      a.age_s = state.time_s - taken_at_;
    }
    count(a.source);
    s_->mirror.write(Mirror{a, state, stats_});
    return a.command;
  }

 private:
  void take(double now_s) noexcept {
    Action next;
    if (!s_->slot.read(next) || gave_up_) return;
    current_ = next;
    taken_at_ = now_s;
    if (!have_) stats_.first_action_s = now_s;
    have_ = true;
    ++stats_.actions;
  }
  ActionSource source(double now_s) noexcept {
    if (!gave_up_ && !have_ && now_s >= first_timeout_s_) {
      gave_up_ = true;
      s_->gave_up.store(true, std::memory_order_release);
    }
    if (gave_up_) return ActionSource::gave_up;
    if (!have_) return ActionSource::waiting;
    return now_s - taken_at_ > stale_s_ ? ActionSource::stale : ActionSource::action;
  }
  void count(ActionSource source) noexcept {
    ++stats_.cycles;
    if (source != ActionSource::action) ++stats_.idle_cycles;
    if (source == ActionSource::stale) {
      ++stats_.stale_cycles;
      if (!stale_) ++stats_.stale_episodes;
    }
    stale_ = source == ActionSource::stale;
  }

  std::shared_ptr<FrontEnd::Shared> s_;
  double first_timeout_s_, stale_s_;
  Action current_{};
  double taken_at_ = 0;
  bool have_ = false, stale_ = false, gave_up_ = false;
  ActionStats stats_{};
};

}  // namespace

FrontEnd::FrontEnd(FrontEndOptions options) : shared_(std::make_shared<Shared>()) {
  if (options.first_action_timeout <= std::chrono::milliseconds::zero() || options.stale_after <= std::chrono::milliseconds::zero())
    throw Exception(invalid(fmt::format("front end: the first-action timeout and the stale limit must be > 0, got {} ms and {} ms",
                                        options.first_action_timeout.count(), options.stale_after.count())));
  shared_->options = options;
}

void FrontEnd::set(const Command& command) {
  check(command);
  auto& s = *shared_;
  const std::lock_guard lock(s.writers);
  s.slot.write(Action{command, ++s.numbered});
  s.set_count.store(s.numbered, std::memory_order_relaxed);
}

void FrontEnd::set_currents(std::array<double, 2> amperes) {
  set(Command{MotorCommand::current(amperes[0]), MotorCommand::current(amperes[1])});
}

ControlLaw FrontEnd::law() const {
  shared_->gave_up.store(false, std::memory_order_release);
  return BackEnd(shared_);
}

AppliedAction FrontEnd::applied() const { return shared_->latest().applied; }
ControlState FrontEnd::state() const { return shared_->latest().state; }
ActionStats FrontEnd::stats() const { return shared_->latest().stats; }
bool FrontEnd::gave_up() const noexcept { return shared_->gave_up.load(std::memory_order_acquire); }
std::uint64_t FrontEnd::actions_set() const noexcept { return shared_->set_count.load(std::memory_order_relaxed); }
const FrontEndOptions& FrontEnd::options() const noexcept { return shared_->options; }

}  // namespace axon::blmc
