#include "axon/c4g/host/server.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/core/counter.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <time.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <thread>

namespace axon::c4g::host {

using protocol::code;
using protocol::Mode;

std::string_view to_string(ServerState s) noexcept {
  switch (s) {
    case ServerState::waiting: return "waiting for the first packet";
    case ServerState::syncing: return "answering, no initialization packet yet";
    case ServerState::running: return "running";
    case ServerState::silent: return "no packets (controller stopped or restarting)";
    case ServerState::stopped: return "stopped";
  }
  return "unknown";
}

std::string_view to_string(FreezeState s) noexcept {
  switch (s) {
    case FreezeState::off: return "off";
    case FreezeState::pending: return "pending (waiting for mode 0)";
    case FreezeState::entering: return "entering (500 sent)";
    case FreezeState::frozen: return "frozen";
    case FreezeState::leaving: return "leaving (exit-from-open sent)";
  }
  return "unknown";
}

namespace {
std::int64_t steady_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
using core::bump;

bool every_axis_in(const protocol::Packet& p, std::int32_t mode) noexcept {
  for (std::size_t i = 0; i < p.count; ++i)
    if (p.axes[i].mode != mode) return false;
  return p.count > 0;
}

// A datagram that may start a session: a cyclic packet or an initialization packet that decodes.
bool well_formed(std::span<const std::byte> in, const net::Datagram& info) noexcept {
  if (info.truncated()) return false;
  switch (protocol::classify(in.size())) {
    case protocol::DatagramKind::cyclic: {
      protocol::Packet p;
      return protocol::decode_packet(in, p).ok();
    }
    case protocol::DatagramKind::init:
      try {  // decoding the initialization packet may allocate (error texts); once per session
        return static_cast<bool>(protocol::decode_init(in));
      } catch (...) {
        return false;
      }
    case protocol::DatagramKind::unknown: break;
  }
  return false;
}

std::string describe_allowed(const net::SocketAddress& a) {
  if (a.ip == 0) return "learned from its first packet";
  if (a.port != 0) return a.to_string();
  return fmt::format("{}.{}.{}.{} (any port)", a.ip >> 24, (a.ip >> 16) & 0xff, (a.ip >> 8) & 0xff, a.ip & 0xff);
}

std::int32_t read_i32(std::span<const std::byte> in, std::size_t offset) noexcept {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | std::to_integer<std::uint32_t>(in[offset + static_cast<std::size_t>(i)]);
  return static_cast<std::int32_t>(v);
}
}  // namespace

Server::Server(Controller& controller, const ServerOptions& options, net::SocketAddress allowed)
    : controller_(controller), options_(options), safety_(options.safety), peer_(allowed), switch_(options.soft_switch), watch_(options.watch) {}

Result<std::unique_ptr<Server>> Server::start(Controller& controller, const ServerOptions& options) {
  AXON_TRY(protocol::validate(options.soft_switch));
  if (options.period.count() < 0)
    return Error(CoreErrc::invalid_argument, "c4g server: the controller's period must be > 0 (or 0: from its initialization packet)");
  net::SocketAddress allowed;  // anyone
  if (!options.controller.host.empty()) {
    AXON_TRY(resolved, net::resolve_ipv4(options.controller));
    if (resolved.ip == 0)
      return Error(CoreErrc::invalid_argument, fmt::format("c4g server: the controller address '{}' names no host",
                                                           options.controller.to_string()));
    allowed = resolved;
  }
  std::unique_ptr<Server> s(new Server(controller, options, allowed));
  AXON_TRY(socket, net::UdpSocket::open(options.listen, options.udp));
  if (!options.pcap_path.empty()) {
    AXON_TRY(rec, PcapRecorder::open(options.pcap_path, options.pcap));
    s->recorder_ = std::move(rec);
  }
  CycleOptions cycle = options.cycle;
  if (options.period.count() > 0) cycle.timing.nominal_period_ns = options.period.count();
  cycle.max_reply = std::max(cycle.max_reply, protocol::kMaxPacketSize);
  cycle.max_datagram = std::max(cycle.max_datagram, protocol::kInitPacketSize + 1);
  CycleHandler& handler = *s;
  s->cycle_ = std::make_unique<CycleThread>(std::move(socket), handler, cycle, s->recorder_.get());
  s->cycle_->start();
  spdlog::info("c4g server listening on {} (replies numbered {}; controller {})", s->local_address().to_string(),
               options.numbering == protocol::ReplyNumbering::same ? "as received" : "NUM + 1",
               describe_allowed(allowed));
  return s;
}

Server::~Server() { stop(); }

void Server::stop() {
  if (cycle_) cycle_->stop();
  if (recorder_) recorder_->close();
  state_.store(ServerState::stopped, std::memory_order_release);
}

std::string Server::foreign_source_text() const {
  const auto last = SessionPeer::unpack(counters_.last_foreign.load(std::memory_order_relaxed));
  return last ? fmt::format(" (last from {})", last->to_string()) : std::string();
}

double Server::period_s() const noexcept {
  const std::int64_t ns = period_ns();
  return ns > 0 ? static_cast<double>(ns) * 1e-9 : 0.002;  // unknown: the controllers' usual 2 ms
}

std::optional<protocol::InitPacket> Server::init() const {
  std::lock_guard lock(init_mutex_);
  return init_copy_;
}

void Server::on_timeout(bool before_first) noexcept {
  if (before_first) return;
  state_.store(ServerState::silent, std::memory_order_release);
  peer_.forget();  // the session is over: the controller may come back from another port
  watch_.on_silence();
  controller_.on_silence();
}

bool Server::accepts(std::span<const std::byte> in, const net::Datagram& info) noexcept {
  if (peer_.matches(info.from)) return true;
  if (peer_.known() || !peer_.admits(info.from)) {
    bump(counters_.foreign);
    counters_.last_foreign.store(SessionPeer::pack(info.from), std::memory_order_relaxed);
    return false;
  }
  // No session yet: only a well-formed packet starts one; anything else is dropped (it would be
  // answered with drive off inside a session) and latches nothing.
  if (!well_formed(in, info)) {
    bump(counters_.protocol_errors);
    bump(counters_.unanswered);
    return false;
  }
  peer_.learn(info.from);
  bump(counters_.sessions);
  return true;
}

std::size_t Server::on_packet(std::span<const std::byte> in, const net::Datagram& info, std::span<std::byte> out) noexcept {
  bump(counters_.packets);
  if (state_.load(std::memory_order_relaxed) == ServerState::waiting ||
      state_.load(std::memory_order_relaxed) == ServerState::silent)
    state_.store(have_init_ ? ServerState::running : ServerState::syncing, std::memory_order_release);
  if (info.truncated()) {
    bump(counters_.protocol_errors);
    bump(counters_.unanswered);
    return 0;
  }
  switch (protocol::classify(in.size())) {
    case protocol::DatagramKind::init: return answer_init(in, out);
    case protocol::DatagramKind::cyclic: return answer_cyclic(in, info, out);
    case protocol::DatagramKind::unknown: break;
  }
  bump(counters_.protocol_errors);
  bump(counters_.unanswered);
  return 0;
}

std::size_t Server::answer_init(std::span<const std::byte> in, std::span<std::byte> out) noexcept {
  bump(counters_.init_packets);
  last_num_ = read_i32(in, 0) & protocol::kMaxProtocolNumber;  // a restart's numbering may start here
  // Decoding the initialization packet may allocate (error texts); it happens once per start-up,
  // before the cyclic exchange, so the cycle's no-allocation rule is kept where it matters.
  try {
    auto decoded = protocol::decode_init(in);
    if (!decoded) {
      bump(counters_.protocol_errors);
      // Answer with the number anyway, so the controller is not kept waiting: one axis, mode 0.
      protocol::Packet p;
      p.num = protocol::reply_number(read_i32(in, 0) & protocol::kMaxProtocolNumber, options_.numbering);
      p.count = 1;
      return protocol::encode_packet(p, out).ok() ? protocol::packet_size(1) : 0;
    }
    init_ = std::move(decoded).value();
    have_init_ = true;
    cycle_->set_nominal_period(static_cast<std::int64_t>(init_.period_ms) * 1'000'000);
    auto map = protocol::AxisMap::from_init(init_);
    have_axes_ = static_cast<bool>(map);
    if (have_axes_) {
      axes_ = map.value();
      safety_.configure(init_, axes_);
      watch_.configure(init_, axes_);
    } else {
      bump(counters_.protocol_errors);
    }
    {
      std::lock_guard lock(init_mutex_);
      init_copy_ = init_;
    }
    have_target_ = {};
    exit_sent_ = {};
    switch_.reset();
    cyclic_count_ = 0;
    init_requested_at_ = 0;
    state_.store(ServerState::running, std::memory_order_release);
    if (have_axes_) {
      try {
        controller_.on_init(init_, axes_);
      } catch (...) {
        bump(counters_.controller_exceptions);
        safety_.trip(FaultReason::controller_exception);
      }
    }
  } catch (...) {
    bump(counters_.protocol_errors);
    return 0;
  }
  protocol::Packet p;
  p.num = protocol::reply_number(init_.protocol_number, options_.numbering);
  p.count = static_cast<std::size_t>(init_.open_axes);
  for (std::size_t i = 0; i < p.count; ++i) {
    const std::int32_t m = have_axes_ ? axes_.startup_mode(i) : 0;
    p.axes[i].mode = protocol::is_known_mode(m) ? m : code(Mode::mode0);
  }
  return protocol::encode_packet(p, out).ok() ? protocol::packet_size(p.count) : 0;
}

std::size_t Server::answer_bad_cyclic(std::span<const std::byte> in, std::span<std::byte> out) noexcept {
  bump(counters_.protocol_errors);
  safety_.trip(FaultReason::bad_packet);
  // Answer with drive off on every axis the datagram's size announces, under its number.
  protocol::Packet p;
  p.num = protocol::reply_number(read_i32(in, 0) & protocol::kMaxProtocolNumber, options_.numbering);
  p.count = (in.size() - protocol::kHeaderSize) / protocol::kAxisSize;
  if (p.count == 0 || p.count > protocol::kMaxAxes) {
    bump(counters_.unanswered);
    return 0;
  }
  Safety::make_drive_off(p, p);
  return protocol::encode_packet(p, out).ok() ? protocol::packet_size(p.count) : 0;
}

void Server::build_safe_reply(const protocol::Packet& req, protocol::Packet& rep) noexcept {
  rep.num = protocol::reply_number(req.num, options_.numbering);
  rep.infpar = 0;
  rep.cmd = 0;
  rep.count = req.count;
  for (std::size_t i = 0; i < req.count; ++i) {
    const auto& q = req.axes[i];
    auto& r = rep.axes[i];
    r = protocol::Axis{};
    r.mode = q.mode;
    switch (q.mode) {
      case code(Mode::mode0_prime):  // the echo test: targets come back unchanged
        r.d1 = q.d1;
        r.d2 = q.d2;
        break;
      case code(Mode::mode1):
      case code(Mode::mode1_standby):
      case code(Mode::mode4):
      case code(Mode::mode4_standby):  // absolute target: hold it (else the controller's), never command zero
        r.d1 = have_target_[i] ? last_target_[i] : q.d1;
        break;
      default: break;  // increments and contributions: zero is "no change"
    }
  }
}

bool Server::arm_trajectory_moving(const protocol::Packet& req, std::size_t arm) const noexcept {
  for (std::size_t k = 0; k < req.count; ++k) {
    const std::size_t a = have_axes_ ? axes_.logical(k).arm : 1;
    if (a == arm && req.axes[k].d2 != 0.0f) return true;
  }
  return false;
}

void Server::enforce_mode_rules(const protocol::Packet& req, protocol::Packet& rep) noexcept {
  rep.num = protocol::reply_number(req.num, options_.numbering);  // not the controller's to change
  rep.count = req.count;
  for (std::size_t i = 0; i < req.count; ++i) {
    const std::size_t arm = have_axes_ ? axes_.logical(i).arm : 1;
    if (req.axes[i].mode == code(Mode::mode0)) exit_sent_[i] = false;
    const auto change = protocol::check_mode_change(req.axes[i].mode, rep.axes[i].mode, exit_sent_[i]);
    bool refused = change != protocol::ModeChange::allowed && change != protocol::ModeChange::unchanged;
    if (change == protocol::ModeChange::allowed && req.axes[i].mode == code(Mode::mode0) &&
        !protocol::is_special_mode(rep.axes[i].mode)) {
      // What the rules cannot see (docs/c4g-server.md, "Who sets the mode"): an open mode needs the
      // drives on (chapter 11, second phase) and the state machine's still state S00 (chapter 24:
      // no GO OPEN from S10, the controller's trajectory moving; its target velocity D2 tells).
      const auto state = arm_trajectory_moving(req, arm) ? protocol::MotionState::closed : protocol::MotionState::stop;
      refused = !protocol::drives_on(req.infpar, arm) || !protocol::next_state(state, protocol::MotionEvent::go_open_a);
    }
    if (refused) {
      bump(counters_.refused_mode_changes);
      rep.axes[i].mode = req.axes[i].mode;
    }
    if (protocol::exit_from_open(rep.infpar, arm)) exit_sent_[i] = true;
  }
}

// Lost, duplicated and reordered packets move the number by a few; a restart takes it back to the
// controller's first number, and the wrap goes from kMaxProtocolNumber to 1.
bool Server::numbering_restarted(std::int32_t num) const noexcept {
  constexpr std::int32_t kWindow = 64;
  if (last_num_ < 0 || num >= last_num_ - kWindow) return false;
  return !(last_num_ > protocol::kMaxProtocolNumber - kWindow && num <= kWindow);
}

// The old session is over as after a silence (the application hears on_silence) and the new one
// must bring its own initialization packet: the old one is no longer used, and when the new one
// was lost on the way, RESTART (506) asks for it after request_init_after packets (the sync phase).
void Server::start_session_over() noexcept {
  bump(counters_.controller_restarts);
  have_init_ = false;
  watch_.reset();
  init_requested_at_ = cyclic_count_;
  state_.store(ServerState::syncing, std::memory_order_release);
  controller_.on_silence();
}

void Server::request_missing_init(const protocol::Packet& req, protocol::Packet& rep) noexcept {
  const auto every = static_cast<std::uint64_t>(std::max(options_.request_init_after, 0));
  if (have_init_ || every == 0 || cyclic_count_ < every) return;
  if (init_requested_at_ != 0 && cyclic_count_ - init_requested_at_ < every) return;
  for (const auto& a : req.open_axes())
    if (a.mode != code(Mode::mode0)) return;  // the controller takes 506 from mode 0 only
  for (auto& a : rep.open_axes()) {
    a = protocol::Axis{};
    a.mode = code(Mode::server_restart);
  }
  init_requested_at_ = cyclic_count_;
  bump(counters_.init_requests);
}

std::size_t Server::encode(const protocol::Packet& req, protocol::Packet& rep, std::span<std::byte> out) noexcept {
  // Remember absolute targets so a later safe reply holds them.
  for (std::size_t i = 0; i < rep.count; ++i) {
    const std::int32_t m = req.axes[i].mode;
    if (m == code(Mode::mode4) || m == code(Mode::mode4_standby) || m == code(Mode::mode1) || m == code(Mode::mode1_standby)) {
      last_target_[i] = rep.axes[i].d1;
      have_target_[i] = true;
    } else {
      have_target_[i] = false;
    }
  }
  if (protocol::encode_packet(rep, out).ok()) return protocol::packet_size(rep.count);
  safety_.trip(FaultReason::not_finite);
  Safety::make_drive_off(req, rep);
  return protocol::encode_packet(rep, out).ok() ? protocol::packet_size(rep.count) : 0;
}

bool Server::wait_frozen(std::chrono::nanoseconds timeout) const {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!frozen()) {
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

bool Server::update_freeze(const protocol::Packet& req) noexcept {
  const bool want = freeze_wanted_.load(std::memory_order_acquire);
  FreezeState st = freeze_state_.load(std::memory_order_relaxed);
  const bool all0 = every_axis_in(req, code(Mode::mode0));
  const bool all500 = every_axis_in(req, code(Mode::freezing_active));
  switch (st) {
    case FreezeState::off:
      if (want) st = all0 && have_init_ ? FreezeState::entering : FreezeState::pending;
      break;
    case FreezeState::pending:
      if (!want) st = FreezeState::off;
      else if (all0 && have_init_) st = FreezeState::entering;
      break;
    case FreezeState::entering:
      if (all500) {
        bump(counters_.freezes);
        st = want ? FreezeState::frozen : FreezeState::leaving;
      } else if (!want) {
        st = FreezeState::off;  // the controller never took it: nothing to undo
      } else if (!all0) {
        st = FreezeState::pending;  // the controller moved on (drive on, a program mode): wait for mode 0
      }
      break;
    case FreezeState::frozen:
      if (!all500) st = want ? FreezeState::pending : FreezeState::off;  // left by the controller (drive off, restart)
      else if (!want) st = FreezeState::leaving;
      break;
    case FreezeState::leaving:
      if (!every_axis_in(req, code(Mode::freezing_active))) st = want ? FreezeState::pending : FreezeState::off;
      break;
  }
  freeze_state_.store(st, std::memory_order_release);
  return st == FreezeState::entering || st == FreezeState::frozen || st == FreezeState::leaving;
}

void Server::build_freeze_reply(const protocol::Packet& req, protocol::Packet& rep) noexcept {
  const FreezeState st = freeze_state_.load(std::memory_order_relaxed);
  rep.num = protocol::reply_number(req.num, options_.numbering);
  rep.infpar = 0;
  rep.cmd = 0;
  rep.count = req.count;
  for (std::size_t i = 0; i < req.count; ++i) {
    rep.axes[i] = protocol::Axis{};
    // Mode 0 content is meaningless to the controller (the manual's precondition), so zero data.
    rep.axes[i].mode = code(Mode::freezing_active);
  }
  if (st == FreezeState::leaving) {
    if (have_axes_) {
      for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm)
        if (axes_.arm_count(arm) > 0) rep.infpar = protocol::request_exit_from_open(rep.infpar, arm);
    } else {
      rep.infpar = protocol::request_exit_from_open(rep.infpar, 1);
    }
  }
}

std::size_t Server::answer_cyclic(std::span<const std::byte> in, const net::Datagram& info, std::span<std::byte> out) noexcept {
  bump(counters_.cyclic_packets);
  const auto fault = have_init_ && have_axes_
                         ? protocol::decode_packet(in, request_, static_cast<std::size_t>(init_.open_axes))
                         : protocol::decode_packet(in, request_);
  if (!fault.ok()) return answer_bad_cyclic(in, out);
  if (numbering_restarted(request_.num)) start_session_over();
  last_num_ = request_.num;

  const bool freezing = update_freeze(request_);
  build_safe_reply(request_, safe_);
  reply_ = safe_;
  switch_.update(request_, period_s());
  bool used_controller = false;
  safety_.begin_cycle();
  if (!safety_.faulted()) {
    const CycleContext ctx{request_,      have_init_ ? &init_ : nullptr, have_axes_ ? &axes_ : nullptr, cyclic_count_,
                           info.wall_ns, &switch_, freezing};
    ReplyBuilder builder(reply_);
    const std::int64_t t0 = steady_ns();
    try {
      controller_.on_cycle(ctx, builder);
      used_controller = true;
    } catch (...) {
      bump(counters_.controller_exceptions);
      safety_.trip(FaultReason::controller_exception);
      reply_ = safe_;
    }
    const std::int64_t took = steady_ns() - t0;
    if (freezing) {
      late_in_row_ = 0;  // the controller no longer checks replies: lateness is allowed
    } else if (took > options_.controller_budget.count()) {
      bump(counters_.controller_late);
      if (options_.max_late_cycles > 0 && ++late_in_row_ >= options_.max_late_cycles)
        safety_.trip(FaultReason::controller_late);
    } else {
      late_in_row_ = 0;
    }
    if (used_controller && !freezing) enforce_mode_rules(request_, reply_);
  }
  if (!freezing) request_missing_init(request_, reply_);
  if (freezing) {
    bump(counters_.frozen_cycles);
    build_freeze_reply(request_, reply_);
    used_controller = false;
  } else if (!used_controller) {
    bump(counters_.safe_replies);
  }
  ++cyclic_count_;
  if (const auto f = protocol::check_reply_fields(reply_); !f.ok()) {
    bump(counters_.unused_fields);
    if (options_.verify_reply_fields) safety_.trip(FaultReason::unused_field, f.axis);
  }
  safety_.apply(request_, reply_);
  watch_.observe(request_, reply_);
  return encode(request_, reply_, out);
}

std::string Server::summary() const {
  std::string out = fmt::format("State: {}\n", to_string(state()));
  auto it = std::back_inserter(out);
  const auto peer = peer_.current();
  fmt::format_to(it, "Controller: {} ({}), sessions {}; foreign datagrams ignored {}{}\n",
                 peer ? peer->to_string() : std::string("none yet"), describe_allowed(peer_.allowed()),
                 counters_.sessions.load(), counters_.foreign.load(), foreign_source_text());
  fmt::format_to(it,
                 "Packets {} (init {}, cyclic {}), protocol errors {}, unanswered {}, controller exceptions {}, "
                 "late {}, refused mode changes {}, safe replies {}, frozen cycles {} (freezes {}, now {}), "
                 "replies with unused fields set {}, initialization packets asked for (506) {}, controller restarts "
                 "seen in the numbering {}\n",
                 counters_.packets.load(), counters_.init_packets.load(), counters_.cyclic_packets.load(),
                 counters_.protocol_errors.load(), counters_.unanswered.load(), counters_.controller_exceptions.load(),
                 counters_.controller_late.load(), counters_.refused_mode_changes.load(), counters_.safe_replies.load(),
                 counters_.frozen_cycles.load(), counters_.freezes.load(), to_string(freeze_state()),
                 counters_.unused_fields.load(), counters_.init_requests.load(), counters_.controller_restarts.load());
  fmt::format_to(it, "Safety: {} (axis {}), currents clamped {}, drive-off replies {}, following-error replies {}\n",
                 to_string(safety_.reason()), safety_.fault_axis(), safety_.counters().currents_clamped.load(),
                 safety_.counters().drive_off_replies.load(), safety_.counters().following_error_replies.load());
  out += watch_.summary();
  out += cycle_->summary();
  if (recorder_)
    fmt::format_to(it, "Capture {}: {} written, {} dropped, {} rotations, {} write failures\n", recorder_->path(),
                   recorder_->written(), recorder_->dropped(), recorder_->rotations(), recorder_->write_failures());
  return out;
}

}  // namespace axon::c4g::host
