#include "axon/fps/host/command_client.hpp"

#include "axon/fps/host/uid_pool.hpp"
#include "axon/core/wakeup.hpp"
#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/identifier.hpp"
#include "axon/fps/protocol/message.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <deque>
#include <unordered_map>

namespace axon::fps::host {

using protocol::CommandId;

namespace {

constexpr std::uint32_t pending_key(std::uint16_t pos, std::uint8_t cmd, std::uint8_t uid) noexcept {
  return (std::uint32_t{pos} << 16) | (std::uint32_t{cmd} << 8) | uid;
}
constexpr std::uint32_t pool_key(std::uint16_t pos, std::uint8_t cmd) noexcept {
  return (std::uint32_t{pos} << 8) | cmd;
}

long long as_ms(core::Duration d) { return std::chrono::duration_cast<std::chrono::milliseconds>(d).count(); }

}  // namespace

Error Reply::error() const {
  return Error(protocol::make_error_code(code),
               fmt::format("positioner {} {} uid {}", positioner, protocol::command_name(command), uid));
}

const Reply* BroadcastResult::from(std::uint16_t positioner) const noexcept {
  for (const auto& r : replies) {
    if (r.positioner == positioner) return &r;
  }
  return nullptr;
}

std::vector<std::uint16_t> BroadcastResult::positioners() const {
  std::vector<std::uint16_t> out;
  out.reserve(replies.size());
  for (const auto& r : replies) out.push_back(r.positioner);
  return out;
}

std::uint64_t ClientCounters::errors() const noexcept {
  std::uint64_t n = 0;
  for (std::size_t i = 1; i < by_code.size(); ++i) n += by_code[i];
  return n;
}

// ---------------------------------------------------------------------------------------------

// The order in which the requests of one pipeline may go out: request i may start taking its uid
// and its in-flight slot only once request i - 1 has been handed to the bus (or given up before
// that). Without it, every request of a run competes for those on its own, and one woken with a
// freed slot resumes a little later than it was woken: meanwhile a later request of the same run
// could take a slot freed after it and reach the robot first. A robot refuses a trajectory point
// that is not later than the one it received before.
struct SendTurns {
  explicit SendTurns(asio::any_io_executor e) : ex(std::move(e)) {}
  asio::any_io_executor ex;
  std::size_t next = 0;                        // the request whose turn it is
  std::map<std::size_t, core::Wakeup*> waiting;  // requests parked until their turn

  asio::awaitable<void> wait(std::size_t i) {
    while (next < i) {
      core::Wakeup w(ex);
      waiting[i] = &w;
      core::OnExit unlist{[this, i] { waiting.erase(i); }};
      co_await w.wait();
    }
  }
  // Request i is on the bus (or will never be): the next one may go.
  void pass(std::size_t i) {
    if (i + 1 <= next) return;
    next = i + 1;
    if (auto it = waiting.find(next); it != waiting.end()) it->second->notify();
  }
};

// A request's place in a SendTurns (none for a lone request).
struct Turn {
  SendTurns* turns = nullptr;
  std::size_t index = 0;
  bool passed = false;
  void pass() {
    if (turns && !passed) turns->pass(index);
    passed = true;
  }
  ~Turn() { pass(); }
};

class CommandClient::Impl : public std::enable_shared_from_this<Impl> {
 public:
  Impl(can::Bus& b, ClientOptions o, std::shared_ptr<const MotionLock> l)
      : bus(b), options(std::move(o)), lock(std::move(l)), ex(b.get_executor()) {}

  can::Bus& bus;
  ClientOptions options;
  std::shared_ptr<const MotionLock> lock;  // may be null: nothing is refused
  asio::any_io_executor ex;
  ClientCounters counters;
  bool stopping = false;
  bool closed = false;
  bool reader_done = false;

  struct Pending {
    explicit Pending(const asio::any_io_executor& e) : wake(e) {}
    core::Wakeup wake;
    std::optional<Reply> reply;
  };
  struct UidWaiter {
    explicit UidWaiter(const asio::any_io_executor& e) : wake(e) {}
    core::Wakeup wake;
    std::optional<std::uint8_t> granted;
  };
  struct PoolEntry {
    UidPool pool;
    std::deque<UidWaiter*> waiters;
    std::size_t grants = 0;  // uids handed to waiters that have not resumed yet (keeps FIFO order)
  };
  struct SlotWaiter {
    explicit SlotWaiter(const asio::any_io_executor& e) : wake(e) {}
    core::Wakeup wake;
    bool granted = false;
  };
  struct Collector {
    Collector(const asio::any_io_executor& e, std::optional<std::size_t> exp, std::optional<std::set<std::uint16_t>> ids)
        : wake(e), expected(exp), waiting(std::move(ids)) {}
    core::Wakeup wake;
    std::optional<std::size_t> expected;
    std::optional<std::set<std::uint16_t>> waiting;  // expected_ids not heard from yet
    BroadcastResult result;
  };

  std::unordered_map<std::uint32_t, Pending*> pending;
  std::unordered_map<std::uint32_t, PoolEntry> pools;
  std::size_t in_flight = 0;
  std::deque<SlotWaiter*> slot_waiters;
  std::size_t slot_grants = 0;  // slots handed to waiters that have not resumed yet (keeps FIFO order)
  std::unordered_map<std::uint8_t, Collector*> collectors;
  std::unordered_map<std::uint8_t, std::deque<core::Wakeup*>> collector_waiters;
  std::map<std::uint64_t, Handler> subscribers;
  std::uint64_t next_subscriber = 1;
  std::vector<core::Wakeup*> stop_waiters;

  // --- reader ------------------------------------------------------------------------------

  static asio::awaitable<void> read_loop(std::shared_ptr<Impl> self) {
    while (!self->stopping) {
      auto f = co_await self->bus.receive(self->options.idle_poll);
      if (!f) {
        if (f.error() == can::CanErrc::timeout) continue;
        spdlog::warn("fps client on {}: bus ended ({}); failing every waiting request", self->bus.name(),
                     f.error().message());
        self->closed = true;
        self->wake_everyone();
        break;
      }
      self->dispatch(f.value());
    }
    self->reader_done = true;
    for (auto* w : self->stop_waiters) w->notify();
  }

  void dispatch(const can::Frame& frame) {
    auto m = protocol::from_frame(frame);
    if (!m) {
      ++counters.foreign;
      spdlog::debug("fps client on {}: ignoring {} ({})", bus.name(), frame.to_string(), m.error().message());
      return;
    }
    const auto& id = m.value().id;
    if (id.positioner == protocol::kBroadcastId) {
      // A request addressed to everyone: another host on the bus, not a positioner.
      ++counters.foreign;
      return;
    }
    Reply r{id.positioner, id.command, id.uid, id.response, m.value().payload, frame.timestamp()};
    if (id.uid == 0) {
      const bool collision = id.command == protocol::number(CommandId::collision_detected);
      if (!collision) {
        if (auto it = collectors.find(id.command); it != collectors.end()) {
          collect(*it->second, r);
          return;
        }
      }
      ++counters.unsolicited;
      if (collision) ++counters.collisions;
      const Unsolicited u{r.positioner, r.command, r.code, r.payload, r.timestamp};
      auto subs = subscribers;  // handlers may subscribe or unsubscribe
      for (auto& [sid, h] : subs) {
        if (subscribers.contains(sid)) h(u);
      }
      return;
    }
    if (auto it = pending.find(pending_key(id.positioner, id.command, id.uid)); it != pending.end()) {
      Pending* p = it->second;
      pending.erase(it);
      ++counters.replies;
      ++counters.by_code[static_cast<std::size_t>(r.code) & 0xF];
      p->reply = r;
      p->wake.notify();
      return;
    }
    if (auto it = pools.find(pool_key(id.positioner, id.command));
        it != pools.end() && it->second.pool.take_late_reply(id.uid, core::steady_now())) {
      ++counters.late;
      spdlog::debug("fps client on {}: late reply {}", bus.name(), protocol::to_string(m.value()));
      grant_uids(it->second);
      return;
    }
    ++counters.unmatched;
    spdlog::debug("fps client on {}: unmatched reply {}", bus.name(), protocol::to_string(m.value()));
  }

  void collect(Collector& c, const Reply& r) {
    if (c.result.from(r.positioner)) {
      ++c.result.duplicates;
      ++counters.broadcast_duplicates;
      return;
    }
    ++counters.replies;
    ++counters.by_code[static_cast<std::size_t>(r.code) & 0xF];
    c.result.replies.push_back(r);
    if (c.waiting) c.waiting->erase(r.positioner);
    if ((c.expected && c.result.replies.size() >= *c.expected) || (c.waiting && c.waiting->empty())) {
      c.result.complete = true;
      c.wake.notify();
    }
  }

  void wake_everyone() {
    for (auto& [k, p] : pending) p->wake.notify();
    for (auto& [k, e] : pools) {
      for (auto* w : e.waiters) w->wake.notify();
    }
    for (auto* w : slot_waiters) w->wake.notify();
    for (auto& [k, c] : collectors) c->wake.notify();
    for (auto& [k, q] : collector_waiters) {
      for (auto* w : q) w->notify();
    }
  }

  [[nodiscard]] Result<void> check_running() const {
    if (stopping) return Error(HostErrc::cancelled, fmt::format("bus {}", bus.name()));
    if (closed) return Error(HostErrc::closed, fmt::format("bus {}", bus.name()));
    return ok();
  }

  // --- uids ----------------------------------------------------------------------------------

  // Hands free uids to waiters, first come first served.
  void grant_uids(PoolEntry& e) {
    while (!e.waiters.empty()) {
      auto u = e.pool.acquire(core::steady_now());
      if (!u) return;
      UidWaiter* w = e.waiters.front();
      e.waiters.pop_front();
      w->granted = *u;
      ++e.grants;
      w->wake.notify();
    }
  }

  void release_uid(std::uint16_t pos, std::uint8_t cmd, std::uint8_t uid) {
    auto& e = pools[pool_key(pos, cmd)];
    e.pool.release(uid);
    grant_uids(e);
  }

  asio::awaitable<Result<std::uint8_t>> acquire_uid(std::uint16_t pos, std::uint8_t cmd) {
    PoolEntry& e = pools[pool_key(pos, cmd)];  // references into unordered_map stay valid
    if (e.waiters.empty() && e.grants == 0) {
      if (auto u = e.pool.acquire(core::steady_now())) co_return *u;
    }
    ++counters.uid_waits;
    UidWaiter w(ex);
    e.waiters.push_back(&w);
    struct Unlist {
      std::deque<UidWaiter*>& q;
      UidWaiter* w;
      ~Unlist() { q.erase(std::remove(q.begin(), q.end(), w), q.end()); }
    } unlist{e.waiters, &w};
    for (;;) {
      if (w.granted) {
        --e.grants;
        co_return *w.granted;
      }
      if (auto r = check_running(); !r) co_return r.error();
      // A quarantine may have run out meanwhile.
      if (e.waiters.front() == &w) {
        if (auto u = e.pool.acquire(core::steady_now())) co_return *u;
      }
      w.wake.reset();
      co_await w.wake.wait_until(e.pool.next_release(core::steady_now()));
    }
  }

  // --- in-flight bound -----------------------------------------------------------------------

  [[nodiscard]] bool slot_free() const noexcept {
    return options.max_in_flight == 0 || in_flight < options.max_in_flight;
  }

  asio::awaitable<Result<void>> acquire_slot() {
    // A slot handed to a waiter belongs to it even before it resumes: nobody may take a free slot
    // past it meanwhile.
    if (slot_waiters.empty() && slot_grants == 0 && slot_free()) {
      ++in_flight;
      co_return ok();
    }
    ++counters.slot_waits;
    SlotWaiter w(ex);
    slot_waiters.push_back(&w);
    struct Unlist {
      std::deque<SlotWaiter*>& q;
      SlotWaiter* w;
      ~Unlist() { q.erase(std::remove(q.begin(), q.end(), w), q.end()); }
    } unlist{slot_waiters, &w};
    for (;;) {
      if (w.granted) {
        --slot_grants;
        co_return ok();
      }
      if (auto r = check_running(); !r) co_return r.error();
      w.wake.reset();
      co_await w.wake.wait_until(core::TimePoint::max());
    }
  }

  void release_slot() {
    if (!slot_waiters.empty()) {
      SlotWaiter* w = slot_waiters.front();  // the slot passes on: in_flight stays
      slot_waiters.pop_front();
      w->granted = true;
      ++slot_grants;
      w->wake.notify();
      return;
    }
    if (in_flight > 0) --in_flight;
  }

  // --- requests ------------------------------------------------------------------------------

  asio::awaitable<Result<Reply>> request(std::uint16_t pos, CommandId cmd, protocol::Payload payload,
                                         RequestOptions ro, Turn* turn = nullptr) {
    Turn lone;
    if (turn == nullptr) turn = &lone;
    if (turn->turns) co_await turn->turns->wait(turn->index);
    const auto& info = protocol::command_info(cmd);
    if (pos == protocol::kBroadcastId) {
      co_return Error(HostErrc::invalid_argument,
                      fmt::format("{} to positioner 0: that is the broadcast address, use broadcast()", info.name));
    }
    if (pos > protocol::kMaxPositionerId) {
      co_return Error(protocol::ProtocolErrc::positioner_out_of_range, fmt::format("positioner {}", pos));
    }
    if (auto r = protocol::check_request(info, false, payload.size()); !r) {
      co_return Error(r.error().code, fmt::format("positioner {} {}: {}", pos, info.name, r.error().detail));
    }
    if (auto a = admit(cmd, pos); !a) co_return a.error();  // at once, rather than after a wait for a uid
    const unsigned attempts = 1 + (info.read_only ? ro.retries.value_or(options.read_retries) : 0);
    const auto timeout = ro.timeout.value_or(options.timeout_for(cmd));
    for (unsigned attempt = 0;; ++attempt) {
      if (attempt > 0) ++counters.retries;
      auto r = co_await attempt_once(pos, cmd, payload, timeout, *turn);
      if (r || r.error() != HostErrc::timeout) co_return r;
      if (attempt + 1 >= attempts) {
        co_return Error(HostErrc::timeout, fmt::format("positioner {} {} on bus {}: no reply within {} ms ({} {})",
                                                       pos, info.name, bus.name(), as_ms(timeout), attempts,
                                                       attempts == 1 ? "attempt" : "attempts"));
      }
    }
  }

  asio::awaitable<Result<Reply>> attempt_once(std::uint16_t pos, CommandId cmd, const protocol::Payload& payload,
                                              core::Duration timeout, Turn& turn) {
    const std::uint8_t n = protocol::number(cmd);
    if (auto r = check_running(); !r) co_return r.error();
    auto uid_r = co_await acquire_uid(pos, n);
    if (!uid_r) co_return uid_r.error();
    const std::uint8_t uid = uid_r.value();
    // Gives the uid back on every way out, unless it was quarantined.
    struct UidGuard {
      Impl& self;
      std::uint16_t pos;
      std::uint8_t cmd, uid;
      bool held = true;
      ~UidGuard() {
        if (held) self.release_uid(pos, cmd, uid);
      }
    } uid_guard{*this, pos, n, uid};

    if (auto s = co_await acquire_slot(); !s) co_return s.error();
    struct SlotGuard {
      Impl& self;
      ~SlotGuard() { self.release_slot(); }
    } slot_guard{*this};

    Pending p(ex);
    const auto key = pending_key(pos, n, uid);
    pending[key] = &p;
    struct PendingGuard {
      Impl& self;
      std::uint32_t key;
      Pending* p;
      ~PendingGuard() {
        if (auto it = self.pending.find(key); it != self.pending.end() && it->second == p) self.pending.erase(it);
      }
    } pending_guard{*this, key, &p};

    auto sent = co_await send(pos, cmd, uid, payload);
    turn.pass();  // the frame is with the bus (or never will be): the next request of the run may go
    if (!sent) co_return sent.error();
    const auto deadline = core::steady_now() + timeout;
    while (!p.reply && !stopping && !closed) {
      if (!co_await p.wake.wait_until(deadline)) break;
      p.wake.reset();
    }
    if (p.reply) {
      if (!p.reply->accepted()) co_return p.reply->error();
      co_return *p.reply;
    }
    if (auto r = check_running(); !r) co_return r.error();
    ++counters.timeouts;
    uid_guard.held = false;
    pools[pool_key(pos, n)].pool.quarantine(uid, core::steady_now() + options.late_window);
    co_return Error(HostErrc::timeout, fmt::format("positioner {} {} uid {}", pos, protocol::command_name(cmd), uid));
  }

  // --- broadcasts ----------------------------------------------------------------------------

  asio::awaitable<Result<BroadcastResult>> broadcast(CommandId cmd, protocol::Payload payload, BroadcastOptions bo) {
    const auto& info = protocol::command_info(cmd);
    if (auto r = protocol::check_request(info, true, payload.size()); !r) {
      co_return Error(r.error().code, fmt::format("broadcast {}: {}", info.name, r.error().detail));
    }
    if (auto a = admit(cmd, protocol::kBroadcastId); !a) co_return a.error();  // at once, rather than after a wait
    const std::uint8_t n = info.number();
    while (collectors.contains(n)) {
      if (auto r = check_running(); !r) co_return r.error();
      core::Wakeup w(ex);
      auto& q = collector_waiters[n];
      q.push_back(&w);
      struct Unlist {
        std::deque<core::Wakeup*>& q;
        core::Wakeup* w;
        ~Unlist() { q.erase(std::remove(q.begin(), q.end(), w), q.end()); }
      } unlist{q, &w};
      co_await w.wait_until(core::TimePoint::max());
    }
    if (auto r = check_running(); !r) co_return r.error();

    Collector c(ex, bo.expected, bo.expected_ids);
    collectors[n] = &c;
    struct CollectorGuard {
      Impl& self;
      std::uint8_t n;
      ~CollectorGuard() {
        self.collectors.erase(n);
        if (auto it = self.collector_waiters.find(n); it != self.collector_waiters.end() && !it->second.empty()) {
          it->second.front()->notify();
        }
      }
    } collector_guard{*this, n};

    if (bo.trigger) {
      // What the trigger starts (the sync line starts trajectories) passes the same check as a frame.
      if (auto a = admit(cmd, protocol::kBroadcastId); !a) co_return a.error();
      auto t = co_await bo.trigger();
      if (!t) co_return t.error();
      ++counters.broadcasts;
    } else {
      auto sent = co_await send(protocol::kBroadcastId, cmd, 0, payload);
      if (!sent) co_return sent.error();
    }
    if ((bo.expected && c.result.replies.size() >= *bo.expected) || (c.waiting && c.waiting->empty()))
      c.result.complete = true;
    const auto deadline = core::steady_now() + bo.window.value_or(options.broadcast_window);
    while (!c.result.complete && !stopping && !closed) {
      if (!co_await c.wake.wait_until(deadline)) break;
      c.wake.reset();
    }
    if (auto r = check_running(); !r) co_return r.error();
    co_return std::move(c.result);
  }

  asio::awaitable<Result<void>> broadcast_now(CommandId cmd) {
    if (closed) co_return Error(HostErrc::closed, fmt::format("bus {}", bus.name()));
    co_return co_await send(protocol::kBroadcastId, cmd, 0, {});
  }

  // --- the way out ---------------------------------------------------------------------------

  // The safety chokepoint (motion_lock.hpp): a command that moves a robot is refused while the
  // lock is held. Every frame goes out through send(), which asks here first; so does a
  // broadcast's trigger.
  Result<void> admit(CommandId cmd, std::uint16_t pos) {
    if (!lock) return ok();
    auto a = lock->admit(cmd, pos);
    if (!a) ++counters.refused;
    return a;
  }

  // Every request frame this client puts on the bus, unicast (uid 1..63) or broadcast (positioner
  // 0, uid 0).
  asio::awaitable<Result<void>> send(std::uint16_t pos, CommandId cmd, std::uint8_t uid,
                                     const protocol::Payload& payload) {
    if (auto a = admit(cmd, pos); !a) co_return a.error();
    auto frame = protocol::make_request(pos, cmd, uid, payload);
    if (!frame) co_return frame.error();
    ++counters.sent;
    if (pos == protocol::kBroadcastId) ++counters.broadcasts;
    auto sent = co_await bus.send(frame.value());
    if (!sent) {
      ++counters.send_errors;
      const auto to = pos == protocol::kBroadcastId ? std::string("broadcast") : fmt::format("positioner {}", pos);
      co_return Error(sent.error().code, fmt::format("{} {} on bus {}: {}", to, protocol::command_name(cmd),
                                                     bus.name(), sent.error().detail));
    }
    co_return ok();
  }

  asio::awaitable<void> stop() {
    stopping = true;
    wake_everyone();
    if (reader_done) co_return;
    core::Wakeup w(ex);
    stop_waiters.push_back(&w);
    struct Unlist {
      std::vector<core::Wakeup*>& q;
      core::Wakeup* w;
      ~Unlist() { q.erase(std::remove(q.begin(), q.end(), w), q.end()); }
    } unlist{stop_waiters, &w};
    co_await w.wait_until(core::TimePoint::max());
  }
};

// ---------------------------------------------------------------------------------------------

CommandClient::CommandClient(can::Bus& bus, ClientOptions options, std::shared_ptr<const MotionLock> lock)
    : impl_(std::make_shared<Impl>(bus, std::move(options), std::move(lock))) {
  asio::co_spawn(impl_->ex, Impl::read_loop(impl_), [name = bus.name()](std::exception_ptr e) {
    if (!e) return;
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& ex) {
      spdlog::error("fps client on {}: reader ended by an exception: {}", name, ex.what());
    }
  });
}

CommandClient::~CommandClient() {
  impl_->stopping = true;
  impl_->wake_everyone();
}

can::Bus& CommandClient::bus() const noexcept { return impl_->bus; }
const ClientOptions& CommandClient::options() const noexcept { return impl_->options; }
const ClientCounters& CommandClient::counters() const noexcept { return impl_->counters; }
const MotionLock* CommandClient::motion_lock() const noexcept { return impl_->lock.get(); }
std::size_t CommandClient::in_flight() const noexcept { return impl_->pending.size(); }
bool CommandClient::running() const noexcept { return !impl_->reader_done && !impl_->stopping; }

asio::awaitable<Result<Reply>> CommandClient::request(std::uint16_t positioner, CommandId command,
                                                      protocol::Payload payload, RequestOptions options) {
  auto self = impl_;
  co_return co_await self->request(positioner, command, payload, options);
}

namespace {

struct PipeState {
  explicit PipeState(const asio::any_io_executor& ex, std::size_t n) : wake(ex), turns(ex), done(n, 0) {}
  core::Wakeup wake;
  SendTurns turns;  // the requests go out in their order
  std::size_t outstanding = 0;
  std::vector<std::uint8_t> done;  // 0 waiting, 1 accepted, 2 failed
  std::map<std::size_t, Error> failures;
};

asio::awaitable<void> pipe_one(std::shared_ptr<CommandClient::Impl> self, PipeState* st, std::uint16_t pos,
                               protocol::Request req, std::size_t i, RequestOptions options) {
  Turn turn{&st->turns, i};
  const protocol::Payload payload = req.payload;
  auto r = co_await self->request(pos, req.command, payload, options, &turn);
  turn.pass();
  if (r) {
    st->done[i] = 1;
  } else {
    st->done[i] = 2;
    st->failures.emplace(i, r.error());
  }
  --st->outstanding;
  st->wake.notify();
}

}  // namespace

asio::awaitable<PipelineResult> CommandClient::pipeline(std::uint16_t positioner,
                                                        std::span<const protocol::Request> requests,
                                                        std::size_t window, std::function<void(std::size_t)> progress,
                                                        RequestOptions options) {
  auto self = impl_;
  window = std::max<std::size_t>(window, 1);
  PipeState st(self->ex, requests.size());
  PipelineResult out;
  std::size_t next = 0;
  for (;;) {
    while (st.failures.empty() && next < requests.size() && st.outstanding < window) {
      ++st.outstanding;
      asio::co_spawn(self->ex, pipe_one(self, &st, positioner, requests[next], next, options), asio::detached);
      ++next;
      ++out.issued;
    }
    const std::size_t before = out.accepted;
    while (out.accepted < requests.size() && st.done[out.accepted] == 1) ++out.accepted;
    if (progress && out.accepted != before) progress(out.accepted);
    if (st.outstanding == 0 && (next == requests.size() || !st.failures.empty())) break;
    st.wake.reset();
    co_await st.wake.wait_until(core::TimePoint::max());
  }
  if (!st.failures.empty()) {
    out.failed_index = st.failures.begin()->first;
    out.error = st.failures.begin()->second;
  }
  co_return out;
}

asio::awaitable<Result<BroadcastResult>> CommandClient::broadcast(CommandId command, protocol::Payload payload,
                                                                  BroadcastOptions options) {
  auto self = impl_;
  co_return co_await self->broadcast(command, payload, std::move(options));
}

asio::awaitable<Result<void>> CommandClient::broadcast_now(CommandId command) {
  auto self = impl_;
  co_return co_await self->broadcast_now(command);
}

std::uint64_t CommandClient::subscribe(Handler handler) {
  const auto id = impl_->next_subscriber++;
  impl_->subscribers.emplace(id, std::move(handler));
  return id;
}

void CommandClient::unsubscribe(std::uint64_t id) noexcept { impl_->subscribers.erase(id); }

asio::awaitable<void> CommandClient::stop() {
  auto self = impl_;
  co_await self->stop();
}

Error CommandClient::bad_reply(const Reply& reply, const Error& why) {
  ++impl_->counters.bad_replies;
  spdlog::warn("fps client on {}: positioner {} {} sent data that does not fit: {}", impl_->bus.name(),
               reply.positioner, protocol::command_name(reply.command), why.message());
  return Error(HostErrc::bad_reply, fmt::format("positioner {} {}: {}", reply.positioner,
                                                protocol::command_name(reply.command), why.message()));
}

}  // namespace axon::fps::host
