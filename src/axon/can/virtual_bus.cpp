#include "axon/can/virtual_bus.hpp"

#include "axon/core/deadline_queue.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <deque>

namespace axon::can {

namespace {

// Whole nanoseconds (rounded up) that `bits` take at `bitrate`, without overflowing for any
// realistic bit count.
core::Duration bits_to_time(std::uint64_t bits, std::uint32_t bitrate) noexcept {
  const std::uint64_t whole_s = bits / bitrate, rest = bits % bitrate;
  return core::Duration(static_cast<std::int64_t>(whole_s * 1'000'000'000ULL + (rest * 1'000'000'000ULL + bitrate - 1) / bitrate));
}

// One endpoint attached to a medium. Its transmit queue is what the medium arbitrates over.
class VirtualNode final : public Bus {
 public:
  struct Queued {
    Frame frame;
    std::uint64_t seq;        // medium-wide order of queueing: breaks ties between equal keys
    core::TimePoint queued;   // when the node handed it over (pacing: it cannot start earlier)
  };

  VirtualNode(std::shared_ptr<VirtualBus> medium, VirtualBus::Impl& impl, std::uint64_t id, std::string name,
              BusOptions options)
      : Bus(impl_executor(impl), std::move(name), options), medium_(std::move(medium)), impl_(&impl), id_(id) {}
  ~VirtualNode() override { detach(); }

  asio::awaitable<Result<void>> send(const Frame& frame) override { co_return submit(frame); }
  [[nodiscard]] std::size_t tx_pending() const noexcept override { return tx_.size(); }
  void close() override {
    detach();
    Bus::close();
  }

  // Medium side.
  [[nodiscard]] std::uint64_t id() const noexcept { return id_; }
  std::deque<Queued>& queue() noexcept { return tx_; }
  void take(const Frame& f, std::uint32_t bits) noexcept { count_sent(f, bits); }
  void hand_in(const Frame& f, std::uint32_t bits) { deliver(f, bits); }

 private:
  static asio::any_io_executor impl_executor(const VirtualBus::Impl& impl);
  Result<void> submit(const Frame& frame);
  void detach() noexcept;

  std::shared_ptr<VirtualBus> medium_;  // keeps the medium alive while the node exists
  VirtualBus::Impl* impl_;              // null once detached
  std::uint64_t id_;
  std::deque<Queued> tx_;
};

}  // namespace

// The medium. Everything runs on `executor`; nothing here is touched from another thread.
// Pacing uses the execution context's DeadlineQueue (one timer for every medium and simulator on
// that thread) rather than a timer of its own.
struct VirtualBus::Impl final : core::DeadlineClient {
  Impl(asio::any_io_executor ex, std::string n, WireModel w)
      : executor(std::move(ex)), name(std::move(n)), wire(w), deadlines(&core::DeadlineQueue::of(executor)),
        delay_timer(executor) {
    stats.created = core::SteadyClock::instance().now();
  }

  // The frame currently on the wire (paced mode) or being handled (unpaced mode).
  struct OnWire {
    Frame frame;
    std::uint64_t sender = 0;
    unsigned copies = 0;    // deliveries still to make (2 for a duplicated frame)
    bool drop = false;
    core::Duration delay{0};
    std::uint32_t bits = 0;  // wire bits of one copy (0 when nothing is accounted)
    core::TimePoint start{};  // pacing: when it went on the wire (the schedule's time, see hold_wire)
    std::uint32_t rx_bits = 0;  // wire bits of what receivers see (differs when corrupted)
  };
  struct Delayed {
    core::TimePoint due;
    std::uint64_t seq;
    Frame frame;
    std::uint64_t sender;
  };

  asio::any_io_executor executor;
  std::string name;
  WireModel wire;
  VirtualBusStats stats;
  FaultInjector injector;
  VirtualBus* owner = nullptr;

  std::vector<VirtualNode*> nodes;  // in attach order
  std::uint64_t next_node_id = 1;
  std::uint64_t next_seq = 0;
  bool active = false;  // a run is scheduled or a frame is on the wire

  OnWire on_wire;
  core::DeadlineQueue* deadlines;  // pacing: ends the frame on the wire (on_deadline)
  core::TimePoint wire_free{};    // pacing: when the last frame ends (or ended) on the schedule

  std::vector<Delayed> delayed;  // min-heap on (due, seq)
  asio::steady_timer delay_timer;
  core::TimePoint delay_armed = core::TimePoint::max();

  [[nodiscard]] bool pacing() const noexcept { return wire.pace_realtime; }
  [[nodiscard]] bool accounting() const noexcept { return wire.enabled || wire.pace_realtime; }
  std::shared_ptr<VirtualBus> self() const { return owner->shared_from_this(); }

  // A node queued a frame: make sure the medium will look at the queues.
  void kick() {
    if (active) return;
    active = true;
    asio::post(executor, [s = self()] { s->impl_->run(); });
  }

  void run() {
    if (pacing()) {
      start_next();
      return;
    }
    while (begin()) {
      while (finish_copy()) {
      }
    }
    active = false;
  }

  // Arbitration: among the heads of all queues, the lowest key wins; equal keys go in queueing
  // order. When pacing, only frames queued by the time the wire is free compete (the schedule may
  // run behind the clock, see hold_wire); if none was, the earliest queued go first. Returns null
  // when every queue is empty.
  VirtualNode* arbitrate() noexcept {
    VirtualNode* best = nullptr;
    std::uint32_t best_key = 0;
    std::uint64_t best_seq = 0;
    unsigned contenders = 0;
    core::TimePoint eligible = core::TimePoint::max();
    if (pacing()) {
      core::TimePoint first = core::TimePoint::max();
      for (auto* n : nodes)
        if (!n->queue().empty()) first = std::min(first, n->queue().front().queued);
      eligible = std::max(first, wire_free);
    }
    for (auto* n : nodes) {
      if (n->queue().empty()) continue;
      if (n->queue().front().queued > eligible) continue;
      ++contenders;
      const auto& head = n->queue().front();
      const std::uint32_t key = arbitration_key(head.frame);
      if (!best || key < best_key || (key == best_key && head.seq < best_seq)) {
        best = n;
        best_key = key;
        best_seq = head.seq;
      }
    }
    if (contenders > 1) ++stats.arbitration_rounds_contended;
    return best;
  }

  // Puts the arbitration winner on the wire: decides its fate and accounts its first copy.
  bool begin() {
    VirtualNode* winner = arbitrate();
    if (!winner) return false;
    const Frame frame = winner->queue().front().frame;
    const core::TimePoint queued = winner->queue().front().queued;
    winner->queue().pop_front();
    const std::uint32_t bits = frame_bits(frame).total;
    winner->take(frame, bits);

    on_wire = OnWire{};
    on_wire.sender = winner->id();
    on_wire.copies = 1;
    on_wire.frame = frame;
    if (!injector.empty()) {
      auto d = injector.apply(frame);
      if (d.drop) {
        on_wire.drop = true;
        ++stats.fault_dropped;
      } else if (d.duplicate) {
        on_wire.copies = 2;
        ++stats.fault_duplicated;
      } else if (d.delay > core::Duration::zero()) {
        on_wire.delay = d.delay;
        ++stats.fault_delayed;
      }
      if (d.corrupted) ++stats.fault_corrupted;
      on_wire.frame = d.frame;
    }
    on_wire.rx_bits = on_wire.frame == frame ? bits : frame_bits(on_wire.frame).total;
    // The wire carries what the sender sent; corruption is the receivers' view of it.
    on_wire.bits = accounting() ? bits : 0;
    on_wire.start = std::max(queued, wire_free);
    account();
    return true;
  }

  void account() noexcept {
    ++stats.frames;
    if (!accounting()) return;
    stats.bits += on_wire.bits;
    stats.busy = bits_to_time(stats.bits, wire.bitrate);
  }

  // The current copy has finished on the wire: hand it over. True when another copy follows
  // (already accounted).
  bool finish_copy() {
    if (!on_wire.drop) {
      const auto now_wall = core::SteadyClock::instance().wall();
      Frame f = on_wire.frame;
      f.set_timestamp(now_wall);
      if (on_wire.delay > core::Duration::zero()) {
        schedule_delayed(core::SteadyClock::instance().now() + on_wire.delay, f, on_wire.sender);
      } else {
        deliver_all(f, on_wire.sender, on_wire.rx_bits);
      }
    }
    if (--on_wire.copies == 0) return false;
    account();
    return true;
  }

  void deliver_all(const Frame& f, std::uint64_t sender, std::uint32_t bits) {
    for (auto* n : nodes)
      if (n->id() != sender) n->hand_in(f, bits);
  }

  // Paced mode: arbitrate, then hold the medium for the winner's bit time.
  void start_next() {
    if (!begin()) {
      active = false;
      return;
    }
    hold_wire();
  }

  // The schedule: a frame starts when the wire is free and not before it was queued, and ends its
  // bit time later; it is delivered when the timer for that end fires. Times come from the
  // schedule, not from when handlers happened to run: a process that wakes up late (a loaded
  // machine, a descheduled thread) delivers what the wire would have carried meanwhile, and no
  // more, since no frame starts before it was queued or before the previous one ended. So wake-up
  // latency neither piles up over a burst nor lets the medium carry more than a real bus would.
  //
  // The deadline queue calls on_deadline() at the end; when the process woke up late, the frames
  // whose ends have passed meanwhile are all handed over in that one wake-up (their deadlines lie
  // in the past, so the queue calls again at once), each still ending at its schedule's time.
  void hold_wire() {
    wire_free = on_wire.start + bits_to_time(on_wire.bits, wire.bitrate);
    deadlines->arm(*this, wire_free);
  }

  void on_deadline() override {
    note_lateness();
    if (finish_copy()) {
      on_wire.start = wire_free;  // the duplicate follows at once
      hold_wire();
      return;
    }
    start_next();
  }

  // How late (process latency) the frame that has just ended is handed over.
  void note_lateness() noexcept {
    const auto late = core::SteadyClock::instance().now() - wire_free;
    if (late <= core::Duration::zero()) return;
    stats.lateness += late;
    stats.max_lateness = std::max(stats.max_lateness, std::chrono::duration_cast<core::Duration>(late));
  }

  static bool later(const Delayed& a, const Delayed& b) noexcept {
    return a.due != b.due ? a.due > b.due : a.seq > b.seq;
  }

  void schedule_delayed(core::TimePoint due, const Frame& f, std::uint64_t sender) {
    delayed.push_back(Delayed{due, next_seq++, f, sender});
    std::push_heap(delayed.begin(), delayed.end(), later);
    if (due < delay_armed) arm_delay(due);
  }

  void arm_delay(core::TimePoint due) {
    delay_armed = due;
    delay_timer.expires_at(due);  // cancels an earlier wait, whose handler then does nothing
    delay_timer.async_wait([s = self()](const boost::system::error_code& ec) {
      if (ec == asio::error::operation_aborted) return;
      s->impl_->flush_delayed();
    });
  }

  void flush_delayed() {
    delay_armed = core::TimePoint::max();
    const auto now = core::SteadyClock::instance().now();
    while (!delayed.empty() && delayed.front().due <= now) {
      std::pop_heap(delayed.begin(), delayed.end(), later);
      Delayed d = delayed.back();
      delayed.pop_back();
      d.frame.set_timestamp(core::SteadyClock::instance().wall());
      deliver_all(d.frame, d.sender, frame_bits(d.frame).total);
    }
    if (!delayed.empty()) arm_delay(delayed.front().due);
  }

  void remove(VirtualNode* n) noexcept { nodes.erase(std::remove(nodes.begin(), nodes.end(), n), nodes.end()); }
};

namespace {

asio::any_io_executor VirtualNode::impl_executor(const VirtualBus::Impl& impl) { return impl.executor; }

Result<void> VirtualNode::submit(const Frame& frame) {
  if (!impl_ || !is_open()) return Error(CanErrc::closed, fmt::format("virtual node {}", name()));
  if (tx_.size() >= options().tx_capacity) {
    ++mutable_stats().tx_dropped;
    return Error(CanErrc::tx_overflow,
                 fmt::format("virtual node {}: {} frames already wait for the wire", name(), tx_.size()));
  }
  const core::TimePoint queued = impl_->pacing() ? core::SteadyClock::instance().now() : core::TimePoint{};
  tx_.push_back(Queued{frame, impl_->next_seq++, queued});
  impl_->kick();
  return ok();
}

void VirtualNode::detach() noexcept {
  if (!impl_) return;
  impl_->remove(this);
  impl_ = nullptr;
  tx_.clear();
}

}  // namespace

// ---- VirtualBus ----

VirtualBus::VirtualBus(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VirtualBus::~VirtualBus() = default;

std::shared_ptr<VirtualBus> VirtualBus::create(asio::any_io_executor ex, std::string name, WireModel wire) {
  if (wire.bitrate == 0) throw Exception(Error(CanErrc::bad_spec, fmt::format("virtual bus {}: bitrate 0", name)));
  std::shared_ptr<VirtualBus> bus(new VirtualBus(std::make_unique<Impl>(std::move(ex), std::move(name), wire)));
  bus->impl_->owner = bus.get();
  return bus;
}

std::unique_ptr<Bus> VirtualBus::attach(std::string node_name, BusOptions options) {
  auto& m = *impl_;
  const std::uint64_t id = m.next_node_id++;
  if (node_name.empty()) node_name = fmt::format("{}#{}", m.name, id);
  options.bitrate = m.wire.bitrate;  // every node of a bus runs at the bus's bitrate
  auto node = std::make_unique<VirtualNode>(shared_from_this(), m, id, std::move(node_name), options);
  m.nodes.push_back(node.get());
  return node;
}

void VirtualBus::set_fault_plan(FaultPlan plan) { impl_->injector = FaultInjector(std::move(plan)); }
const std::string& VirtualBus::name() const noexcept { return impl_->name; }
const WireModel& VirtualBus::wire() const noexcept { return impl_->wire; }
const VirtualBusStats& VirtualBus::stats() const noexcept { return impl_->stats; }
std::size_t VirtualBus::node_count() const noexcept { return impl_->nodes.size(); }

double VirtualBus::load(core::TimePoint now) const noexcept {
  const double elapsed = std::chrono::duration<double>(now - impl_->stats.created).count();
  if (elapsed <= 0) return 0.0;
  return std::chrono::duration<double>(impl_->stats.busy).count() / elapsed;
}

// ---- VirtualBusRegistry ----

Result<std::shared_ptr<VirtualBus>> VirtualBusRegistry::add(std::string name, WireModel wire) {
  if (name.empty()) return Error(CanErrc::bad_spec, "virtual bus name is empty");
  if (find(name)) return Error(CanErrc::bad_spec, fmt::format("virtual bus '{}' already exists", name));
  if (wire.bitrate == 0) return Error(CanErrc::bad_spec, fmt::format("virtual bus '{}': bitrate 0", name));
  auto bus = VirtualBus::create(executor_, name, wire);
  buses_.emplace_back(std::move(name), bus);
  return bus;
}

std::shared_ptr<VirtualBus> VirtualBusRegistry::find(std::string_view name) const {
  for (const auto& [n, bus] : buses_)
    if (n == name) return bus;
  return nullptr;
}

Result<std::unique_ptr<Bus>> VirtualBusRegistry::open(std::string_view channel, BusOptions options) {
  if (auto bus = find(channel)) return bus->attach({}, options);
  const auto known = channels();
  return Error(CanErrc::bad_spec, fmt::format("no virtual bus '{}' (known: {})", channel,
                                              known.empty() ? std::string("none") : fmt::format("{}", fmt::join(known, ", "))));
}

std::vector<std::string> VirtualBusRegistry::channels() const {
  std::vector<std::string> out;
  out.reserve(buses_.size());
  for (const auto& entry : buses_) out.push_back(entry.first);
  return out;
}

}  // namespace axon::can
