#include "axon/blmc/host/homing.hpp"

#include "axon/blmc/host/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace axon::blmc::host {

const char* to_string(MotorHoming::State s) noexcept {
  switch (s) {
    case MotorHoming::State::idle: return "idle";
    case MotorHoming::State::searching: return "searching";
    case MotorHoming::State::found: return "found";
    case MotorHoming::State::failed: return "failed";
  }
  return "?";
}

namespace {
void check_homing(const HomingOptions& o) {
  auto bad = [](const char* what, double v) {
    throw Exception(Error(HostErrc::invalid_argument, fmt::format("homing: {}, got {}", what, v)));
  };
  if (!std::isfinite(o.speed_rev_s) || o.speed_rev_s == 0) bad("speed must not be 0 (its sign gives the direction)", o.speed_rev_s);
  if (!std::isfinite(o.kp) || o.kp <= 0) bad("kp must be > 0", o.kp);
  if (!std::isfinite(o.kd) || o.kd < 0) bad("kd must be >= 0", o.kd);
  if (!std::isfinite(o.max_current_a) || o.max_current_a <= 0) bad("current limit must be > 0 A", o.max_current_a);
  if (!std::isfinite(o.max_travel_rev) || o.max_travel_rev <= 0) bad("travel must be > 0 rev", o.max_travel_rev);
}
}  // namespace

HomingController::HomingController(std::size_t boards, HomingOptions options)
    : options_(options), motors_(boards * 2), index_seen_(boards * 2, 0) {
  check_homing(options_);
}

bool HomingController::all_found() const noexcept {
  return std::all_of(motors_.begin(), motors_.end(), [](const MotorHoming& m) {
    return m.state == MotorHoming::State::found || m.state == MotorHoming::State::idle;
  });
}

void HomingController::start(const ControlInput& in) noexcept {
  t0_ = in.now;
  for (std::size_t b = 0; b < in.boards.size() && b * 2 < motors_.size(); ++b) {
    const auto& m = in.boards[b];
    const double pos[2] = {m.position.value.motor1, m.position.value.motor2};
    for (std::size_t k = 0; k < 2; ++k) {
      auto& h = motors_[b * 2 + k];
      h.start_rev = pos[k];
      h.state = options_.motors[k] ? MotorHoming::State::searching : MotorHoming::State::idle;
      index_seen_[b * 2 + k] = m.index[k].count;
    }
  }
}

void HomingController::update(const ControlInput& in, std::span<MotorPair> currents) noexcept {
  const double t = std::chrono::duration<double>(in.now - t0_).count();
  bool busy = false;
  for (std::size_t b = 0; b < in.boards.size() && b * 2 < motors_.size(); ++b) {
    const auto& m = in.boards[b];
    const double pos[2] = {m.position.value.motor1, m.position.value.motor2};
    const double vel[2] = {krpm_to_rev_per_s(m.velocity.value.motor1), krpm_to_rev_per_s(m.velocity.value.motor2)};
    double out[2] = {0, 0};
    for (std::size_t k = 0; k < 2; ++k) {
      auto& h = motors_[b * 2 + k];
      double target = pos[k];
      double target_v = 0;
      switch (h.state) {
        case MotorHoming::State::idle: continue;
        case MotorHoming::State::searching: {
          if (m.index[k].count > index_seen_[b * 2 + k]) {
            h.index_rev = m.index[k].value;
            h.state = MotorHoming::State::found;
            target = h.index_rev;
            break;
          }
          const double travel = options_.speed_rev_s * t;
          if (std::abs(travel) > options_.max_travel_rev) {
            h.state = MotorHoming::State::failed;
            continue;  // zero current
          }
          target = h.start_rev + travel;
          target_v = options_.speed_rev_s;
          busy = true;
          break;
        }
        case MotorHoming::State::found: target = h.index_rev; break;
        case MotorHoming::State::failed: continue;
      }
      const double c = options_.kp * (target - pos[k]) + options_.kd * (target_v - vel[k]);
      out[k] = std::clamp(c, -options_.max_current_a, options_.max_current_a);
    }
    currents[b] = {out[0], out[1]};
  }
  if (!busy) done_.store(true, std::memory_order_release);
}

}  // namespace axon::blmc::host
