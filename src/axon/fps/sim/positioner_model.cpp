// PositionerModel: construction, power, simulated time and the motion of the arms.
#include "axon/fps/sim/positioner_model.hpp"

#include <algorithm>
#include <cmath>

namespace axon::fps::sim {

using protocol::StatusBit;

std::string_view to_string(RunState s) noexcept {
  switch (s) {
    case RunState::off: return "off";
    case RunState::booting: return "booting";
    case RunState::bootloader: return "bootloader";
    case RunState::application: return "application";
    case RunState::failed_boot: return "failed_boot";
  }
  return "?";
}

std::string_view to_string(Activity a) noexcept {
  switch (a) {
    case Activity::idle: return "idle";
    case Activity::go_to: return "go_to";
    case Activity::trajectory: return "trajectory";
    case Activity::datum_search: return "datum_search";
    case Activity::datum_calibration: return "datum_calibration";
    case Activity::motor_calibration: return "motor_calibration";
    case Activity::cogging_calibration: return "cogging_calibration";
  }
  return "?";
}

std::string_view to_string(HallFault f) noexcept {
  switch (f) {
    case HallFault::none: return "none";
    case HallFault::stuck: return "stuck";
    case HallFault::motor_dead: return "motor_dead";
  }
  return "?";
}

std::optional<HallFault> hall_fault_from(std::string_view name) noexcept {
  if (name == "dead") return HallFault::motor_dead;
  for (const HallFault f : {HallFault::none, HallFault::stuck, HallFault::motor_dead})
    if (name == to_string(f)) return f;
  return std::nullopt;
}

PositionerModel::PositionerModel(PositionerConfig config, SimTime now) : config_(std::move(config)), now_(now) {
  if (auto v = config_.validate(); !v) throw Exception(v.error());
  // The flash as the configuration describes it.
  for (Arm a : kArms) {
    flash_.calibration.motor[a] = config_.motors_calibrated;
    flash_.calibration.datum[a] = config_.datums_calibrated;
    flash_.calibration.cogging[a] = config_.cogging_calibrated;
    flash_.initialized[a] = config_.datums_initialized;
    arms_[a].theta = config_.start_position_deg[a];
  }
  flash_.calibration.holding_current = {{protocol::kDefaultHoldingCurrentAlpha, protocol::kDefaultHoldingCurrentBeta}};
  flash_.position_saved = config_.datums_initialized;
  flash_.main = flash_.backup = FirmwareSlot{config_.firmware, true, 0};
  flash_.main_booted = true;
  if (config_.sync_line_low_at_power_on) {
    enter_bootloader(now_);
  } else {
    start_application(now_);
  }
}

Result<PositionerModel> PositionerModel::make(PositionerConfig config, SimTime now) {
  AXON_TRY(config.validate());
  return PositionerModel(std::move(config), now);
}

// ---- time -----------------------------------------------------------------------------------

std::optional<SimTime> PositionerModel::next_event() const noexcept {
  std::optional<SimTime> next;
  const auto consider = [&](const std::optional<SimTime>& t) {
    if (t && (!next || *t < *next)) next = t;
  };
  consider(boot_done_at_);
  consider(bootloader_deadline_);
  consider(watchdog_at_);
  consider(led_off_at_);
  consider(hall_ready_at_);
  consider(sync_check_at_);
  for (Arm a : kArms) {
    const ArmState& s = arms_[a];
    if (!s.moving) continue;
    consider(s.collision_at);
    consider(s.phys.end());
  }
  return next;
}

Outbox PositionerModel::advance(SimTime now) {
  Outbox out;
  run_until(now, out);
  return out;
}

void PositionerModel::run_until(SimTime t, Outbox& out) {
  if (t < now_) t = now_;
  // Every event clears its own trigger, so this loop ends.
  for (auto next = next_event(); next && *next <= t; next = next_event()) {
    now_ = std::max(now_, *next);
    fire(now_, out);
  }
  now_ = t;
}

void PositionerModel::fire(SimTime t, Outbox& out) {
  const auto due = [&](std::optional<SimTime>& when) {
    if (!when || *when > t) return false;
    when.reset();
    return true;
  };
  if (due(boot_done_at_)) start_application(t);
  if (due(bootloader_deadline_)) {
    boot_.status.set(protocol::BootloaderBit::bootloader_timeout);
    boot_application(t, config_.boot_time);
  }
  if (due(watchdog_at_)) {
    // The new image never came up: the watchdog restores the last image that did.
    ++counters_.watchdog_resets;
    flash_.main = flash_.backup;
    flash_.main_booted = true;
    boot_application(t, config_.boot_time);
  }
  if (due(led_off_at_)) led_ = false;
  due(hall_ready_at_);
  // A collision with a hard stop, then arms reaching the ends of their paths.
  std::optional<Arm> hit;
  for (Arm a : kArms) {
    const ArmState& s = arms_[a];
    if (s.moving && s.collision_at && *s.collision_at <= t && (!hit || *s.collision_at < *arms_[*hit].collision_at)) {
      hit = a;
    }
  }
  if (hit) {
    collide(*hit, *arms_[*hit].collision_at, out);
    return;
  }
  for (Arm a : kArms) {
    if (arms_[a].moving && arms_[a].phys.end() <= t) finish_arm(a, arms_[a].phys.end());
  }
  if (due(sync_check_at_)) sync_recheck(out);
}

// ---- power ----------------------------------------------------------------------------------

void PositionerModel::power_off(SimTime now, bool save_position) {
  Outbox ignored;
  run_until(now, ignored);
  if (run_ == RunState::application) {
    const bool was_moving = moving();
    stop_motion(now_);
    if (save_position) {
      flash_.position_saved = true;
      flash_.position_estimated = was_moving;
      for (Arm a : kArms) {
        flash_.counter_error_deg[a] = arms_[a].datum_err + arms_[a].slip;
        flash_.initialized[a] = arms_[a].initialized;
      }
    } else {
      flash_.position_saved = false;
    }
  }
  run_ = RunState::off;
  boot_done_at_.reset();
  bootloader_deadline_.reset();
  watchdog_at_.reset();
  led_off_at_.reset();
  hall_ready_at_.reset();
  sync_check_at_.reset();
  led_ = false;
  upload_ = {};
  boot_ = {};
}

void PositionerModel::power_on(SimTime now, bool sync_line_low) {
  if (run_ != RunState::off) power_off(now);
  now_ = std::max(now_, now);
  if (sync_line_low) {
    enter_bootloader(now_);
  } else {
    boot_application(now_, config_.boot_time);
  }
}

void PositionerModel::power_cycle(SimTime now, bool sync_line_low) {
  power_off(now);
  power_on(now, sync_line_low);
}

void PositionerModel::enter_bootloader(SimTime t) {
  run_ = RunState::bootloader;
  boot_ = {};
  boot_.status.set(protocol::BootloaderBit::bootloader_init);
  // A main image that has proved it boots becomes the fallback for the next upgrade.
  if (flash_.main_booted && flash_.backup != flash_.main) {
    flash_.backup = flash_.main;
    boot_.status.set(protocol::BootloaderBit::bsettings_changed);
  }
  bootloader_deadline_ = t + config_.bootloader_timeout;
}

void PositionerModel::boot_application(SimTime t, SimDuration delay) {
  boot_.image.clear();
  boot_.image.shrink_to_fit();
  if (!flash_.main.bootable) {
    run_ = RunState::failed_boot;
    watchdog_at_ = t + config_.watchdog_timeout;
    return;
  }
  if (delay <= SimDuration::zero()) {
    start_application(t);
    return;
  }
  run_ = RunState::booting;
  boot_done_at_ = t + delay;
}

void PositionerModel::start_application(SimTime t) {
  run_ = RunState::application;
  flash_.main_booted = true;
  cal_ = flash_.calibration;
  activity_ = Activity::idle;
  upload_ = {};
  hall_on_ = true;
  hall_sleeping_ = false;
  hall_ready_at_.reset();
  led_ = true;
  led_off_at_ = t + config_.led_blink;
  const PerArm<std::int32_t> margins{{protocol::kDefaultCollisionMarginAlpha, protocol::kDefaultCollisionMarginBeta}};
  for (Arm a : kArms) {
    ArmState& s = arms_[a];
    const double theta = s.theta;
    s = ArmState{};
    s.theta = theta;
    s.speed_rpm = config_.default_speed_rpm;
    s.drive_current = config_.default_drive_current_percent;
    s.margin = margins[a];
    if (flash_.position_saved) {
      s.datum_err = flash_.counter_error_deg[a];
      s.initialized = flash_.initialized[a];
    } else {
      s.datum_err = -theta;  // the step counter starts from zero wherever the arm is
      s.initialized = false;
    }
  }
  position_restored_ = flash_.position_saved;
  position_estimated_ = flash_.position_saved && flash_.position_estimated;
}

// ---- sync line and faults ---------------------------------------------------------------------

Outbox PositionerModel::set_sync_line(bool high, SimTime now) {
  Outbox out;
  run_until(now, out);  // a look due before this change sees the level the line had
  const bool rising = high && !sync_high_;
  sync_high_ = high;
  if (rising && run_ == RunState::application && !sync_check_at_) {
    sync_check_at_ = now_ + config_.sync_recheck;
    run_until(now_, out);  // a recheck of zero looks at once
  }
  return out;
}

void PositionerModel::sync_recheck(Outbox& out) {
  if (run_ != RunState::application) return;
  if (!sync_high_) {
    ++counters_.sync_glitches;
    return;
  }
  ++counters_.sync_starts;
  const auto code = start_trajectory(now_);
  ++counters_.requests;
  if (code != protocol::ResponseCode::accepted) ++counters_.rejected;
  out.push_back(protocol::Message{
      protocol::Identifier{config_.id, protocol::number(protocol::CommandId::start_trajectory), 0, code}, {}});
}

Outbox PositionerModel::set_hall_fault(Arm arm, HallFault fault, SimTime now) {
  Outbox out;
  run_until(now, out);
  if (fault == HallFault::stuck && hall_fault_[arm] != HallFault::stuck) hall_stuck_deg_[arm] = hall_deg(arm);
  hall_fault_[arm] = fault;
  return out;
}

double PositionerModel::friction_current_percent(Arm a, double motor_rpm) const noexcept {
  const double level = friction_[a] ? std::max(0, *friction_[a]) : 0;
  const double stiction = config_.stiction_current_percent[a] + level;
  const double viscous = config_.viscous_current_percent_per_krpm[a] + level / 5.0;
  return stiction + viscous * std::abs(motor_rpm) / 1000.0;
}

Outbox PositionerModel::inject_collision(Arm arm, SimTime now) {
  Outbox out;
  run_until(now, out);
  if (run_ == RunState::application) collide(arm, now_, out);
  return out;
}

// ---- motion ---------------------------------------------------------------------------------

double PositionerModel::arm_speed(Arm a) const noexcept {
  return static_cast<double>(arms_[a].speed_rpm) * 6.0 / config_.gear_ratio;
}

double PositionerModel::max_arm_speed() const noexcept {
  return static_cast<double>(config_.max_speed_rpm) * 6.0 / config_.gear_ratio;
}

double PositionerModel::physical_at(Arm a, SimTime t) const noexcept {
  const ArmState& s = arms_[a];
  return s.moving ? s.phys.at(t) : s.theta;
}

double PositionerModel::belief_at(Arm a, SimTime t) const noexcept {
  const ArmState& s = arms_[a];
  if (!s.moving) return s.theta + s.datum_err + s.slip;
  return s.follows_hall ? s.phys.at(t) + s.err0 : s.cmd.at(t);
}

double PositionerModel::belief(Arm a) const noexcept { return belief_at(a, now_); }

double PositionerModel::reported_deg(Arm a) const noexcept { return belief(a) - cal_.offset_deg[a]; }

double PositionerModel::physical_deg(Arm a) const noexcept { return physical_at(a, now_); }

double PositionerModel::hall_deg(Arm a) const noexcept {
  if (hall_fault_[a] == HallFault::stuck) return hall_stuck_deg_[a];
  if (hall_unavailable()) return hall_frozen_[a];
  return physical_deg(a) + arms_[a].datum_err - cal_.offset_deg[a];
}

bool PositionerModel::hall_unavailable() const noexcept {
  return hall_sleeping_ || (hall_ready_at_ && now_ < *hall_ready_at_);
}

void PositionerModel::start_commanded(Arm a, ArmPath cmd) {
  ArmState& s = arms_[a];
  s.err0 = s.datum_err + s.slip;
  s.follows_hall = s.closed_loop;
  ArmPath raw = cmd.shifted(-s.err0);
  // A dead motor, or a stuck sensor the closed loop commutates by, leaves the arm where it is.
  const HallFault fault = hall_fault_[a];
  if ((fault == HallFault::motor_dead || (fault == HallFault::stuck && s.closed_loop)) && raw.end() > raw.start()) {
    ArmPath still(raw.start(), raw.at(raw.start()));
    still.point(raw.end(), raw.at(raw.start()));
    raw = std::move(still);
  }
  s.collision_at.reset();
  if (s.detection) {
    // The arm stops at the first contact; the path need not be clamped.
    s.collision_at = raw.first_outside(lower_stop(a), upper_stop(a));
    // Too much friction for the margin, or a sensor that sees no motion: the controller takes it
    // for a stall right after the start.
    const bool stalls = (friction_[a] && *friction_[a] > s.margin) || fault != HallFault::none;
    if (stalls && raw.end() > raw.start()) {
      const SimTime stall = raw.start() + std::min<SimDuration>(std::chrono::milliseconds(200), raw.end() - raw.start());
      if (!s.collision_at || stall < *s.collision_at) s.collision_at = stall;
    }
    s.phys = std::move(raw);
  } else {
    s.phys = raw.clamped(lower_stop(a), upper_stop(a), !s.closed_loop);
  }
  s.cmd = std::move(cmd);
  s.moving = true;
}

void PositionerModel::start_physical(Arm a, ArmPath phys) {
  ArmState& s = arms_[a];
  s.err0 = s.datum_err + s.slip;
  s.follows_hall = true;
  s.collision_at.reset();
  s.cmd = phys.shifted(s.err0);
  s.phys = std::move(phys);
  s.moving = true;
}

void PositionerModel::settle(Arm a, SimTime t) {
  ArmState& s = arms_[a];
  if (!s.moving) return;
  const double b = belief_at(a, t);
  s.theta = s.phys.at(t);
  s.slip = b - s.theta - s.datum_err;
  s.moving = false;
  s.cmd = {};
  s.phys = {};
  s.collision_at.reset();
}

void PositionerModel::stop_motion(SimTime t) {
  for (Arm a : kArms) settle(a, t);
  activity_ = Activity::idle;
  if (!hall_on_ && !hall_sleeping_) {
    for (Arm a : kArms) hall_frozen_[a] = hall_deg(a);
    hall_sleeping_ = true;
  }
}

void PositionerModel::finish_arm(Arm a, SimTime t) {
  settle(a, t);
  ArmState& s = arms_[a];
  const auto found_datum = [&] {
    s.theta = lower_stop(a);
    s.datum_err = cal_.zero_error_deg[a];
    s.slip = 0;
    s.initialized = true;
  };
  switch (activity_) {
    case Activity::datum_search: found_datum(); break;
    case Activity::datum_calibration:
      cal_.datum[a] = true;
      cal_.datum_error[a] = pending_spread_[a];
      cal_.zero_error_deg[a] = pending_zero_error_[a];
      found_datum();
      break;
    case Activity::motor_calibration:
      cal_.motor[a] = true;
      cal_.motor_error[a] = static_cast<std::int32_t>(noise() * 3.0);
      break;
    case Activity::cogging_calibration:
      cal_.cogging[a] = true;
      if (cal_.datum[a]) found_datum();
      break;
    case Activity::idle:
    case Activity::go_to:
    case Activity::trajectory: break;
  }
  if (!arms_[Arm::alpha].moving && !arms_[Arm::beta].moving) stop_motion(t);
}

void PositionerModel::collide(Arm a, SimTime t, Outbox& out) {
  stop_motion(t);
  arms_[a].collided = true;
  ++counters_.collisions;
  out.push_back(protocol::Message{
      protocol::Identifier{config_.id, protocol::number(protocol::CommandId::collision_detected), 0,
                           a == Arm::alpha ? protocol::ResponseCode::alpha_collision
                                           : protocol::ResponseCode::beta_collision},
      {}});
}

double PositionerModel::noise() noexcept {
  // splitmix64 over (seed, id, draw number): reproducible for a given configuration and history.
  std::uint64_t z = config_.seed * 0x9E3779B97F4A7C15ULL + (std::uint64_t{config_.id} << 32) + (++noise_counter_);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

// ---- observers ------------------------------------------------------------------------------

protocol::FirmwareVersion PositionerModel::running_version() const noexcept {
  return run_ == RunState::bootloader ? config_.bootloader : flash_.main.version;
}

protocol::PositionerStatus PositionerModel::status() const noexcept {
  protocol::PositionerStatus s;
  if (run_ != RunState::application) return s;
  const ArmState& al = arms_[Arm::alpha];
  const ArmState& be = arms_[Arm::beta];
  const bool hall_off = hall_unavailable();
  s.set(StatusBit::system_initialized);
  s.set(StatusBit::receiving_trajectory, upload_.receiving);
  const bool have = upload_.receiving || upload_.loaded;
  s.set(StatusBit::trajectory_alpha_received,
        have && upload_.points[Arm::alpha].size() == upload_.expected[Arm::alpha]);
  s.set(StatusBit::trajectory_beta_received, have && upload_.points[Arm::beta].size() == upload_.expected[Arm::beta]);
  s.set(StatusBit::low_power_after_move);
  s.set(StatusBit::displacement_completed, activity_ == Activity::idle);
  s.set(StatusBit::displacement_completed_alpha, !al.moving);
  s.set(StatusBit::displacement_completed_beta, !be.moving);
  s.set(StatusBit::collision_alpha, al.collided);
  s.set(StatusBit::collision_beta, be.collided);
  s.set(StatusBit::closed_loop_alpha, al.closed_loop);
  s.set(StatusBit::closed_loop_beta, be.closed_loop);
  s.set(StatusBit::collision_detect_alpha_disable, !al.detection);
  s.set(StatusBit::collision_detect_beta_disable, !be.detection);
  s.set(StatusBit::motor_calibration, activity_ == Activity::motor_calibration);
  s.set(StatusBit::motor_alpha_calibrated, cal_.motor[Arm::alpha]);
  s.set(StatusBit::motor_beta_calibrated, cal_.motor[Arm::beta]);
  s.set(StatusBit::datum_calibration, activity_ == Activity::datum_calibration);
  s.set(StatusBit::datum_alpha_calibrated, cal_.datum[Arm::alpha]);
  s.set(StatusBit::datum_beta_calibrated, cal_.datum[Arm::beta]);
  s.set(StatusBit::datum_initialization, activity_ == Activity::datum_search);
  s.set(StatusBit::datum_alpha_initialized, al.initialized);
  s.set(StatusBit::datum_beta_initialized, be.initialized);
  s.set(StatusBit::hall_alpha_disable, hall_off || (!al.closed_loop && !al.detection));
  s.set(StatusBit::hall_beta_disable, hall_off || (!be.closed_loop && !be.detection));
  s.set(StatusBit::cogging_calibration, activity_ == Activity::cogging_calibration);
  s.set(StatusBit::cogging_alpha_calibrated, cal_.cogging[Arm::alpha]);
  s.set(StatusBit::cogging_beta_calibrated, cal_.cogging[Arm::beta]);
  s.set(StatusBit::estimated_position, position_estimated_);
  s.set(StatusBit::position_restored, position_restored_);
  s.set(StatusBit::precise_move_alpha, al.precise);
  s.set(StatusBit::precise_move_beta, be.precise);
  s.set(StatusBit::switch_off_hall_after_move, !hall_on_);
  return s;
}

}  // namespace axon::fps::sim
