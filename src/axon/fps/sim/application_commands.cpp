// PositionerModel: the commands of the main application (interface document 5.3, table 6).
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/sim/positioner_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace axon::fps::sim {

namespace proto = protocol;
using proto::CommandId;
using proto::ResponseCode;

namespace {

constexpr double kStepsPerDegree = static_cast<double>(proto::kStepsPerTurn) / proto::kDegreesPerTurn;

// Degrees to the wire's position steps, saturating at the int32 range.
proto::Angle angle(double deg) noexcept {
  const double steps = std::round(deg * kStepsPerDegree);
  constexpr double lo = std::numeric_limits<std::int32_t>::min();
  constexpr double hi = std::numeric_limits<std::int32_t>::max();
  if (!(steps >= lo)) return proto::Angle::from_steps(std::numeric_limits<std::int32_t>::min());
  if (steps > hi) return proto::Angle::from_steps(std::numeric_limits<std::int32_t>::max());
  return proto::Angle::from_steps(static_cast<std::int32_t>(steps));
}

double degrees(proto::Angle a) noexcept { return static_cast<double>(a.steps()) / kStepsPerDegree; }

bool is_calibration(Activity a) noexcept {
  return a == Activity::datum_calibration || a == Activity::motor_calibration || a == Activity::cogging_calibration;
}

// A cogging table entry: deterministic per (seed, id, arm, index, direction), about +-1000.
std::int32_t cogging_value(std::uint64_t seed, std::uint16_t id, Arm arm, std::uint32_t index, bool positive) {
  std::uint64_t z = seed ^ (std::uint64_t{id} << 40) ^ (std::uint64_t{index} << 8) ^
                    (static_cast<std::uint64_t>(arm) << 4) ^ (positive ? 1u : 2u);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  const auto v = static_cast<std::int32_t>(z % 2001) - 1000;
  return positive ? v : -v;
}

}  // namespace

void PositionerModel::reply(const proto::Message& m, ResponseCode code, Outbox& out, const proto::Payload& payload) {
  ++counters_.requests;
  if (code != ResponseCode::accepted) ++counters_.rejected;
  out.push_back(proto::Message{proto::Identifier{config_.id, m.id.command, m.id.uid, code},
                               code == ResponseCode::accepted ? payload : proto::Payload{}});
}

Outbox PositionerModel::handle(const proto::Message& m, SimTime now) {
  Outbox out;
  run_until(now, out);
  if (!listening() || (!m.id.is_broadcast() && m.id.positioner != config_.id)) {
    ++counters_.ignored;
    return out;
  }
  const auto mode = run_ == RunState::bootloader ? proto::Mode::bootloader : proto::Mode::application;
  auto verdict =
      proto::check_device_request(m.id.command, mode, m.id.is_broadcast(), m.payload.size(), config_.device_options);
  if (mode == proto::Mode::application && verdict.command != nullptr &&
      !firmware_takes(verdict.command->id, flash_.main.version, config_.firmware_history)) {
    verdict.code = ResponseCode::unknown_command;  // a number this version has never heard of
  }
  if (verdict.code != ResponseCode::accepted) {
    reply(m, verdict.code, out);
    return out;
  }
  if (mode == proto::Mode::bootloader) {
    handle_bootloader(m, *verdict.command, out);
    // Every valid command restarts the bootloader's wait.
    if (run_ == RunState::bootloader && out.back().id.response == ResponseCode::accepted) {
      bootloader_deadline_ = now_ + config_.bootloader_timeout;
    }
  } else {
    handle_application(m, *verdict.command, out);
  }
  return out;
}

ResponseCode PositionerModel::motion_check(Activity kind, PerArm<bool> arms) const noexcept {
  if (arms_[Arm::alpha].collided) return ResponseCode::alpha_collision;
  if (arms_[Arm::beta].collided) return ResponseCode::beta_collision;
  if (is_calibration(activity_)) return ResponseCode::calibration_mode_active;
  if (activity_ != Activity::idle) return ResponseCode::already_in_motion;
  const bool search = kind == Activity::datum_search;
  const bool calibration = search || is_calibration(kind);
  const bool needs_motor = calibration && kind != Activity::motor_calibration;
  const bool needs_datum = kind == Activity::trajectory;  // GO_TO_ABSOLUTE checks it itself
  for (Arm a : kArms) {
    if (arms[a] && needs_datum && !arms_[a].initialized) return ResponseCode::datum_not_initialized;
  }
  for (Arm a : kArms) {
    if (!arms[a] || cal_.motor[a]) continue;
    const bool uses_hall = arms_[a].closed_loop || arms_[a].detection;
    if (needs_motor || (!calibration && uses_hall)) return ResponseCode::motor_not_calibrated;
  }
  for (Arm a : kArms) {
    if (arms[a] && search && !cal_.datum[a]) return ResponseCode::datum_not_calibrated;
  }
  if (hall_unavailable()) return ResponseCode::hall_sensors_disabled;
  for (Arm a : kArms) {
    if (arms[a] && calibration && !arms_[a].closed_loop && !arms_[a].detection) {
      return ResponseCode::hall_sensors_disabled;
    }
  }
  return ResponseCode::accepted;
}

ResponseCode PositionerModel::start_trajectory(SimTime t) {
  if (!upload_.loaded && config_.start_without_trajectory == EmptyStart::accept) {
    // Nothing to start: the robot stays as it is. A collision flag still answers 8/9, the answer
    // the document's start sequence looks for [7.2].
    if (arms_[Arm::alpha].collided) return ResponseCode::alpha_collision;
    if (arms_[Arm::beta].collided) return ResponseCode::beta_collision;
    return ResponseCode::accepted;
  }
  if (const auto code = motion_check(Activity::trajectory, {{true, true}}); code != ResponseCode::accepted) {
    return code;
  }
  if (!upload_.loaded) return ResponseCode::invalid_trajectory;
  // The first point is reached from where the arm is now (time 0): within the speed limit?
  for (Arm a : kArms) {
    const auto& pts = upload_.points[a];
    if (pts.empty()) continue;
    const double d = std::abs(pts.front().deg + cal_.offset_deg[a] - belief(a));
    if (d > max_arm_speed() * to_seconds(pts.front().t) + 1e-9) return ResponseCode::value_out_of_range;
  }
  bool any = false;
  for (Arm a : kArms) {
    const auto& pts = upload_.points[a];
    if (pts.empty()) continue;
    ArmPath p(t, belief(a));
    for (const auto& pt : pts) p.point(t + pt.t, pt.deg + cal_.offset_deg[a]);
    start_commanded(a, std::move(p));
    any = true;
  }
  upload_ = {};
  activity_ = any ? Activity::trajectory : Activity::idle;
  return ResponseCode::accepted;
}

void PositionerModel::start_activity(Activity kind, PerArm<bool> arms, SimTime t) {
  activity_ = kind;
  for (Arm a : kArms) {
    if (!arms[a]) continue;
    const double v = arm_speed(a);
    const double lo = lower_stop(a);
    const double hi = upper_stop(a);
    const double theta = arms_[a].theta;
    const double motor_turn = 360.0 / config_.gear_ratio;  // one motor turn at the arm
    ArmPath p(t, theta);
    switch (kind) {
      case Activity::datum_search: p.line_to(lo, v); break;
      case Activity::datum_calibration: {
        p.line_to(lo, v);
        for (int k = 0; k < 2; ++k) p.line_to(lo + config_.datum_backoff_deg, v).line_to(lo, v);
        // Three contacts read with a little scatter (motor degrees); the new zero is their mean.
        double lo_read = 0, hi_read = 0, sum = 0;
        for (int k = 0; k < 3; ++k) {
          const double r = (noise() - 0.5) * config_.datum_spread_motor_deg;
          lo_read = k == 0 ? r : std::min(lo_read, r);
          hi_read = k == 0 ? r : std::max(hi_read, r);
          sum += r;
        }
        pending_spread_[a] = static_cast<std::int32_t>(std::lround(hi_read - lo_read));
        pending_zero_error_[a] = sum / 3.0 / config_.gear_ratio;
        break;
      }
      case Activity::motor_calibration: {
        // A few motor turns away from the nearer stop and back.
        const double sweep = config_.motor_calibration_turns * motor_turn;
        const double target = std::clamp(theta - lo < hi - theta ? theta + sweep : theta - sweep, lo, hi);
        p.point(t + config_.motor_calibration_time / 2, target).point(t + config_.motor_calibration_time, theta);
        break;
      }
      case Activity::cogging_calibration: {
        p.line_to(lo, v);
        const SimTime at_stop = p.end();
        p.point(at_stop + config_.cogging_calibration_time / 2, std::min(lo + 4 * motor_turn, hi))
            .point(at_stop + config_.cogging_calibration_time, lo);
        break;
      }
      case Activity::idle:
      case Activity::go_to:
      case Activity::trajectory: break;
    }
    start_physical(a, std::move(p));
  }
}

void PositionerModel::handle_application(const proto::Message& m, const proto::CommandInfo& c, Outbox& out) {
  const auto bytes = m.payload.span();
  const auto done = [&](ResponseCode code, const proto::Payload& p = {}) { reply(m, code, out, p); };
  const auto code_of = [](const Error& e) { return proto::response_code_for(e.code); };
  const auto setting_check = [&]() -> ResponseCode {  // settings that cannot change during a move
    if (is_calibration(activity_)) return ResponseCode::calibration_mode_active;
    if (activity_ != Activity::idle) return ResponseCode::already_in_motion;
    return ResponseCode::accepted;
  };
  const auto move_or_calibrate = [&](Activity kind, PerArm<bool> arms) {
    const auto code = motion_check(kind, arms);
    if (code == ResponseCode::accepted) start_activity(kind, arms, now_);
    done(code);
  };
  const auto set_mode = [&](Arm a, bool closed, bool detection) {
    const auto code = setting_check();
    if (code == ResponseCode::accepted) {
      arms_[a].closed_loop = closed;
      arms_[a].detection = detection;
    }
    done(code);
  };
  const PerArm<bool> both{{true, true}}, alpha{{true, false}}, beta{{false, true}};

  switch (c.id) {
    case CommandId::get_id: return done(ResponseCode::accepted, proto::PositionerIdReply{config_.id}.encode());
    case CommandId::get_firmware_version:
      return done(ResponseCode::accepted, flash_.main.version.encode(config_.version_byte_order));
    case CommandId::get_status: return done(ResponseCode::accepted, proto::StatusReply{status()}.encode());

    case CommandId::send_new_trajectory: {
      if (arms_[Arm::alpha].collided) return done(ResponseCode::alpha_collision);
      if (arms_[Arm::beta].collided) return done(ResponseCode::beta_collision);
      if (const auto code = setting_check(); code != ResponseCode::accepted) return done(code);
      if (!arms_[Arm::alpha].initialized || !arms_[Arm::beta].initialized) {
        return done(ResponseCode::datum_not_initialized);
      }
      auto size = proto::TrajectorySize::decode(bytes);
      if (!size) return done(code_of(size.error()));
      upload_ = {};
      upload_.receiving = true;
      upload_.expected = {{size.value().alpha_points, size.value().beta_points}};
      return done(ResponseCode::accepted);
    }
    case CommandId::send_trajectory_data: {
      auto point = proto::TrajectoryPoint::decode(bytes);
      if (!point) return done(code_of(point.error()));
      if (!upload_.receiving) return done(ResponseCode::invalid_trajectory);
      // Alpha points until the announced number is reached, then beta points.
      Arm a = Arm::alpha;
      if (upload_.points[Arm::alpha].size() >= upload_.expected[Arm::alpha]) {
        a = Arm::beta;
        if (upload_.points[Arm::beta].size() >= upload_.expected[Arm::beta]) {
          upload_.bad = true;  // more points than announced
          return done(ResponseCode::invalid_trajectory);
        }
      }
      auto& pts = upload_.points[a];
      const TimedPoint p{from_wire_time(point.value().time), degrees(point.value().position)};
      const TimedPoint prev = pts.empty() ? TimedPoint{SimDuration::zero(), reported_deg(a)} : pts.back();
      pts.push_back(p);
      const double target = p.deg + cal_.offset_deg[a];
      const bool in_range = target > lower_stop(a) && target < upper_stop(a);
      const bool later = p.t > prev.t;
      const bool slow_enough = later && std::abs(p.deg - prev.deg) <= max_arm_speed() * to_seconds(p.t - prev.t) + 1e-9;
      if (!in_range || !slow_enough) {
        upload_.bad = true;
        return done(ResponseCode::value_out_of_range);
      }
      return done(ResponseCode::accepted);
    }
    case CommandId::trajectory_data_end: {
      if (!upload_.receiving) return done(ResponseCode::invalid_trajectory);
      const bool complete = upload_.points[Arm::alpha].size() == upload_.expected[Arm::alpha] &&
                            upload_.points[Arm::beta].size() == upload_.expected[Arm::beta];
      if (!complete || upload_.bad) {
        upload_ = {};
        return done(ResponseCode::invalid_trajectory);
      }
      upload_.receiving = false;
      upload_.loaded = true;
      return done(ResponseCode::accepted);
    }
    case CommandId::trajectory_abort:
    case CommandId::stop_trajectory:
      stop_motion(now_);
      upload_ = {};
      if (c.id == CommandId::stop_trajectory) {
        for (Arm a : kArms) arms_[a].collided = false;
      }
      return done(ResponseCode::accepted);
    case CommandId::start_trajectory: return done(start_trajectory(now_));

    case CommandId::go_to_datums: return move_or_calibrate(Activity::datum_search, both);
    case CommandId::go_to_datum_alpha: return move_or_calibrate(Activity::datum_search, alpha);
    case CommandId::go_to_datum_beta: return move_or_calibrate(Activity::datum_search, beta);
    case CommandId::calibrate_datum: return move_or_calibrate(Activity::datum_calibration, both);
    case CommandId::calibrate_datum_alpha: return move_or_calibrate(Activity::datum_calibration, alpha);
    case CommandId::calibrate_datum_beta: return move_or_calibrate(Activity::datum_calibration, beta);
    case CommandId::calibrate_motors: return move_or_calibrate(Activity::motor_calibration, both);
    case CommandId::calibrate_motor_alpha: return move_or_calibrate(Activity::motor_calibration, alpha);
    case CommandId::calibrate_motor_beta: return move_or_calibrate(Activity::motor_calibration, beta);
    case CommandId::calibrate_cogging: return move_or_calibrate(Activity::cogging_calibration, both);
    case CommandId::calibrate_cogging_alpha: return move_or_calibrate(Activity::cogging_calibration, alpha);
    case CommandId::calibrate_cogging_beta: return move_or_calibrate(Activity::cogging_calibration, beta);
    case CommandId::get_datum_calibration_error:
      return done(ResponseCode::accepted,
                  proto::ArmValues{cal_.datum_error[Arm::alpha], cal_.datum_error[Arm::beta]}.encode());

    case CommandId::go_to_absolute_position:
    case CommandId::go_to_relative_position: {
      auto target = proto::ArmPositions::decode(bytes);
      if (!target) return done(code_of(target.error()));
      const bool absolute = c.id == CommandId::go_to_absolute_position;
      if (auto code = motion_check(Activity::go_to, both); code != ResponseCode::accepted) return done(code);
      if (absolute && (!arms_[Arm::alpha].initialized || !arms_[Arm::beta].initialized)) {
        return done(ResponseCode::datum_not_initialized);
      }
      PerArm<double> goal{};
      goal[Arm::alpha] = degrees(target.value().alpha);
      goal[Arm::beta] = degrees(target.value().beta);
      for (Arm a : kArms) {
        goal[a] += absolute ? cal_.offset_deg[a] : belief(a);
        // Without a datum the firmware cannot know where the stops are: relative moves go unchecked.
        if (!arms_[a].initialized) continue;
        const double top = goal[a] + (arms_[a].precise ? config_.precise_approach_deg : 0.0);
        if (!(goal[a] > lower_stop(a) && top < upper_stop(a))) return done(ResponseCode::value_out_of_range);
      }
      PerArm<SimDuration> eta{};
      for (Arm a : kArms) {
        const double v = arm_speed(a);
        ArmPath p(now_, belief(a));
        // Precise moves overshoot by the approach angle and come back to the target in open loop.
        if (arms_[a].precise) p.line_to(goal[a] + config_.precise_approach_deg, v);
        p.line_to(goal[a], v);
        eta[a] = p.end() - now_;
        start_commanded(a, std::move(p));
      }
      activity_ = Activity::go_to;
      return done(ResponseCode::accepted,
                  proto::ArmTimes{to_wire_time(eta[Arm::alpha]), to_wire_time(eta[Arm::beta])}.encode());
    }
    case CommandId::get_current_position:
      return done(ResponseCode::accepted,
                  proto::ArmPositions{angle(reported_deg(Arm::alpha)), angle(reported_deg(Arm::beta))}.encode());
    case CommandId::set_current_position: {
      auto pos = proto::ArmPositions::decode(bytes);
      if (!pos) return done(code_of(pos.error()));
      if (const auto code = setting_check(); code != ResponseCode::accepted) return done(code);
      const PerArm<double> want{{degrees(pos.value().alpha), degrees(pos.value().beta)}};
      for (Arm a : kArms) {
        ArmState& s = arms_[a];
        s.datum_err = want[a] + cal_.offset_deg[a] - s.theta;
        s.slip = 0;
        s.initialized = true;
      }
      return done(ResponseCode::accepted);
    }
    case CommandId::get_offsets:
      return done(ResponseCode::accepted, proto::ArmPositions{angle(cal_.offset_deg[Arm::alpha]),
                                                              angle(cal_.offset_deg[Arm::beta])}.encode());
    case CommandId::set_offsets: {
      auto off = proto::ArmPositions::decode(bytes);
      if (!off) return done(code_of(off.error()));
      if (const auto code = setting_check(); code != ResponseCode::accepted) return done(code);
      cal_.offset_deg[Arm::alpha] = degrees(off.value().alpha);
      cal_.offset_deg[Arm::beta] = degrees(off.value().beta);
      return done(ResponseCode::accepted);
    }
    case CommandId::set_speed: {
      auto speeds = proto::ArmSpeeds::decode(bytes);
      if (!speeds) return done(code_of(speeds.error()));
      for (const auto rpm : {speeds.value().alpha.rpm(), speeds.value().beta.rpm()}) {
        if (rpm < config_.min_speed_rpm || rpm > config_.max_speed_rpm) return done(ResponseCode::value_out_of_range);
      }
      arms_[Arm::alpha].speed_rpm = speeds.value().alpha.rpm();
      arms_[Arm::beta].speed_rpm = speeds.value().beta.rpm();
      return done(ResponseCode::accepted);
    }
    case CommandId::set_current: {
      auto cur = proto::ArmCurrents::decode(bytes);
      if (!cur) return done(code_of(cur.error()));
      for (const auto pc : {cur.value().alpha.percent(), cur.value().beta.percent()}) {
        if (pc > config_.max_current_percent) return done(ResponseCode::value_out_of_range);
      }
      arms_[Arm::alpha].drive_current = cur.value().alpha.percent();
      arms_[Arm::beta].drive_current = cur.value().beta.percent();
      return done(ResponseCode::accepted);
    }
    case CommandId::get_hall_position:
      return done(ResponseCode::accepted,
                  proto::ArmPositions{angle(hall_deg(Arm::alpha)), angle(hall_deg(Arm::beta))}.encode());
    case CommandId::get_motor_calibration_error:
      return done(ResponseCode::accepted,
                  proto::ArmValues{cal_.motor_error[Arm::alpha], cal_.motor_error[Arm::beta]}.encode());
    case CommandId::save_calibration:
      if (is_calibration(activity_)) return done(ResponseCode::calibration_mode_active);
      flash_.calibration = cal_;
      return done(ResponseCode::accepted);

    case CommandId::get_position_and_current_alpha:
    case CommandId::get_position_and_current_beta:
    case CommandId::get_position_and_torque_alpha:
    case CommandId::get_position_and_torque_beta:
    case CommandId::get_currents:
    case CommandId::get_torques: {
      const auto reading = [&](Arm a, bool torque) -> std::int32_t {
        const ArmState& s = arms_[a];
        if (!s.moving) return static_cast<std::int32_t>(cal_.holding_current[a]);
        const double v = s.phys.speed_at(now_);
        const double magnitude = s.closed_loop ? friction_current_percent(a, v * config_.gear_ratio / 6.0)
                                               : static_cast<double>(s.drive_current);
        const auto value = static_cast<std::int32_t>(std::lround(magnitude));
        return torque && v < 0 ? -value : value;
      };
      const bool torque = c.id == CommandId::get_position_and_torque_alpha ||
                          c.id == CommandId::get_position_and_torque_beta || c.id == CommandId::get_torques;
      if (c.id == CommandId::get_currents || c.id == CommandId::get_torques) {
        return done(ResponseCode::accepted,
                    proto::ArmValues{reading(Arm::alpha, torque), reading(Arm::beta, torque)}.encode());
      }
      const Arm a = (c.id == CommandId::get_position_and_current_alpha ||
                     c.id == CommandId::get_position_and_torque_alpha)
                        ? Arm::alpha
                        : Arm::beta;
      return done(ResponseCode::accepted, proto::PositionAndValue{angle(reported_deg(a)), reading(a, torque)}.encode());
    }

    case CommandId::get_cogging_vector_length:
      return done(ResponseCode::accepted, proto::U32Value{config_.cogging_vector_length}.encode());
    case CommandId::get_cogging_positive:
    case CommandId::get_cogging_negative:
    case CommandId::get_cogging_angles: {
      auto idx = proto::ArmIndices::decode(bytes);
      if (!idx) return done(code_of(idx.error()));
      const PerArm<std::uint32_t> at{{idx.value().alpha, idx.value().beta}};
      PerArm<std::int32_t> v{};
      for (Arm a : kArms) {
        if (at[a] >= config_.cogging_vector_length) return done(ResponseCode::value_out_of_range);
        if (c.id == CommandId::get_cogging_angles) {
          // Degrees within one motor turn, spread evenly over the table.
          v[a] = static_cast<std::int32_t>(static_cast<std::uint64_t>(at[a]) * 360 / config_.cogging_vector_length);
        } else if (cal_.cogging[a]) {
          v[a] = cogging_value(config_.seed, config_.id, a, at[a], c.id == CommandId::get_cogging_positive);
        }
      }
      return done(ResponseCode::accepted, proto::ArmValues{v[Arm::alpha], v[Arm::beta]}.encode());
    }
    case CommandId::set_collision_margin: {
      auto margins = proto::ArmMargins::decode(bytes);
      if (!margins) return done(code_of(margins.error()));
      arms_[Arm::alpha].margin = margins.value().alpha.value();
      arms_[Arm::beta].margin = margins.value().beta.value();
      return done(ResponseCode::accepted);
    }
    case CommandId::set_holding_current: {
      auto cur = proto::ArmCurrents::decode(bytes);
      if (!cur) return done(code_of(cur.error()));
      cal_.holding_current = {{cur.value().alpha.percent(), cur.value().beta.percent()}};
      return done(ResponseCode::accepted);
    }
    case CommandId::get_holding_current:
      return done(ResponseCode::accepted, proto::Payload()
                                              .put_u32(cal_.holding_current[Arm::alpha])
                                              .put_u32(cal_.holding_current[Arm::beta]));
    case CommandId::switch_on_hall:
      hall_on_ = true;
      if (hall_sleeping_) {
        hall_sleeping_ = false;
        hall_ready_at_ = now_ + config_.hall_wake_up;
      }
      return done(ResponseCode::accepted);
    case CommandId::switch_off_hall:
      // Asleep at once when idle, otherwise when the running move ends.
      hall_on_ = false;
      if (activity_ == Activity::idle && !hall_sleeping_) {
        for (Arm a : kArms) hall_frozen_[a] = hall_deg(a);
        hall_sleeping_ = true;
        hall_ready_at_.reset();
      }
      return done(ResponseCode::accepted);
    case CommandId::alpha_closed_loop_with_collision_detection: return set_mode(Arm::alpha, true, true);
    case CommandId::alpha_closed_loop_without_collision_detection: return set_mode(Arm::alpha, true, false);
    case CommandId::alpha_open_loop_with_collision_detection: return set_mode(Arm::alpha, false, true);
    case CommandId::alpha_open_loop_without_collision_detection: return set_mode(Arm::alpha, false, false);
    case CommandId::beta_closed_loop_with_collision_detection: return set_mode(Arm::beta, true, true);
    case CommandId::beta_closed_loop_without_collision_detection: return set_mode(Arm::beta, true, false);
    case CommandId::beta_open_loop_with_collision_detection: return set_mode(Arm::beta, false, true);
    case CommandId::beta_open_loop_without_collision_detection: return set_mode(Arm::beta, false, false);
    case CommandId::switch_on_led:
    case CommandId::switch_off_led:
      led_ = c.id == CommandId::switch_on_led;
      led_off_at_.reset();
      return done(ResponseCode::accepted);
    case CommandId::switch_on_precise_move_alpha:
    case CommandId::switch_off_precise_move_alpha:
      arms_[Arm::alpha].precise = c.id == CommandId::switch_on_precise_move_alpha;
      return done(ResponseCode::accepted);
    case CommandId::switch_on_precise_move_beta:
    case CommandId::switch_off_precise_move_beta:
      arms_[Arm::beta].precise = c.id == CommandId::switch_on_precise_move_beta;
      return done(ResponseCode::accepted);
    case CommandId::get_raw_temperature:
      // The motors warm the board a little while they run.
      return done(ResponseCode::accepted, proto::U32Value{config_.raw_temperature + (moving() ? 12u : 0u)}.encode());

    case CommandId::collision_detected:
    case CommandId::start_firmware_upgrade:
    case CommandId::firmware_data: break;  // refused by check_device_request already
  }
  done(ResponseCode::invalid_command);
}

}  // namespace axon::fps::sim
