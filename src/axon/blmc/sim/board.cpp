#include "axon/blmc/sim/board.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace axon::blmc::sim {

namespace proto = protocol;
using proto::CommandCode;
using proto::MessageId;

namespace {

constexpr std::uint64_t kStatusEvery = static_cast<std::uint64_t>(proto::kStatusPeriod / proto::kDataPeriod);
constexpr double kCycleS = std::chrono::duration<double>(kCycle).count();

std::size_t kind_index(FaultKind k) noexcept { return static_cast<std::size_t>(k); }

double seconds(BoardTime t) noexcept { return std::chrono::duration<double>(t).count(); }

BoardConfig checked(BoardConfig c) {
  auto v = c.validate();
  if (!v) throw Exception(v.error());
  return c;
}

BoardFaultPlan checked(BoardFaultPlan p) {
  auto v = p.validate();
  if (!v) throw Exception(v.error());
  std::stable_sort(p.events.begin(), p.events.end(), [](const FaultEvent& a, const FaultEvent& b) { return a.at < b.at; });
  return p;
}

}  // namespace

Board::Board(BoardConfig config, BoardFaultPlan faults)
    : config_(checked(std::move(config))), plan_(checked(std::move(faults))), rng_(plan_.seed),
      motors_{MotorModel(config_.motors[0]), MotorModel(config_.motors[1])} {
  settings_.system_enabled = config_.system_enabled_at_power_up;
}

void Board::reset_firmware() {
  state_ = {};
  settings_ = {};
  settings_.system_enabled = config_.system_enabled_at_power_up;
  faults_ = {};
  over_current_ = false;
  undocumented_ = false;
  cause_until_ = {};
  last_iq_ref_ = next_cycle_time();
  pending_.clear();
  injected_.clear();
  for (std::size_t i = 0; i < motors_.size(); ++i) {
    motors_[i].set_state(config_.motors[i].initial_position_rev, 0.0);
  }
}

void Board::power_cycle() { reset_firmware(); }

// ---- receiving -------------------------------------------------------------------------------

bool Board::link_lost(LinkDirection dir, BoardTime t) {
  const auto hits = [dir](LinkDirection d) { return d == LinkDirection::both || d == dir; };
  for (const auto& s : plan_.stalls) {
    if (hits(s.direction) && t >= s.from && t < s.until) {
      ++(dir == LinkDirection::rx ? stats_.rx_stalled : stats_.tx_stalled);
      return true;
    }
  }
  for (const auto& d : plan_.drops) {
    if (!hits(d.direction) || t < d.from || t >= d.until || d.probability <= 0) continue;
    if (std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < d.probability) {
      ++(dir == LinkDirection::rx ? stats_.rx_dropped : stats_.tx_dropped);
      return true;
    }
  }
  return false;
}

Result<void> Board::receive(const can::Frame& frame, BoardTime now) {
  ++stats_.frames_received;
  if (link_lost(LinkDirection::rx, now)) return ok();
  auto msg = proto::decode_to_board(frame);
  if (!msg) {
    const auto& code = msg.error().code;
    if (code == proto::ProtocolErrc::unknown_id || code == proto::ProtocolErrc::not_standard_frame) {
      ++stats_.ignored;
    } else {
      ++stats_.malformed;
    }
    return msg.error();
  }
  if (pending_.size() >= config_.receive_queue) {
    ++stats_.rx_overflow;
    return ok();
  }
  pending_.push_back(Pending{now, std::move(msg).value()});
  return ok();
}

void Board::apply(const proto::ToBoard& msg, BoardTime at) {
  if (const auto* cmd = std::get_if<proto::Command>(&msg)) {
    ++stats_.commands;
    apply_command(*cmd, at);
    return;
  }
  const auto& pair = std::get<proto::PairMessage>(msg);
  const std::array<double, 2> v{pair.values.motor1, pair.values.motor2};
  if (pair.id == MessageId::iq_ref) {
    ++stats_.iq_refs;
    last_iq_ref_ = at;
  } else {
    ++stats_.controller_frames;
  }
  for (std::size_t i = 0; i < 2; ++i) {
    auto& m = state_[i];
    switch (pair.id) {
      case MessageId::iq_ref: m.iq_ref_a = v[i]; break;
      case MessageId::kp: m.kp = v[i]; break;
      case MessageId::kd: m.kd = v[i]; break;
      case MessageId::pos_ref: m.pos_ref_rev = v[i]; break;
      case MessageId::vel_ref: m.vel_ref_krpm = v[i]; break;
      default: break;
    }
  }
}

void Board::apply_command(const proto::Command& cmd, BoardTime at) {
  const bool on = cmd.raw_value() != 0;
  const auto enable_motor = [&](std::size_t i) {
    auto& m = state_[i];
    m.enabled = on;
    if (!on) m.aligning = false;  // an aborted alignment starts over at the next enable
  };
  switch (cmd.code()) {
    case CommandCode::enable_sys:
      if (!on) {
        settings_.system_enabled = false;
        break;
      }
      // Recovery: latched errors go unless their cause is still there.
      faults_.recv_timeout = false;
      faults_.pos_rollover = false;
      if (at >= cause_until_[kind_index(FaultKind::encoder)]) faults_.encoder = false;
      if (at >= cause_until_[kind_index(FaultKind::pos_converter)]) faults_.pos_converter = false;
      if (at >= cause_until_[kind_index(FaultKind::transmit)]) faults_.transmit = false;
      if (at >= cause_until_[kind_index(FaultKind::over_current)]) over_current_ = false;
      if (at >= cause_until_[kind_index(FaultKind::undocumented)]) undocumented_ = false;
      if (any_fault()) {
        ++stats_.recoveries_refused;
        break;
      }
      settings_.system_enabled = true;
      break;
    case CommandCode::enable_mtr1: enable_motor(0); break;
    case CommandCode::enable_mtr2: enable_motor(1); break;
    case CommandCode::enable_vspring1:
    case CommandCode::enable_vspring2: {
      const std::size_t i = cmd.code() == CommandCode::enable_vspring1 ? 0 : 1;
      state_[i].vspring = on;
      state_[i].vspring_anchor_rev = motors_[i].position_rev();
      break;
    }
    case CommandCode::send_current: settings_.send_current = on; break;
    case CommandCode::send_position: settings_.send_position = on; break;
    case CommandCode::send_velocity: settings_.send_velocity = on; break;
    case CommandCode::send_adc6: settings_.send_adc = on; break;
    case CommandCode::send_enc_index: settings_.send_enc_index = on; break;
    case CommandCode::send_all:
      settings_.send_current = settings_.send_position = settings_.send_velocity = settings_.send_adc =
          settings_.send_enc_index = on;
      break;
    case CommandCode::set_can_recv_timeout: settings_.recv_timeout_ms = cmd.raw_value(); break;
    case CommandCode::enable_pos_rollover_error: settings_.rollover_error = on; break;
    case CommandCode::p_controller_limit_iq_mtr1: state_[0].p_limit_a = std::abs(cmd.value()); break;
    case CommandCode::p_controller_limit_iq_mtr2: state_[1].p_limit_a = std::abs(cmd.value()); break;
    case CommandCode::d_controller_limit_iq_mtr1: state_[0].d_limit_a = std::abs(cmd.value()); break;
    case CommandCode::d_controller_limit_iq_mtr2: state_[1].d_limit_a = std::abs(cmd.value()); break;
  }
}

// ---- faults ----------------------------------------------------------------------------------

bool Board::any_fault() const noexcept {
  return faults_.encoder || faults_.transmit || faults_.recv_timeout || faults_.pos_converter || faults_.pos_rollover ||
         over_current_ || undocumented_;
}

void Board::disable_all() noexcept {
  settings_.system_enabled = false;
  for (auto& m : state_) {
    m.enabled = false;
    m.aligning = false;
  }
}

void Board::latch(bool& flag) {
  if (!flag) ++stats_.errors_raised;
  flag = true;
  disable_all();
}

void Board::raise(FaultKind kind, core::Duration duration, bool persistent, BoardTime at) {
  auto& until = cause_until_[kind_index(kind)];
  const BoardTime end = persistent ? BoardTime::max() : (duration > BoardTime::zero() ? at + duration : at);
  until = std::max(until, end);
  switch (kind) {
    case FaultKind::encoder: latch(faults_.encoder); break;
    case FaultKind::pos_converter: latch(faults_.pos_converter); break;
    case FaultKind::transmit: latch(faults_.transmit); break;
    case FaultKind::over_current: latch(over_current_); break;
    case FaultKind::undocumented: latch(undocumented_); break;
  }
}

void Board::inject(FaultKind kind, core::Duration duration, bool persistent) {
  injected_.push_back(FaultEvent{next_cycle_time(), kind, duration, persistent});
}

proto::Status Board::status() const noexcept {
  proto::Status s;
  s.system_enabled = settings_.system_enabled;
  s.motor1_enabled = state_[0].enabled;
  s.motor1_ready = state_[0].ready;
  s.motor2_enabled = state_[1].enabled;
  s.motor2_ready = state_[1].ready;
  s.error = proto::reported_error(faults_);
  if (s.error == proto::ErrorCode::none && over_current_) s.error = proto::ErrorCode::other;
  return s;
}

std::uint8_t Board::status_byte() const noexcept {
  const auto s = status();
  if (s.error != proto::ErrorCode::none || !undocumented_) return s.to_byte();
  return static_cast<std::uint8_t>(s.to_byte() | (proto::kUndocumentedErrorCode << 5));
}

// ---- the cycle -------------------------------------------------------------------------------

double Board::motor_command(std::size_t i, BoardTime t) {
  auto& m = state_[i];
  const auto& motor = motors_[i];
  if (!settings_.system_enabled || !m.enabled) return 0.0;
  if (!m.ready) {
    if (!m.aligning) {
      m.aligning = true;
      m.alignment_start = t;
    }
    if (t - m.alignment_start < config_.alignment_time) return 0.0;
    m.aligning = false;
    m.ready = true;
  }
  double iq = m.iq_ref_a;
  if (m.vspring) iq = -config_.vspring_gain_a_per_rev * (motor.position_rev() - m.vspring_anchor_rev);
  const double p = std::clamp(m.kp * (m.pos_ref_rev - motor.position_rev()), -m.p_limit_a, m.p_limit_a);
  const double d = std::clamp(m.kd * (m.vel_ref_krpm - motor.velocity_krpm()), -m.d_limit_a, m.d_limit_a);
  return iq + p + d;
}

void Board::emit(const Result<can::Frame>& frame, BoardTime t, std::vector<can::Frame>& out) {
  if (!frame) {
    ++stats_.encode_errors;
    return;
  }
  if (link_lost(LinkDirection::tx, t)) return;
  out.push_back(frame.value());
  ++stats_.frames_sent;
}

void Board::run_cycle(std::uint64_t k, bool send_data, std::vector<can::Frame>& out) {
  const BoardTime t = kCycle * static_cast<std::int64_t>(k);
  // 1. Frames received up to now.
  while (!pending_.empty() && pending_.front().at <= t) {
    const Pending p = std::move(pending_.front());
    pending_.pop_front();
    apply(p.msg, p.at);
  }
  // 2. Faults due.
  while (next_event_ < plan_.events.size() && plan_.events[next_event_].at <= t) {
    const auto& e = plan_.events[next_event_++];
    raise(e.kind, e.duration, e.persistent, t);
  }
  for (const auto& e : injected_) raise(e.kind, e.duration, e.persistent, t);
  injected_.clear();
  // 3. Receive timeout.
  if (settings_.recv_timeout_ms > 0 && settings_.system_enabled) {
    const bool armed = std::any_of(state_.begin(), state_.end(), [](const MotorState& m) { return m.enabled && m.iq_ref_a != 0.0; });
    if (armed && t - last_iq_ref_ > std::chrono::milliseconds(settings_.recv_timeout_ms)) latch(faults_.recv_timeout);
  }
  // 4. What each driver is asked for; an over-current trip stops everything at once.
  std::array<double, 2> cmd{};
  for (std::size_t i = 0; i < 2; ++i) cmd[i] = motor_command(i, t);
  if (config_.over_current_trip_a > 0 &&
      (std::abs(cmd[0]) > config_.over_current_trip_a || std::abs(cmd[1]) > config_.over_current_trip_a)) {
    raise(FaultKind::over_current, core::Duration::zero(), false, t);
    cmd = {};
  }
  for (std::size_t i = 0; i < 2; ++i) state_[i].command_a = cmd[i];
  // 5. What goes out this cycle: status, then the data in the documented order, then index marks.
  if (k % kStatusEvery == 0) {
    const std::array<std::uint8_t, 1> byte{status_byte()};
    emit(can::Frame::standard(static_cast<std::uint32_t>(MessageId::status), byte), t, out);
  }
  const bool data_on = settings_.system_enabled || config_.data_while_disabled;
  if (data_on && send_data) {
    const auto pair = [&](MessageId id, double a, double b) { emit(proto::encode(proto::PairMessage{id, {a, b}}), t, out); };
    if (settings_.send_current) pair(MessageId::current, motors_[0].current_a(), motors_[1].current_a());
    if (settings_.send_position) pair(MessageId::position, motors_[0].position_rev(), motors_[1].position_rev());
    if (settings_.send_velocity) pair(MessageId::velocity, motors_[0].velocity_krpm(), motors_[1].velocity_krpm());
    if (settings_.send_adc) pair(MessageId::adc6, config_.adc[0].value(seconds(t)), config_.adc[1].value(seconds(t)));
  } else if (data_on) {
    stats_.data_skipped += (settings_.send_current ? 1 : 0) + (settings_.send_position ? 1 : 0) +
                           (settings_.send_velocity ? 1 : 0) + (settings_.send_adc ? 1 : 0);
  }
  for (std::uint8_t i = 0; i < 2; ++i) {
    auto& motor = motors_[i];
    if (data_on && settings_.send_enc_index) {
      for (double pos : motor.index_events()) {
        const auto before = stats_.frames_sent;
        emit(proto::encode(proto::EncoderIndex{pos, i}), t, out);
        stats_.index_frames += stats_.frames_sent - before;
      }
    }
    motor.clear_index_events();
  }
  // 6. The motors over the next millisecond.
  for (std::size_t i = 0; i < 2; ++i) {
    auto& motor = motors_[i];
    const auto wraps = motor.rollovers();
    if (state_[i].aligning) {
      motor.hold(kCycleS);
    } else {
      motor.advance(cmd[i], kCycleS);
    }
    if (settings_.rollover_error && motor.rollovers() != wraps) latch(faults_.pos_rollover);
  }
}

void Board::advance(BoardTime now, std::vector<can::Frame>& out, std::size_t max_data_cycles) {
  if (now < next_cycle_time()) return;
  const auto last = static_cast<std::uint64_t>(now / kCycle);
  while (next_cycle_ <= last) {
    const std::uint64_t k = next_cycle_++;
    const bool send_data = last - k < max_data_cycles;
    run_cycle(k, send_data, out);
  }
}

}  // namespace axon::blmc::sim
