#include "axon/c4g/sim/controller.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/safety.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <cmath>
#include <numbers>

namespace axon::c4g::sim {
namespace {

namespace P = protocol;

bool is_special(std::int32_t m) { return m >= 500 && m <= 508; }
bool is_sensor(std::int32_t m) { return m > 100 && m < 200; }
// Modes whose axis belongs to the PC until its exit-from-open (the ones with an exit sequence).
bool is_open_mode(std::int32_t m) {
  return m == 1 || m == 2 || m == 4 || m == 5 || m == 7 || m == 8 || m == 9 || is_sensor(m);
}
// The mode whose rules apply (standby codes behave like their mode).
std::int32_t base_mode(std::int32_t m) {
  if (auto b = P::base_of_standby(m)) return *b;
  return m;
}
std::string mode_text(std::int32_t m) { return fmt::format("{} ({})", m, P::mode_name(m)); }

// Minimum-jerk profile: position, velocity and acceleration fractions at tau in [0, 1].
void min_jerk(double tau, double& s, double& ds, double& dds) {
  const double t2 = tau * tau, t3 = t2 * tau;
  s = t3 * (10 - 15 * tau + 6 * t2);
  ds = 30 * t2 * (1 - 2 * tau + t2);
  dds = 60 * tau * (1 - 3 * tau + 2 * t2);
}

}  // namespace

std::string_view to_string(EventLevel l) noexcept {
  switch (l) {
    case EventLevel::info: return "info";
    case EventLevel::warning: return "warning";
    case EventLevel::error: return "error";
  }
  return "?";
}

std::string_view to_string(Phase p) noexcept {
  switch (p) {
    case Phase::sync: return "sync";
    case Phase::init: return "init";
    case Phase::cycle: return "cycle";
    case Phase::passive_freeze: return "passive_freeze";
    case Phase::ended: return "ended";
    case Phase::failed: return "failed";
  }
  return "?";
}

Result<Controller> Controller::create(RobotConfig robot, Scenario scenario, ControllerOptions options) {
  if (options.period_ms != 0) {
    if (options.period_ms < 1 || options.period_ms > 2)
      return Error(CoreErrc::invalid_argument, fmt::format("period {} ms: the controller runs at 1 or 2 ms", options.period_ms));
    robot.init.period_ms = options.period_ms;
  }
  if (options.max_misses < 1) return Error(CoreErrc::invalid_argument, "max_misses must be at least 1");
  if (auto v = P::validate(robot.init); !v)
    return Error(v.error().code, fmt::format("{}: C4GOpen: configuration error: {}", event::kConfigurationError, v.error().detail));
  auto map = P::AxisMap::from_init(robot.init);
  if (!map)
    return Error(map.error().code, fmt::format("{}: C4GOpen: configuration error: {}", event::kConfigurationError, map.error().detail));
  Controller c;
  c.robot_ = std::move(robot);
  c.scenario_ = std::move(scenario);
  c.options_ = options;
  c.map_ = std::move(map).value();
  c.period_ = c.robot_.init.period_ms * 1e-3;
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    if (c.map_.arm_count(arm) == 0) continue;
    auto t = P::ArmTransform::from_init(c.robot_.init, arm);
    if (!t) return Error(t.error().code, fmt::format("arm {}: {}", arm, t.error().detail));
    c.arms_[arm].present = true;
    c.arms_[arm].transform = std::move(t).value();
  }
  for (std::size_t i = 0; i < c.map_.count(); ++i) {
    AxisSim& ax = c.axes_[i];
    const auto ref = c.map_.logical(i);
    ax.arm = ref.arm;
    ax.axis = ref.axis;
    const double ratio = c.robot_.init.transmission_ratio[ref.arm - 1][ref.axis - 1];
    AxisParams params = c.robot_.axes[ref.arm - 1][ref.axis - 1];
    params.current_limit = c.robot_.init.current_limit[ref.arm - 1][ref.axis - 1];
    params.following_error = c.robot_.init.following_error[ref.arm - 1][ref.axis - 1];
    ax.model = AxisModel(params, ratio);
    // Link position 0 is motor position q0 (the calibration constant).
    const double q0 = c.robot_.init.calibration[ref.arm - 1][ref.axis - 1];
    ax.model.reset(q0);
    ax.traj_pos = ax.ref_pos = ax.prev_ref_pos = ax.hold_pos = q0;
    const std::int32_t start = c.map_.startup_mode(i);
    ax.mode = start == P::kModeUnspecified ? 0 : start;
    ax.last_request = ax.mode;
  }
  // A start-up mode on an axis the open-axis lists leave out: the controller ignores it and says so.
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm)
    for (std::size_t axis = 1; axis <= P::kAxesPerArm; ++axis)
      if (c.robot_.init.modes[arm - 1][axis - 1] != 0 && !c.map_.open_index(arm, axis))
        c.emit(EventLevel::error, event::kAxisNotPresent, fmt::format("C4GOpen: Arm {} Axis {} not present", arm, axis));
  return c;
}

bool Controller::finished() const noexcept {
  return phase_ == Phase::failed || phase_ == Phase::ended || scenario_failed() || scenario_done_;
}

bool Controller::drives_on(std::size_t arm) const noexcept {
  return arm >= 1 && arm <= P::kMaxArms && arms_[arm].powered && arms_[arm].drive_on_left == 0;
}

std::vector<Event> Controller::take_events() {
  std::vector<Event> out;
  out.swap(events_);
  return out;
}

void Controller::emit(EventLevel level, std::string_view name, std::string text) {
  events_.push_back(Event{time_s(), stats_.ticks, level, std::string(name), std::move(text)});
}

std::vector<double> Controller::joint_degrees(std::size_t arm) const {
  std::array<double, P::kAxesPerArm> q{};
  const auto n = link_degrees(arm, false, q);
  return {q.begin(), q.begin() + static_cast<std::ptrdiff_t>(n)};
}

std::size_t Controller::link_degrees(std::size_t arm, bool target, std::span<double> out) const noexcept {
  if (arm < 1 || arm > P::kMaxArms || !arms_[arm].transform) return 0;
  const auto& t = *arms_[arm].transform;
  // Fixed capacity (transform.hpp): no allocation.
  P::ArmTransform::Vector motor(static_cast<Eigen::Index>(t.axes()));
  for (std::size_t k = 0; k < t.axes(); ++k) {
    const auto open = map_.open_index(arm, k + 1);
    motor[static_cast<Eigen::Index>(k)] = !open ? t.calibration()[static_cast<Eigen::Index>(k)]
                                          : target ? axes_[*open].ref_pos
                                                   : axes_[*open].model.position();
  }
  const auto q = t.link_position(motor);
  const auto n = std::min(out.size(), static_cast<std::size_t>(q.size()));
  for (std::size_t k = 0; k < n; ++k) out[k] = q[static_cast<Eigen::Index>(k)] * 180.0 / std::numbers::pi;
  return n;
}

// ---- sending ---------------------------------------------------------------------------------

std::span<const std::byte> Controller::begin_cycle() {
  awaiting_ = false;
  reply_ok_ = false;
  sent_cyclic_ = false;
  tx_size_ = 0;
  if (phase_ != Phase::sync && phase_ != Phase::init && phase_ != Phase::cycle) return {};
  num_ = stats_.packets_sent == 0 ? options_.first_number : P::next_protocol_number(num_);
  if (phase_ == Phase::init) {
    P::InitPacket init = robot_.init;
    init.protocol_number = num_;
    if (auto r = P::encode_init(init, tx_); !r) {
      emit(EventLevel::error, event::kConfigurationError, "C4GOpen: configuration error: " + r.error().detail);
      return {};
    }
    tx_size_ = P::kInitPacketSize;
    ++stats_.init_sent;
    emit(EventLevel::info, event::kInitSent,
         fmt::format("initialization packet: {} open axes, {} ms, protocol number {}", map_.count(), robot_.init.period_ms, num_));
  } else {
    encode_cyclic(phase_ == Phase::cycle ? pending_special_ : 0);
    if (tx_size_ == 0) return {};
    if (phase_ == Phase::sync) ++stats_.sync_sent;
    else {
      ++stats_.cyclic_sent;
      sent_cyclic_ = true;
    }
  }
  expected_ = P::reply_number(num_, options_.numbering);
  awaiting_ = true;
  ++stats_.packets_sent;
  return {tx_.data(), tx_size_};
}

void Controller::encode_cyclic(std::int32_t force_mode) {
  P::Packet& p = scratch_;
  p.num = num_;
  p.infpar = 0;
  p.cmd = 0;
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    if (!arms_[arm].present) continue;
    if (drives_on(arm)) p.infpar = P::with_arm_byte(p.infpar, arm, P::kDrivesOn);
    p.cmd = P::with_arm_byte(p.cmd, arm, arms_[arm].cmd);
  }
  p.count = map_.count();
  // A program's special code (502, 504, 506) is issued from mode 0: the packets first show mode 0 at
  // least once, so the PC sees the open mode end before the special (a state no packet shows does
  // not exist for the PC). 503 follows the silence of 502 directly.
  bool shown_mode0 = true;
  for (std::size_t i = 0; i < p.count; ++i) shown_mode0 = shown_mode0 && axes_[i].sent_mode == 0;
  const std::int32_t special = shown_mode0 || force_mode == P::code(P::Mode::freezing_passive_out) ? force_mode : 0;
  special_in_packet_ = special;
  for (std::size_t i = 0; i < p.count; ++i) {
    const AxisSim& ax = axes_[i];
    P::Axis& a = p.axes[i];
    a.mode = phase_ == Phase::sync ? 0 : (special != 0 ? special : ax.mode);
    axes_[i].sent_mode = a.mode;
    a.d1 = static_cast<float>(ax.ref_pos);
    a.d2 = static_cast<float>(ax.ref_vel * period_);
    a.d3 = static_cast<float>(ax.model.position());
    a.d4 = static_cast<float>(ax.model.velocity() * period_);
    a.d5 = static_cast<float>(ax.model.current());
    a.ext1 = static_cast<float>(ax.model.dynamic_current());
    a.ext2 = static_cast<float>(ax.model.inertia());
    a.ext3 = 0;
  }
  const P::Fault f = P::encode_packet(p, tx_);
  if (!f.ok()) {
    emit(EventLevel::error, event::kTransmitError, "C4GOpen: error in socket UDP transmission: " + P::to_error(f).detail);
    tx_size_ = 0;
    return;
  }
  tx_size_ = P::packet_size(p.count);
}

void Controller::on_send_failed(std::string_view why) {
  emit(EventLevel::error, event::kTransmitError, fmt::format("C4GOpen: error in socket UDP transmission ({})", why));
  awaiting_ = false;
}

// ---- receiving -------------------------------------------------------------------------------

void Controller::on_datagram(std::span<const std::byte> d) { judge_datagram(d); }

void Controller::judge_datagram(std::span<const std::byte> d) {
  if (P::classify(d.size()) != P::DatagramKind::cyclic) {
    ++stats_.wrong_size;
    return;
  }
  P::Packet rx;
  const P::Fault f = P::decode_packet(d, rx, map_.count());
  if (!f.ok()) {
    if (f.code == P::ProtocolErrc::axis_count_mismatch || f.code == P::ProtocolErrc::wrong_size ||
        f.code == P::ProtocolErrc::too_many_axes)
      ++stats_.wrong_size;
    else
      ++stats_.malformed;
    return;
  }
  if (awaiting_ && rx.num == expected_) {
    if (reply_ok_) {
      ++stats_.duplicate_replies;
      return;
    }
    reply_ok_ = true;
    reply_ = rx;
    return;
  }
  if (std::find(recent_.begin(), recent_.end(), rx.num) != recent_.end()) ++stats_.late_replies;
  else ++stats_.wrong_number;
}

// ---- the tick ---------------------------------------------------------------------------------

void Controller::end_cycle() {
  std::array<std::int32_t, P::kMaxAxes> before{};
  for (std::size_t i = 0; i < map_.count(); ++i) before[i] = axes_[i].mode;
  const std::int32_t sent_special = sent_cyclic_ ? special_in_packet_ : 0;
  if (awaiting_) {
    recent_[recent_next_] = expected_;
    recent_next_ = (recent_next_ + 1) % recent_.size();
  }

  switch (phase_) {
    case Phase::sync:
      if (reply_ok_) {
        ++stats_.replies_ok;
        ++sync_answered_;
        sync_last_answer_tick_ = stats_.ticks;
        if (sync_answered_ >= options_.sync_packets) {
          phase_ = Phase::init;
          emit(EventLevel::info, event::kSynchronised, fmt::format("synchronised after {} sync packets", stats_.sync_sent));
        }
      } else if (ticks_to_s(stats_.ticks - sync_last_answer_tick_) > options_.sync_timeout_s) {
        communication_failure(fmt::format("no answer to the sync packets for {} s", options_.sync_timeout_s));
      }
      break;
    case Phase::init:
      if (reply_ok_) ++stats_.init_answers;
      phase_ = Phase::cycle;
      break;
    case Phase::cycle:
      if (sent_cyclic_) cyclic_tick();
      break;
    case Phase::passive_freeze:
      ++stats_.frozen_cycles;
      if (passive_left_ > 0) --passive_left_;
      if (passive_left_ == 0) {
        phase_ = Phase::cycle;
        pending_special_ = P::code(P::Mode::freezing_passive_out);
        emit(EventLevel::info, event::kFreezing, "passive freezing ends: 503 in the next packet");
      }
      break;
    case Phase::ended:
    case Phase::failed:
      break;
  }

  check_offset_limit();
  step_physics();
  check_following_error();
  check_soft_switch();

  // The program's special codes take effect once their packet went out.
  if (phase_ == Phase::cycle && sent_special != 0 && sent_special == pending_special_) {
    pending_special_ = 0;
    switch (sent_special) {
      case 502:
        phase_ = Phase::passive_freeze;
        emit(EventLevel::info, event::kFreezing, fmt::format("passive freezing (502): no packets for {} ticks", passive_left_));
        break;
      case 503: emit(EventLevel::info, event::kFreezing, "passive freezing over (503): back to mode 0"); break;
      case 504:
        phase_ = Phase::ended;
        emit(EventLevel::info, event::kCommunicationEnd, "exit open (504): the real-time exchange ends here");
        break;
      case 506:
        phase_ = Phase::init;
        for (std::size_t i = 0; i < map_.count(); ++i) {
          const std::int32_t start = map_.startup_mode(i);
          set_mode(i, start == P::kModeUnspecified ? 0 : start, {});
        }
        emit(EventLevel::info, event::kInitSent, "restart (506): the initialization packet follows");
        break;
      default: break;
    }
  }

  if (phase_ != Phase::failed) advance_modes();
  if (scenario_started_) run_scenario();

  awaiting_ = false;

  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    if (!arms_[arm].present) continue;
    const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
    bool changed = false, uniform = true;
    for (std::size_t i = first; i < first + n; ++i) {
      changed |= axes_[i].mode != before[i];
      uniform &= axes_[i].mode == axes_[first].mode && before[i] == before[first];
    }
    if (!changed) continue;
    if (uniform) {
      emit(EventLevel::info, event::kModeChange,
           fmt::format("arm {}: mode {} -> {}", arm, mode_text(before[first]), mode_text(axes_[first].mode)));
    } else {
      std::string text = fmt::format("arm {}:", arm);
      for (std::size_t i = first; i < first + n; ++i)
        if (axes_[i].mode != before[i]) text += fmt::format(" axis {} {} -> {};", axes_[i].axis, before[i], axes_[i].mode);
      text.pop_back();
      emit(EventLevel::info, event::kModeChange, std::move(text));
    }
  }
  ++stats_.ticks;
}

void Controller::cyclic_tick() {
  scenario_started_ = true;
  if (frozen_active_) {
    ++stats_.frozen_cycles;
    if (reply_ok_) {
      ++stats_.replies_ok;
      consecutive_misses_ = 0;
      apply_reply();
    }
    return;
  }
  if (!reply_ok_) {
    ++stats_.misses;
    ++consecutive_misses_;
    stats_.max_consecutive_misses = std::max<std::uint64_t>(stats_.max_consecutive_misses, consecutive_misses_);
    if (consecutive_misses_ == 1)
      emit(EventLevel::warning, event::kReceiveDebug,
           fmt::format("C4GOpen: Rx Debug: no valid answer to packet {}", num_));
    if (consecutive_misses_ >= options_.max_misses)
      communication_failure(fmt::format("{} consecutive packets without a valid answer", consecutive_misses_));
    return;
  }
  ++stats_.replies_ok;
  if (consecutive_misses_ > 0)
    emit(EventLevel::info, event::kReceiveDebug, fmt::format("answers again after {} missed", consecutive_misses_));
  consecutive_misses_ = 0;
  apply_reply();
}

void Controller::communication_failure(std::string_view why) {
  comm_error_ = true;
  phase_ = Phase::failed;
  emit(EventLevel::error, event::kCommunicationError, fmt::format("C4GOpen: communication error ({})", why));
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm)
    if (arms_[arm].present && arms_[arm].powered) drive_off(arm, 0);
}

void Controller::apply_reply() {
  bool any_exit = false;
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    if (!arms_[arm].present || !P::exit_from_open(reply_.infpar, arm)) continue;
    any_exit = true;
    if (arms_[arm].open && !exit_requested_[arm]) {
      exit_requested_[arm] = true;
      arms_[arm].exit_while_moving = arms_[arm].move.active;
    }
  }
  if (frozen_active_ && any_exit) {
    frozen_active_ = false;
    for (std::size_t i = 0; i < map_.count(); ++i)
      if (axes_[i].mode == P::code(P::Mode::freezing_active)) set_mode(i, 0, {});
    emit(EventLevel::info, event::kFreezing, "active freezing ended by the PC's exit-from-open: replies are checked again");
  }
  for (std::size_t i = 0; i < map_.count(); ++i) {
    AxisSim& ax = axes_[i];
    ax.pc = reply_.axes[i];
    if (is_sensor(ax.mode)) ax.measure = ax.pc.d3;
    handle_request(i, reply_.axes[i].mode);
  }
}

void Controller::handle_request(std::size_t i, std::int32_t req) {
  AxisSim& ax = axes_[i];
  const std::int32_t cur = ax.mode;
  const bool repeated = req == ax.last_request;
  ax.last_request = req;
  // The PC answers the packet it got: repeating that packet's code is no request.
  if (req == cur || req == ax.sent_mode) return;
  const bool pc_special = req == P::code(P::Mode::freezing_active) || req == P::code(P::Mode::drive_off) ||
                          req == P::code(P::Mode::server_restart) || req == P::code(P::Mode::following_error);
  auto refuse = [&](std::string_view why) {
    if (repeated) return;  // counted and reported once per change of the request
    ++stats_.refused_requests;
    emit(EventLevel::warning, event::kRequestRefused,
         fmt::format("arm {} axis {}: the PC sent mode {} while in {}: {}", ax.arm, ax.axis, mode_text(req), mode_text(cur), why));
  };
  if (!pc_special) {
    handle_mode_request(i, req, refuse);
    return;
  }
  if (cur == P::code(P::Mode::driving_on)) {
    refuse("ignored while driving on (501)");
    return;
  }
  const auto change = P::check_mode_change(cur, req, false);
  if (change != P::ModeChange::allowed) {
    refuse(P::to_string(change));
    return;
  }
  const std::size_t arm = ax.arm;
  switch (req) {
    case 505:
      emit(EventLevel::error, event::kDriveOffFromPc, fmt::format("C4GOpen: Drive Off from Pc (arm {} axis {})", arm, ax.axis));
      drive_off(arm, req);
      break;
    case 508:
      emit(EventLevel::error, event::kFollowErrorFromPc,
           fmt::format("C4GOpen: arm {} axis {} Following error out of range", arm, ax.axis));
      drive_off(arm, req);
      break;
    case 500: {
      for (std::size_t k = 0; k < map_.count(); ++k)
        if (axes_[k].mode != 0 && axes_[k].mode != 500) {
          refuse("active freezing needs every axis in mode 0");
          return;
        }
      frozen_active_ = true;
      for (std::size_t k = 0; k < map_.count(); ++k) set_mode(k, req, {});
      emit(EventLevel::info, event::kFreezing, "active freezing (500) from the PC: replies are not checked until exit-from-open");
      break;
    }
    case 506: {
      for (std::size_t k = 0; k < map_.count(); ++k)
        if (axes_[k].mode != 0) {
          refuse("restart needs every axis in mode 0");
          return;
        }
      pending_special_ = req;
      emit(EventLevel::info, event::kInitSent, "restart (506) asked by the PC");
      break;
    }
    default: break;
  }
}

// A mode asked by the PC (chapter 11, second phase; 15.2: the mode is the one set by the PC or by
// the program): taken from mode 0 once the drives are on and the arm's trajectory is at rest
// (chapter 13: modes change between moves). While the PC's own exit-from-open is carried out, its
// SM field is not a request (the next mode is taken from mode 0).
void Controller::handle_mode_request(std::size_t i, std::int32_t req, const std::function<void(std::string_view)>& refuse) {
  AxisSim& ax = axes_[i];
  const std::int32_t cur = ax.mode;
  if (ax.exit.active) return;
  if (cur == P::code(P::Mode::driving_on)) {
    refuse("ignored while driving on (501)");
    return;
  }
  const auto change = P::check_mode_change(cur, req, false);
  if (change != P::ModeChange::allowed) {
    refuse(P::to_string(change));
    return;
  }
  ArmSim& a = arms_[ax.arm];
  if (req == P::code(P::Mode::mode2_standby)) {  // the PC ends mode 2 (state machine, mode 2)
    start_exit(ax.arm);
    return;
  }
  if (!drives_on(ax.arm)) {
    refuse("the drives are off: open modes are set once they are on (chapter 11)");
    return;
  }
  if (selector_prog_) {
    refuse("the state selector is in PROG: the open modes work in AUTO only (chapter 2)");
    return;
  }
  if (a.move.active) {
    refuse("the robot moves: modes change only between two moves (chapter 13)");
    return;
  }
  const P::ModeInfo* info = P::find_mode(req);
  if (info == nullptr || !info->available) {
    refuse("not available on this controller");
    return;
  }
  set_mode(i, req, {});
  if (is_open_mode(req) && !a.open) {
    a.open = true;
    a.type = OpenType::a;  // no program motion asked for: the PC alone moves the arm
    a.open_mode = req;
    a.exit_while_moving = false;
  }
}

// ---- modes ------------------------------------------------------------------------------------

void Controller::set_mode(std::size_t i, std::int32_t mode, std::string_view) {
  AxisSim& ax = axes_[i];
  if (ax.mode == mode) return;
  const std::int32_t base = base_mode(mode);
  const bool to_pc = (base == 1 || base == 2) && base_mode(ax.mode) != base;
  if (to_pc || ((mode == 11 || mode == 12) && ax.mode == base)) {  // soft switching in or out: hold here
    ax.hold_pos = ax.model.position();
    ax.scs.start(to_pc ? P::SwitchDirection::to_pc : P::SwitchDirection::to_drive, ax.hold_pos);
  }
  ax.mode = mode;
}

void Controller::set_arm_mode(std::size_t arm, std::int32_t mode, std::string_view why) {
  const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
  for (std::size_t i = first; i < first + n; ++i) set_mode(i, mode, why);
}

void Controller::start_drive_on(std::size_t arm) {
  ArmSim& a = arms_[arm];
  a.powered = true;
  a.drive_off_left = 0;
  a.drive_on_left = std::max(1, static_cast<int>(std::lround(robot_.drive_on_s / period_)));
  const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
  for (std::size_t i = first; i < first + n; ++i) {
    AxisSim& ax = axes_[i];
    // The trajectory starts where the brakes held the axis.
    ax.traj_pos = ax.ref_pos = ax.prev_ref_pos = ax.model.position();
    ax.traj_vel = ax.traj_acc = ax.ref_vel = 0;
    ax.offset = 0;
    ax.model.reset(ax.model.position());
    ax.mode_before_special = is_special(ax.mode) ? 0 : ax.mode;
    set_mode(i, P::code(P::Mode::driving_on), {});
  }
}

void Controller::drive_off(std::size_t arm, std::int32_t shown_code) {
  ArmSim& a = arms_[arm];
  const bool was_on = a.powered;
  a.powered = false;
  a.drive_on_left = 0;
  a.drive_off_left = std::max(1, static_cast<int>(std::lround(robot_.drive_off_s / period_)));
  a.drive_off_code = shown_code;
  a.move.active = false;
  a.open = false;
  exit_requested_[arm] = false;
  const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
  for (std::size_t i = first; i < first + n; ++i) {
    AxisSim& ax = axes_[i];
    ax.exit.active = false;
    ax.scs.clear();
    ax.traj_vel = ax.traj_acc = 0;
    set_mode(i, shown_code != 0 ? shown_code : (frozen_active_ ? ax.mode : 0), {});
  }
  if (was_on) emit(EventLevel::info, event::kDrivesOff, fmt::format("arm {}: drives off", arm));
}

int Controller::standby_ticks(std::int32_t code) const {
  if (code == 11 || code == 12) return std::max(1, static_cast<int>(std::lround(robot_.scs.times.total_s() / period_)));
  return std::max(1, robot_.standby_cycles);
}

void Controller::start_exit(std::size_t arm) {
  ArmSim& a = arms_[arm];
  const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
  for (std::size_t i = first; i < first + n; ++i) {
    AxisSim& ax = axes_[i];
    if (ax.exit.active || !is_open_mode(ax.mode)) continue;
    ax.exit.seq = P::exit_sequence(ax.mode, !a.move.active);
    ax.exit.index = 0;
    ax.exit.active = true;
    if (ax.exit.seq.count == 0) {
      ax.exit.seq.codes[0] = 0;
      ax.exit.seq.count = 1;
    }
    const std::int32_t code = ax.exit.seq.codes[0];
    if (code == 0) {
      finish_open_mode(i);
    } else {
      ax.exit.remaining = standby_ticks(code);
      set_mode(i, code, {});
    }
  }
}

void Controller::finish_open_mode(std::size_t i) {
  AxisSim& ax = axes_[i];
  const std::int32_t base = base_mode(ax.mode);
  const ArmSim& a = arms_[ax.arm];
  if (base == 4) {
    ax.traj_pos = ax.ref_pos;  // the trajectory generator continues from the PC's last target
    ax.offset = 0;
  } else if (base == 1) {
    ax.traj_pos = ax.model.position();
    ax.offset = 0;
  } else if (!a.move.active) {
    ax.traj_pos += ax.offset;  // modes 5, 7, ...: the accumulated increments become the trajectory's
    ax.offset = 0;
  }
  ax.exit.active = false;
  ax.scs.clear();
  set_mode(i, 0, {});
}

void Controller::advance_modes() {
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    ArmSim& a = arms_[arm];
    if (!a.present) continue;
    const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
    if (a.drive_on_left > 0 && --a.drive_on_left == 0) {
      for (std::size_t i = first; i < first + n; ++i) set_mode(i, axes_[i].mode_before_special, {});
      emit(EventLevel::info, event::kDrivesOn, fmt::format("arm {}: drives on", arm));
    }
    if (a.drive_off_left > 0 && --a.drive_off_left == 0) {
      for (std::size_t i = first; i < first + n; ++i)
        if (axes_[i].mode == a.drive_off_code && a.drive_off_code != 0) set_mode(i, 0, {});
    }
    if (exit_requested_[arm]) {
      exit_requested_[arm] = false;
      std::array<bool, P::kMaxAxes> was_exiting{};
      for (std::size_t i = first; i < first + n; ++i) was_exiting[i] = axes_[i].exit.active;
      start_exit(arm);
      // The standby codes count from the next packet (as when the program starts the exit): the loop
      // below would otherwise take one tick off at once (and one period off the switch back). Only
      // for exits started now: a PC that keeps asking (it may, every packet) must not stretch them.
      for (std::size_t i = first; i < first + n; ++i) axes_[i].exit.remaining += axes_[i].exit.active && !was_exiting[i] ? 1 : 0;
    }
    bool any_open = false;
    for (std::size_t i = first; i < first + n; ++i) {
      AxisSim& ax = axes_[i];
      if (ax.exit.active) {
        const std::int32_t code = ax.exit.seq.codes[ax.exit.index];
        const bool waits_for_motion = code == P::code(P::Mode::mode7_standby) && a.move.active;
        if (!waits_for_motion && --ax.exit.remaining <= 0) {
          ++ax.exit.index;
          const std::int32_t next = ax.exit.index < ax.exit.seq.count ? ax.exit.seq.codes[ax.exit.index] : 0;
          if (next == 0) {
            finish_open_mode(i);
          } else {
            ax.exit.remaining = standby_ticks(next);
            set_mode(i, next, {});
          }
        }
      }
      any_open |= is_open_mode(ax.mode) || ax.exit.active || P::base_of_standby(ax.mode).has_value();
    }
    if (a.open && !any_open) {
      a.open = false;
      // Chapter 13: the open modality ends on two events, the controller's trajectory end and the
      // PC's exit-from-open, in either order; say which came last.
      emit(EventLevel::info, event::kOpenEnd,
           a.type == OpenType::a
               ? fmt::format("arm {}: open type A (mode {}) ended by the PC's exit-from-open", arm, a.open_mode)
               : fmt::format("arm {}: open type B (mode {}) ended: {}", arm, a.open_mode,
                             a.exit_while_moving ? "PC exit first, then the controller's trajectory end"
                                                 : "controller's trajectory end first, then the PC exit"));
    }
  }
}

// ---- motion -----------------------------------------------------------------------------------

void Controller::advance_moves() {
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    ArmSim& a = arms_[arm];
    if (!a.present || !a.move.active) continue;
    Move& mv = a.move;
    mv.elapsed += period_;
    const double tau = std::min(1.0, mv.elapsed / mv.duration);
    double s = 0, ds = 0, dds = 0;
    min_jerk(tau, s, ds, dds);
    const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
    for (std::size_t i = first; i < first + n; ++i) {
      AxisSim& ax = axes_[i];
      const double d = mv.goal[ax.axis - 1] - mv.start[ax.axis - 1];
      ax.traj_pos = mv.start[ax.axis - 1] + d * s;
      ax.traj_vel = tau < 1.0 ? d * ds / mv.duration : 0.0;
      ax.traj_acc = tau < 1.0 ? d * dds / (mv.duration * mv.duration) : 0.0;
    }
    if (tau >= 1.0) {
      mv.active = false;
      for (std::size_t i = first; i < first + n; ++i) {
        AxisSim& ax = axes_[i];
        if (ax.mode == 0 && ax.offset != 0) {
          ax.traj_pos += ax.offset;
          ax.offset = 0;
        }
      }
    }
  }
}

void Controller::step_physics() {
  advance_moves();
  const int dsa_ticks = std::max(1, static_cast<int>(std::lround(period_ / kDsaPeriod)));
  for (std::size_t i = 0; i < map_.count(); ++i) {
    AxisSim& ax = axes_[i];
    const ArmSim& a = arms_[ax.arm];
    const P::Axis& pc = ax.pc;
    const double limit = std::fabs(ax.model.params().current_limit);
    const std::int32_t m = ax.mode;
    const std::int32_t base = base_mode(m);
    AxisCommand c;
    double dsa_ref = ax.traj_pos + ax.offset;
    double reported = dsa_ref;
    double vel = ax.traj_vel;
    double acc = ax.traj_acc;
    bool echo_test = false;
    switch (base) {
      case 10:  // 0': the controller keeps sending its own trajectory; the DSA gets what the PC echoed
        echo_test = true;
        dsa_ref = pc.d1;
        vel = pc.d2 / period_;
        break;
      case 1:  // the PC generates and closes the loops; the DSA holds until the switch is complete
        dsa_ref = ax.hold_pos;
        reported = pc.d1;
        vel = pc.d2 / period_;
        acc = 0;
        c.velocity = 0;
        ax.scs.command(robot_.scs, time_s(), pc.d5, limit, c);
        break;
      case 2:  // the controller generates, the PC closes the loops
        ax.scs.command(robot_.scs, time_s(), pc.d5, limit, c);
        break;
      case 4:  // absolute targets from the PC
        dsa_ref = reported = pc.d1;
        vel = pc.d2 / period_;
        acc = (vel - ax.ref_vel) / period_;
        break;
      case 5: {  // relative trajectory: the PC's delta per cycle, scaled by the general override, is integrated
        const double delta = pc.d2 * override_percent_ / 100.0;
        ax.offset += delta;
        dsa_ref = reported = ax.traj_pos + ax.offset;
        vel = ax.traj_vel + delta / period_;
        break;
      }
      case 7:  // additive position correction (none in 170)
        if (m != P::code(P::Mode::mode7_standby_exit)) {
          ax.offset += pc.d1;
          vel = ax.traj_vel + pc.d1 / period_;
        }
        dsa_ref = reported = ax.traj_pos + ax.offset;
        break;
      case 8: c.velocity_add = pc.d4 / period_; break;
      case 9:
        c.current_add = P::saturate_current(pc.d5, static_cast<float>(limit));
        c.dynamic_model = false;
        break;
      default: break;  // 0, 1xx (measure only) and the special codes: the controller's trajectory
    }
    if (base != 1) c.velocity = vel;
    c.acceleration = acc;
    const bool powered = a.powered;
    for (int k = 1; k <= dsa_ticks; ++k) {
      c.position = ax.prev_ref_pos + (dsa_ref - ax.prev_ref_pos) * k / dsa_ticks;
      ax.model.step(c, powered);
    }
    const bool pc_current = base == 1 || base == 2 || base == 9;
    if (ax.model.saturated() || (pc_current && a.powered && std::fabs(pc.d5) > limit)) ++stats_.saturated_cycles;
    ax.prev_ref_pos = dsa_ref;
    ax.dsa_ref = dsa_ref;
    ax.ref_pos = reported;
    ax.ref_vel = echo_test ? ax.traj_vel : vel;
  }
}

void Controller::check_following_error() {
  for (std::size_t i = 0; i < map_.count(); ++i) {
    AxisSim& ax = axes_[i];
    const ArmSim& a = arms_[ax.arm];
    const double threshold = ax.model.params().following_error;
    if (!a.powered || a.drive_on_left > 0 || threshold <= 0) continue;
    const std::int32_t base = base_mode(ax.mode);
    if (base == 1 || is_special(ax.mode)) continue;  // mode 1: not checked by the controller (manual)
    if (!P::following_error_exceeded(ax.dsa_ref, ax.model.position(), threshold)) continue;
    emit(EventLevel::error, event::kFollowErrorController,
         fmt::format("arm {} axis {}: following error {:.3f} turns over {:.3f} in mode {}", ax.arm, ax.axis,
                     ax.dsa_ref - ax.model.position(), threshold, mode_text(ax.mode)));
    drive_off(ax.arm, 0);
  }
}

bool Controller::arm_moving(std::size_t arm) const {
  const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
  for (std::size_t i = first; i < first + n; ++i)
    if (std::fabs(axes_[i].model.velocity()) > robot_.scs.still_velocity) return true;
  return false;
}

void Controller::check_soft_switch() {
  for (std::size_t i = 0; i < map_.count(); ++i) {
    AxisSim& ax = axes_[i];
    if (!arms_[ax.arm].powered || !ax.scs.moved(robot_.scs, ax.model.position())) continue;
    emit(EventLevel::error, event::kSoftSwitchMotion,
         fmt::format("arm {} axis {}: moved {:.4f} motor turns during soft control switching ({} {}), over {:.4f}", ax.arm,
                     ax.axis, ax.model.position() - ax.scs.anchor(), P::to_string(ax.scs.direction()),
                     P::to_string(ax.scs.last().interval), robot_.scs.still_tolerance));
    drive_off(ax.arm, 0);
  }
}

// Modes 7, 8, 9 (chapter 14.17.1): the controller keeps checking the offset between a reference
// position and the one scheduled before it. Only mode 7 lets the PC move the reference (8 and 9 act
// on the loops), so only its correction can trip it.
void Controller::check_offset_limit() {
  const double limit = robot_.max_offset_speed * period_;
  for (std::size_t i = 0; i < map_.count(); ++i) {
    AxisSim& ax = axes_[i];
    if (!arms_[ax.arm].powered || base_mode(ax.mode) != 7 || ax.mode == P::code(P::Mode::mode7_standby_exit)) continue;
    if (std::fabs(ax.pc.d1) <= limit) continue;
    emit(EventLevel::error, event::kOffsetLimit,
         fmt::format("arm {} axis {}: reference offset {:.4f} motor turns in one cycle over the limit {:.4f} (mode {})", ax.arm,
                     ax.axis, ax.pc.d1, limit, mode_text(ax.mode)));
    ax.pc = P::Axis{};
    drive_off(ax.arm, 0);
  }
}

void Controller::force_mode0(std::size_t arm) {
  ArmSim& a = arms_[arm];
  const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
  bool any = false;
  for (std::size_t i = first; i < first + n; ++i) any |= axes_[i].mode != 0 && !is_special(axes_[i].mode);
  if (!any) return;
  emit(EventLevel::error, event::kForcedMode0, fmt::format("C4GOpen: arm {} , forced 0 modality", arm));
  for (std::size_t i = first; i < first + n; ++i) {
    AxisSim& ax = axes_[i];
    if (ax.mode == 0 || is_special(ax.mode)) continue;
    // No exit: the trajectory generator's position (pos_i) is not brought to the PC's (pos_k).
    const std::int32_t base = base_mode(ax.mode);
    const double before = base == 1 || base == 2 ? ax.model.position() : ax.dsa_ref;
    const double jump = ax.traj_pos - before;
    if (std::fabs(jump) > 1e-3)
      emit(EventLevel::warning, event::kPositionJump,
           fmt::format("arm {} axis {}: mode {} left without its exit: the reference jumps {:.4f} motor turns (pos_i not "
                       "updated to pos_k; recovery: $C4G_PA := 1, C4GOPEN_MODE := 0, CSA, CCRC)",
                       arm, ax.axis, mode_text(ax.mode), jump));
    ax.offset = 0;
    ax.exit.active = false;
    ax.scs.clear();
    set_mode(i, 0, {});
  }
  a.open = false;
  exit_requested_[arm] = false;
}

// ---- the robot program ----------------------------------------------------------------------

std::vector<std::size_t> Controller::step_arms(const Step& s) const {
  std::vector<std::size_t> out;
  if (s.arms.empty()) {
    for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm)
      if (arms_[arm].present) out.push_back(arm);
  } else {
    for (int a : s.arms) out.push_back(static_cast<std::size_t>(a));
  }
  return out;
}

bool Controller::all_axes_in_mode0() const {
  for (std::size_t i = 0; i < map_.count(); ++i)
    if (axes_[i].mode != 0) return false;
  return true;
}

void Controller::fail_scenario(const Step& s, std::string_view why) {
  scenario_error_ = fmt::format("{}: {}: {}", s.where, to_string(s.kind), why);
  emit(EventLevel::error, event::kScenarioError, scenario_error_);
}

void Controller::run_scenario() {
  if (scenario_done_ || scenario_failed()) return;
  while (step_index_ < scenario_.steps.size()) {
    const Step& s = scenario_.steps[step_index_];
    if (!step_started_) {
      step_started_ = true;
      step_start_tick_ = stats_.ticks;
      emit(EventLevel::info, event::kStep, fmt::format("step {}: {} ({})", step_index_ + 1, to_string(s.kind), s.where));
      if (!start_step(s)) return;
    }
    if (!step_complete(s)) return;
    ++step_index_;
    step_started_ = false;
  }
  scenario_done_ = true;
  emit(EventLevel::info, event::kScenarioDone, fmt::format("scenario '{}' completed", scenario_.name));
}

bool Controller::start_step(const Step& s) {
  const auto arms = step_arms(s);
  for (std::size_t arm : arms)
    if (!arms_[arm].present) {
      fail_scenario(s, fmt::format("arm {} has no open axes", arm));
      return false;
    }
  switch (s.kind) {
    case StepKind::drive_on:
      for (std::size_t arm : arms)
        if (!arms_[arm].powered) start_drive_on(arm);
      return true;
    case StepKind::drive_off:
      for (std::size_t arm : arms)
        if (arms_[arm].powered) drive_off(arm, 0);
      return true;
    case StepKind::go_open:
      for (std::size_t arm : arms) {
        ArmSim& a = arms_[arm];
        if (!drives_on(arm)) {
          fail_scenario(s, fmt::format("arm {}: drives are not on", arm));
          return false;
        }
        if (selector_prog_ && s.mode != 0) {
          fail_scenario(s, "the state selector is in PROG: the open modes work in AUTO only (chapter 2)");
          return false;
        }
        const bool switches = s.mode == 1 || s.mode == 2;  // soft switching needs a still robot (T1..T3)
        const bool moving = a.move.active || (switches && arm_moving(arm));
        // The state machine (chapter 24): GO OPEN only from S00, the robot still (not from S10).
        const auto event = s.type == OpenType::a ? P::MotionEvent::go_open_a : P::MotionEvent::go_open_b;
        if (!a.open && !P::next_state(moving ? P::MotionState::closed : P::MotionState::stop, event)) {
          fail_scenario(s, fmt::format("arm {}: the robot moves; modes change only between moves", arm));
          return false;
        }
        const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
        if (s.mode == P::code(P::Mode::mode2_standby) && a.open && a.open_mode == P::code(P::Mode::mode2)) {
          // Mode 2 is the one the robot program ends itself (state machine: the program sets 2' after
          // its move, then waits while control ramps back to the drive): the exit sequence 12 -> 0.
          start_exit(arm);
          continue;
        }
        for (std::size_t i = first; i < first + n; ++i) {
          const std::int32_t cur = axes_[i].mode;
          if (cur != 0 && cur != 10 && cur != s.mode) {
            fail_scenario(s, fmt::format("arm {} axis {} is in mode {}: a mode is set from mode 0", arm, axes_[i].axis, mode_text(cur)));
            return false;
          }
        }
        set_arm_mode(arm, s.mode, {});
        a.open = is_open_mode(s.mode);
        a.type = s.type;
        a.open_mode = s.mode;
        a.exit_while_moving = false;
      }
      return true;
    case StepKind::move: {
      const std::size_t arm = static_cast<std::size_t>(s.arm);
      ArmSim& a = arms_[arm];
      if (!a.present) {
        fail_scenario(s, fmt::format("arm {} has no open axes", arm));
        return false;
      }
      if (!drives_on(arm)) {
        fail_scenario(s, fmt::format("arm {}: drives are not on", arm));
        return false;
      }
      // The state machine: MOVE from S00 (to S10) or as the controller's part of S11 (type B); none
      // from S01, where the PC alone moves the robot.
      if (a.open && a.type == OpenType::a && !P::next_state(P::MotionState::open_a, P::MotionEvent::move)) {
        fail_scenario(s, "MOVE while open type A (the PC moves the robot; the state machine forbids it)");
        return false;
      }
      if (a.open && (a.open_mode == 1 || a.open_mode == 4 || a.open_mode == 5)) {
        fail_scenario(s, fmt::format("MOVE in mode {}: the PC generates the trajectory", a.open_mode));
        return false;
      }
      const auto& t = *a.transform;
      const auto na = static_cast<Eigen::Index>(t.axes());
      P::ArmTransform::Vector motor(na);
      for (Eigen::Index k = 0; k < na; ++k) {
        const auto open = map_.open_index(arm, static_cast<std::size_t>(k) + 1);
        motor[k] = open ? axes_[*open].traj_pos : t.calibration()[k];
      }
      auto q = t.link_position(motor);
      for (std::size_t k = 0; k < s.deg.size() && k < t.axes(); ++k)
        if (s.deg[k]) q[static_cast<Eigen::Index>(k)] = *s.deg[k] * std::numbers::pi / 180.0;
      const auto goal = t.motor_position(q);
      Move& mv = a.move;
      mv = Move{};
      const std::size_t first = map_.arm_first(arm), n = map_.arm_count(arm);
      for (std::size_t i = first; i < first + n; ++i) {
        const std::size_t k = axes_[i].axis - 1u;
        mv.start[k] = axes_[i].traj_pos;
        mv.goal[k] = k < t.axes() ? goal[static_cast<Eigen::Index>(k)] : axes_[i].traj_pos;
      }
      mv.duration = s.seconds;
      mv.active = true;
      return true;
    }
    case StepKind::cmd: arms_[static_cast<std::size_t>(s.arm)].cmd = static_cast<std::uint8_t>(s.value); return true;
    case StepKind::freeze_passive:
    case StepKind::restart:
    case StepKind::exit_open: {
      if (!all_axes_in_mode0()) {
        fail_scenario(s, "needs every axis in mode 0");
        return false;
      }
      if (s.kind == StepKind::freeze_passive) {
        pending_special_ = P::code(P::Mode::freezing_passive_in);
        passive_left_ = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(s.seconds / period_)));
      } else {
        pending_special_ = s.kind == StepKind::restart ? P::code(P::Mode::server_restart) : P::code(P::Mode::exit_open);
      }
      return true;
    }
    case StepKind::run: running_forever_ = true; return true;
    case StepKind::selector:
      if (selector_prog_ != (s.value == 1)) {
        selector_prog_ = s.value == 1;
        for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm)
          if (arms_[arm].present) force_mode0(arm);
      }
      return true;
    case StepKind::general_override: override_percent_ = s.value; return true;
    case StepKind::delay:
    case StepKind::wait_for_pc: return true;
  }
  return true;
}

bool Controller::step_complete(const Step& s) {
  const double elapsed = ticks_to_s(stats_.ticks - step_start_tick_);
  switch (s.kind) {
    case StepKind::drive_on:
      for (std::size_t arm : step_arms(s))
        if (!drives_on(arm)) return false;
      return true;
    case StepKind::drive_off:
      for (std::size_t arm : step_arms(s))
        if (arms_[arm].powered || arms_[arm].drive_off_left > 0) return false;
      return true;
    case StepKind::go_open:
      if (s.mode == P::code(P::Mode::mode2_standby))  // leaving mode 2 blocks until mode 0, like its delays
        for (std::size_t arm : step_arms(s))
          if (arms_[arm].open) return false;
      return true;
    case StepKind::cmd:
    case StepKind::selector:
    case StepKind::general_override: return true;
    case StepKind::wait_for_pc:
      for (std::size_t arm : step_arms(s))
        if (arms_[arm].open) {
          if (s.seconds > 0 && elapsed >= s.seconds) fail_scenario(s, fmt::format("no exit-from-open within {} s", s.seconds));
          return false;
        }
      return true;
    case StepKind::move: {
      const ArmSim& a = arms_[static_cast<std::size_t>(s.arm)];
      if (!a.powered) {
        fail_scenario(s, "move aborted: drives off");
        return false;
      }
      return !a.move.active;
    }
    case StepKind::delay: return elapsed + 1e-9 >= s.seconds;
    case StepKind::freeze_passive:
    case StepKind::restart: return pending_special_ == 0 && phase_ == Phase::cycle;
    case StepKind::exit_open: return phase_ == Phase::ended;
    case StepKind::run: return false;
  }
  return true;
}

}  // namespace axon::c4g::sim
