#include "axon/fps/host/positioner.hpp"

#include "axon/core/wakeup.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace axon::fps::host {

using protocol::CommandId;
using protocol::PositionerStatus;
using protocol::StatusBit;

namespace {

double seconds(core::Duration d) { return std::chrono::duration<double>(d).count(); }

ArmAngles from_wire(const protocol::ArmPositions& p) { return {p.alpha.degrees(), p.beta.degrees()}; }

Result<protocol::ArmPositions> to_wire(ArmAngles a, std::uint16_t id, std::string_view what) {
  auto alpha = protocol::Angle::from_degrees(a.alpha);
  if (!alpha) return Error(alpha.error().code, fmt::format("positioner {} {} alpha {}", id, what, alpha.error().detail));
  auto beta = protocol::Angle::from_degrees(a.beta);
  if (!beta) return Error(beta.error().code, fmt::format("positioner {} {} beta {}", id, what, beta.error().detail));
  return protocol::ArmPositions{alpha.value(), beta.value()};
}

Result<void> need_one_arm(Arm arm, std::uint16_t id, std::string_view what) {
  if (arm == Arm::both) {
    return Error(HostErrc::invalid_argument, fmt::format("positioner {} {}: pick alpha or beta", id, what));
  }
  return ok();
}

CommandId per_arm(Arm arm, CommandId both, CommandId alpha, CommandId beta) {
  return arm == Arm::both ? both : arm == Arm::alpha ? alpha : beta;
}

bool has_arm_flags(const PositionerStatus& st, Arm arm, StatusBit alpha, StatusBit beta) {
  const bool a = st.has(alpha), b = st.has(beta);
  return arm == Arm::both ? (a && b) : arm == Arm::alpha ? a : b;
}

}  // namespace

const char* to_string(Arm a) noexcept {
  switch (a) {
    case Arm::alpha: return "alpha";
    case Arm::beta: return "beta";
    case Arm::both: return "both";
  }
  return "?";
}

const char* to_string(UploadResult::Stage s) noexcept {
  switch (s) {
    case UploadResult::Stage::not_sent: return "not sent";
    case UploadResult::Stage::new_trajectory: return "SEND_NEW_TRAJECTORY";
    case UploadResult::Stage::points: return "SEND_TRAJECTORY_DATA";
    case UploadResult::Stage::data_end: return "TRAJECTORY_DATA_END";
    case UploadResult::Stage::done: return "done";
  }
  return "?";
}

std::string UploadResult::describe() const {
  if (ok()) return fmt::format("loaded ({} points)", points_accepted);
  const std::string why = error ? error->message() : std::string("no reason recorded");
  if (stage == Stage::points && arm && point) {
    // A response code means the robot said no; anything else (timeout, lost bus) means the point
    // was never confirmed either way.
    const bool refused = error && error->code.category() == protocol::response_category();
    return fmt::format("{} point {} {} ({} points accepted before it): {}", to_string(*arm), *point,
                       refused ? "refused" : "not confirmed", points_accepted, why);
  }
  return fmt::format("{} failed: {}", to_string(stage), why);
}

Positioner::Positioner(CommandClient& client, std::uint16_t id, PositionerOptions options, MotionGate* gate)
    : client_(&client), id_(id), options_(std::move(options)), gate_(gate) {}

Result<void> Positioner::still_free() const {
  const MotionLock* lock = client_->motion_lock();
  if (lock == nullptr || !lock->locked()) return ok();
  return lock->interrupted(id_);
}

Result<void> Positioner::firmware_gate(CommandId c) const {
  if (!firmware_ || firmware_->is_bootloader()) return ok();
  auto why = protocol::firmware_lacks(c, *firmware_, options_.firmware_history);
  if (c == CommandId::get_status && why.empty()) why = protocol::status_layout_unknown(*firmware_);
  if (why.empty()) return ok();
  return Error(HostErrc::firmware_lacks, fmt::format("positioner {}: {}; not sent", id_, why));
}

asio::awaitable<Result<void>> Positioner::simple(CommandId c) {
  if (auto g = firmware_gate(c); !g) co_return g.error();
  auto r = co_await client_->request(id_, c);
  if (!r) co_return r.error();
  co_return ok();
}

// --- reads ---------------------------------------------------------------------------------------

asio::awaitable<Result<protocol::FirmwareVersion>> Positioner::read_firmware_version() {
  auto r = co_await client_->request(id_, CommandId::get_firmware_version);
  if (!r) co_return r.error();
  auto v = protocol::FirmwareVersion::decode(r.value().payload, options_.version_byte_order);
  if (!v)
    co_return Error(v.error().code, fmt::format("positioner {}: firmware version: {} (is the byte order option right?)", id_,
                                                v.error().detail));
  firmware_ = v.value();
  co_return *firmware_;
}

asio::awaitable<Result<PositionerStatus>> Positioner::read_status() {
  if (auto g = firmware_gate(CommandId::get_status); !g) co_return g.error();
  auto r = co_await client_->request(id_, CommandId::get_status);
  if (!r) co_return r.error();
  if (r.value().payload.size() == protocol::BootloaderStatus::kWireSize) {
    auto b = client_->decode_reply<protocol::BootloaderStatusReply>(r.value());
    if (!b) co_return b.error();
    boot_status_ = b.value().status;
    co_return Error(HostErrc::not_ready, fmt::format("positioner {} runs its bootloader (status {})", id_,
                                                     boot_status_->to_string()));
  }
  auto s = client_->decode_reply<protocol::StatusReply>(r.value());
  if (!s) co_return s.error();
  status_ = s.value().status;
  co_return *status_;
}

asio::awaitable<Result<protocol::BootloaderStatus>> Positioner::read_bootloader_status() {
  auto r = co_await client_->request(id_, CommandId::get_status);
  if (!r) co_return r.error();
  if (r.value().payload.size() == PositionerStatus::kWireSize) {
    auto s = client_->decode_reply<protocol::StatusReply>(r.value());
    if (s) status_ = s.value().status;
    co_return Error(HostErrc::not_in_bootloader, fmt::format("positioner {}", id_));
  }
  auto b = client_->decode_reply<protocol::BootloaderStatusReply>(r.value());
  if (!b) co_return b.error();
  boot_status_ = b.value().status;
  co_return *boot_status_;
}

asio::awaitable<Result<ArmAngles>> Positioner::read_position() {
  auto r = co_await client_->call<CommandId::get_current_position>(id_);
  if (!r) co_return r.error();
  co_return from_wire(r.value());
}

asio::awaitable<Result<ArmAngles>> Positioner::read_offsets() {
  auto r = co_await client_->call<CommandId::get_offsets>(id_);
  if (!r) co_return r.error();
  co_return from_wire(r.value());
}

asio::awaitable<Result<ArmAngles>> Positioner::read_hall_position() {
  auto r = co_await client_->call<CommandId::get_hall_position>(id_);
  if (!r) co_return r.error();
  co_return from_wire(r.value());
}

asio::awaitable<Result<protocol::ArmValues>> Positioner::read_datum_calibration_error() {
  co_return co_await client_->call<CommandId::get_datum_calibration_error>(id_);
}
asio::awaitable<Result<protocol::ArmValues>> Positioner::read_motor_calibration_error() {
  co_return co_await client_->call<CommandId::get_motor_calibration_error>(id_);
}
asio::awaitable<Result<protocol::ArmValues>> Positioner::read_currents() {
  co_return co_await client_->call<CommandId::get_currents>(id_);
}
asio::awaitable<Result<protocol::ArmValues>> Positioner::read_torques() {
  co_return co_await client_->call<CommandId::get_torques>(id_);
}

asio::awaitable<Result<protocol::PositionAndValue>> Positioner::read_position_and_current(Arm arm) {
  if (auto a = need_one_arm(arm, id_, "position and current"); !a) co_return a.error();
  if (arm == Arm::alpha) co_return co_await client_->call<CommandId::get_position_and_current_alpha>(id_);
  co_return co_await client_->call<CommandId::get_position_and_current_beta>(id_);
}

asio::awaitable<Result<protocol::PositionAndValue>> Positioner::read_position_and_torque(Arm arm) {
  if (auto a = need_one_arm(arm, id_, "position and torque"); !a) co_return a.error();
  if (arm == Arm::alpha) co_return co_await client_->call<CommandId::get_position_and_torque_alpha>(id_);
  co_return co_await client_->call<CommandId::get_position_and_torque_beta>(id_);
}

asio::awaitable<Result<protocol::ArmCurrents>> Positioner::read_holding_current() {
  co_return co_await client_->call<CommandId::get_holding_current>(id_);
}

asio::awaitable<Result<std::uint32_t>> Positioner::read_raw_temperature() {
  auto r = co_await client_->call<CommandId::get_raw_temperature>(id_);
  if (!r) co_return r.error();
  co_return r.value().value;
}

asio::awaitable<Result<std::uint32_t>> Positioner::read_cogging_vector_length() {
  auto r = co_await client_->call<CommandId::get_cogging_vector_length>(id_);
  if (!r) co_return r.error();
  co_return r.value().value;
}

asio::awaitable<Result<protocol::ArmValues>> Positioner::read_cogging(CoggingTable table, std::uint32_t alpha_index,
                                                                      std::uint32_t beta_index) {
  const protocol::ArmIndices idx{alpha_index, beta_index};
  switch (table) {
    case CoggingTable::positive: co_return co_await client_->call<CommandId::get_cogging_positive>(id_, idx);
    case CoggingTable::negative: co_return co_await client_->call<CommandId::get_cogging_negative>(id_, idx);
    case CoggingTable::angles: break;
  }
  co_return co_await client_->call<CommandId::get_cogging_angles>(id_, idx);
}

// --- settings ------------------------------------------------------------------------------------

asio::awaitable<Result<void>> Positioner::set_speed(std::int64_t alpha_rpm, std::int64_t beta_rpm) {
  auto a = protocol::MotorSpeed::from_rpm(alpha_rpm);
  if (!a) co_return a.error();
  auto b = protocol::MotorSpeed::from_rpm(beta_rpm);
  if (!b) co_return b.error();
  auto r = co_await client_->call<CommandId::set_speed>(id_, {a.value(), b.value()});
  if (!r) co_return r.error();
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_current(std::int64_t alpha_percent, std::int64_t beta_percent) {
  auto a = protocol::CurrentPercent::from_percent(alpha_percent);
  if (!a) co_return a.error();
  auto b = protocol::CurrentPercent::from_percent(beta_percent);
  if (!b) co_return b.error();
  auto r = co_await client_->call<CommandId::set_current>(id_, {a.value(), b.value()});
  if (!r) co_return r.error();
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_holding_current(std::int64_t alpha_percent, std::int64_t beta_percent) {
  auto a = protocol::CurrentPercent::from_percent(alpha_percent);
  if (!a) co_return a.error();
  auto b = protocol::CurrentPercent::from_percent(beta_percent);
  if (!b) co_return b.error();
  auto r = co_await client_->call<CommandId::set_holding_current>(id_, {a.value(), b.value()});
  if (!r) co_return r.error();
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_collision_margin(std::int64_t alpha, std::int64_t beta) {
  auto a = protocol::CollisionMargin::from_value(alpha);
  if (!a) co_return a.error();
  auto b = protocol::CollisionMargin::from_value(beta);
  if (!b) co_return b.error();
  auto r = co_await client_->call<CommandId::set_collision_margin>(id_, {a.value(), b.value()});
  if (!r) co_return r.error();
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_offsets(ArmAngles offsets) {
  auto p = to_wire(offsets, id_, "offsets");
  if (!p) co_return p.error();
  auto r = co_await client_->call<CommandId::set_offsets>(id_, p.value());
  if (!r) co_return r.error();
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_position(ArmAngles position) {
  auto p = to_wire(position, id_, "position");
  if (!p) co_return p.error();
  auto r = co_await client_->call<CommandId::set_current_position>(id_, p.value());
  if (!r) co_return r.error();
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_loop(Arm arm, Loop loop, bool collision_detection) {
  // 118..121 alpha, 122..125 beta: closed+detect, closed, open+detect, open.
  const unsigned offset = (loop == Loop::open ? 2u : 0u) + (collision_detection ? 0u : 1u);
  if (arm != Arm::beta) {
    auto r = co_await simple(static_cast<CommandId>(118 + offset));
    if (!r) co_return r;
  }
  if (arm != Arm::alpha) co_return co_await simple(static_cast<CommandId>(122 + offset));
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_precise_move(Arm arm, bool on) {
  if (arm != Arm::beta) {
    auto r = co_await simple(on ? CommandId::switch_on_precise_move_alpha : CommandId::switch_off_precise_move_alpha);
    if (!r) co_return r;
  }
  if (arm != Arm::alpha) {
    co_return co_await simple(on ? CommandId::switch_on_precise_move_beta : CommandId::switch_off_precise_move_beta);
  }
  co_return ok();
}

asio::awaitable<Result<void>> Positioner::set_led(bool on) {
  co_return co_await simple(on ? CommandId::switch_on_led : CommandId::switch_off_led);
}

asio::awaitable<Result<void>> Positioner::set_hall(bool on) {
  co_return co_await simple(on ? CommandId::switch_on_hall : CommandId::switch_off_hall);
}

// --- motion --------------------------------------------------------------------------------------

asio::awaitable<Result<void>> Positioner::abort() { co_return co_await simple(CommandId::trajectory_abort); }
asio::awaitable<Result<void>> Positioner::stop() { co_return co_await simple(CommandId::stop_trajectory); }

asio::awaitable<Result<protocol::ArmTimes>> Positioner::start_goto(ArmAngles position, bool relative) {
  auto p = to_wire(position, id_, relative ? "relative move" : "absolute move");
  if (!p) co_return p.error();
  if (relative) co_return co_await client_->call<CommandId::go_to_relative_position>(id_, p.value());
  co_return co_await client_->call<CommandId::go_to_absolute_position>(id_, p.value());
}

asio::awaitable<Result<MoveResult>> Positioner::goto_absolute(ArmAngles target) { return move(target, false); }
asio::awaitable<Result<MoveResult>> Positioner::goto_relative(ArmAngles delta) { return move(delta, true); }

asio::awaitable<Result<MoveResult>> Positioner::move(ArmAngles value, bool relative) {
  MoveResult out;
  out.target = value;
  if (relative) {
    auto start = co_await read_position();
    if (!start) co_return start.error();
    out.target = {start.value().alpha + value.alpha, start.value().beta + value.beta};
  }
  auto eta = co_await start_goto(value, relative);
  if (!eta) co_return eta.error();
  out.eta = eta.value();
  const auto started = core::steady_now();
  const auto eta_d = std::chrono::duration_cast<core::Duration>(
      std::chrono::duration<double>(std::max(out.eta.alpha.seconds(), out.eta.beta.seconds())));
  // The move has finished once the robot reports DISPLACEMENT_COMPLETED after having been seen
  // moving, or after its own ETA (a short move may end between two polls).
  bool seen_moving = false;
  auto done = [&](const PositionerStatus& st) {
    if (!st.idle()) {
      seen_moving = true;
      return false;
    }
    return seen_moving || core::steady_now() - started >= eta_d;
  };
  auto st = co_await watch_motion(done, eta_d + options_.move_margin, relative ? "relative move" : "absolute move");
  if (!st) co_return st.error();
  auto reached = co_await read_position();
  if (!reached) co_return reached.error();
  out.reached = reached.value();
  const double da = std::abs(out.reached.alpha - out.target.alpha), db = std::abs(out.reached.beta - out.target.beta);
  if (da > options_.position_tolerance || db > options_.position_tolerance) {
    co_return Error(HostErrc::position_mismatch,
                    fmt::format("positioner {}: reached alpha {:.4f} beta {:.4f} deg, target alpha {:.4f} beta {:.4f} "
                                "(tolerance {} deg)",
                                id_, out.reached.alpha, out.reached.beta, out.target.alpha, out.target.beta,
                                options_.position_tolerance));
  }
  co_return out;
}

asio::awaitable<Result<PositionerStatus>> Positioner::wait_until_idle(core::Duration timeout) {
  co_return co_await wait_for([](const PositionerStatus& st) { return st.idle(); }, timeout, "wait until idle", false);
}

asio::awaitable<Result<PositionerStatus>> Positioner::wait_for(std::function<bool(const PositionerStatus&)> done,
                                                               core::Duration timeout, std::string what, bool motion) {
  const auto deadline = core::steady_now() + timeout;
  for (;;) {
    if (motion) {
      if (auto g = still_free(); !g) co_return g.error();
    }
    auto st = co_await read_status();
    if (!st) co_return st.error();
    if (st.value().collided()) {
      if (gate_) gate_->collision_seen(id_, st.value());
      co_return Error(HostErrc::collision,
                      fmt::format("positioner {} during {}: {}", id_, what, st.value().to_string()));
    }
    if (done(st.value())) co_return st.value();
    const auto t = core::steady_now();
    if (t >= deadline) {
      co_return Error(HostErrc::timeout, fmt::format("positioner {}: {} not finished after {:.1f} s (status {})", id_,
                                                     what, seconds(timeout), st.value().to_string()));
    }
    co_await core::sleep_for(std::min<core::Duration>(options_.poll_interval, deadline - t));
  }
}

asio::awaitable<Result<PositionerStatus>> Positioner::run_step(CommandId c, core::Duration timeout,
                                                               std::function<bool(const PositionerStatus&)> done,
                                                               std::string what) {
  if (auto r = co_await simple(c); !r) co_return r.error();
  co_return co_await watch_motion(std::move(done), timeout, std::move(what));
}

asio::awaitable<Result<PositionerStatus>> Positioner::watch_motion(std::function<bool(const PositionerStatus&)> done,
                                                                   core::Duration timeout, std::string what) {
  auto st = co_await wait_for(std::move(done), timeout, std::move(what));
  // Given up on (no end in time, no status replies, the bus lost): the robot may still be moving,
  // so it is stopped rather than left unwatched. A collision or a lock has stopped it already.
  if (!st && st.error() != HostErrc::collision && st.error() != HostErrc::locked) {
    if (auto aborted = co_await abort(); !aborted)
      co_return Error(st.error().code, fmt::format("{}; TRAJECTORY_ABORT not sent: {}", st.error().detail, aborted.error().message()));
    co_return Error(st.error().code, fmt::format("{}; TRAJECTORY_ABORT sent to it", st.error().detail));
  }
  co_return st;
}

asio::awaitable<Result<PositionerStatus>> Positioner::go_to_datums(Arm arm) {
  const auto c = per_arm(arm, CommandId::go_to_datums, CommandId::go_to_datum_alpha, CommandId::go_to_datum_beta);
  co_return co_await run_step(
      c, options_.datum_timeout,
      [arm](const PositionerStatus& st) {
        return st.idle() && !st.has(StatusBit::datum_initialization) &&
               has_arm_flags(st, arm, StatusBit::datum_alpha_initialized, StatusBit::datum_beta_initialized);
      },
      fmt::format("datum search ({})", to_string(arm)));
}

asio::awaitable<Result<PositionerStatus>> Positioner::calibrate_motors(Arm arm) {
  const auto c =
      per_arm(arm, CommandId::calibrate_motors, CommandId::calibrate_motor_alpha, CommandId::calibrate_motor_beta);
  co_return co_await run_step(
      c, options_.motor_calibration_timeout,
      [arm](const PositionerStatus& st) {
        return st.idle() && !st.has(StatusBit::motor_calibration) &&
               has_arm_flags(st, arm, StatusBit::motor_alpha_calibrated, StatusBit::motor_beta_calibrated);
      },
      fmt::format("motor calibration ({})", to_string(arm)));
}

asio::awaitable<Result<PositionerStatus>> Positioner::calibrate_datums(Arm arm) {
  const auto c =
      per_arm(arm, CommandId::calibrate_datum, CommandId::calibrate_datum_alpha, CommandId::calibrate_datum_beta);
  co_return co_await run_step(
      c, options_.datum_calibration_timeout,
      [arm](const PositionerStatus& st) {
        return st.idle() && !st.has(StatusBit::datum_calibration) &&
               has_arm_flags(st, arm, StatusBit::datum_alpha_calibrated, StatusBit::datum_beta_calibrated);
      },
      fmt::format("datum calibration ({})", to_string(arm)));
}

asio::awaitable<Result<PositionerStatus>> Positioner::calibrate_cogging(Arm arm) {
  const auto c = per_arm(arm, CommandId::calibrate_cogging, CommandId::calibrate_cogging_alpha,
                         CommandId::calibrate_cogging_beta);
  co_return co_await run_step(
      c, options_.cogging_calibration_timeout,
      [arm](const PositionerStatus& st) {
        return st.idle() && !st.has(StatusBit::cogging_calibration) &&
               has_arm_flags(st, arm, StatusBit::cogging_alpha_calibrated, StatusBit::cogging_beta_calibrated);
      },
      fmt::format("cogging calibration ({})", to_string(arm)));
}

asio::awaitable<Result<void>> Positioner::save_calibration() { co_return co_await simple(CommandId::save_calibration); }

asio::awaitable<Result<CalibrationReport>> Positioner::calibrate(CalibrationPlan plan) {
  CalibrationReport report;
  if (plan.motors) {
    if (auto r = co_await calibrate_motors(plan.arm); !r) co_return r.error();
    auto e = co_await read_motor_calibration_error();
    if (!e) co_return e.error();
    report.motor_error = e.value();
  }
  if (plan.datums) {
    if (auto r = co_await calibrate_datums(plan.arm); !r) co_return r.error();
    auto e = co_await read_datum_calibration_error();
    if (!e) co_return e.error();
    report.datum_error = e.value();
  }
  if (plan.cogging) {
    if (auto r = co_await calibrate_cogging(plan.arm); !r) co_return r.error();
  }
  if (plan.save) {
    if (auto r = co_await save_calibration(); !r) co_return r.error();
    report.saved = true;
  }
  auto st = co_await read_status();
  if (!st) co_return st.error();
  report.final_status = st.value();
  co_return report;
}

asio::awaitable<UploadResult> Positioner::upload_trajectory(const protocol::Trajectory& trajectory) {
  UploadResult out;
  const std::vector<protocol::Request> reqs = trajectory.requests();  // new, points..., end
  out.stage = UploadResult::Stage::new_trajectory;
  if (auto r = co_await client_->request(id_, reqs.front().command, reqs.front().payload); !r) {
    if (r.error() == HostErrc::locked) out.stage = UploadResult::Stage::not_sent;  // refused before sending
    out.error = r.error();
    co_return out;
  }
  out.stage = UploadResult::Stage::points;
  const std::span<const protocol::Request> points(reqs.data() + 1, reqs.size() - 2);
  auto p = co_await client_->pipeline(id_, points, options_.trajectory_window);
  out.points_accepted = p.accepted;
  if (!p.ok()) {
    const std::size_t i = *p.failed_index, n_alpha = trajectory.alpha().size();
    out.arm = i < n_alpha ? Arm::alpha : Arm::beta;
    out.point = i < n_alpha ? i : i - n_alpha;
    out.error = p.error;
    co_return out;
  }
  out.stage = UploadResult::Stage::data_end;
  if (auto r = co_await client_->request(id_, reqs.back().command, reqs.back().payload); !r) {
    out.error = r.error();
    co_return out;
  }
  out.stage = UploadResult::Stage::done;
  co_return out;
}

}  // namespace axon::fps::host
