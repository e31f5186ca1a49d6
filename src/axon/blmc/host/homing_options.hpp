// What homing is asked to do and what it found per motor (homing.hpp runs it), apart from the
// controller so that the blocking API (motor_board.hpp) can name them without the event loop.
#pragma once

#include <array>
#include <cstdint>

namespace axon::blmc::host {

struct HomingOptions {
  std::array<bool, 2> motors{true, true};
  double speed_rev_s = 0.5;     // motor revolutions per second (sign: direction)
  double kp = 2.0;              // A per rev
  double kd = 0.02;             // A per (rev/s)
  double max_current_a = 0.5;   // homing never asks for more
  double max_travel_rev = 2.0;  // an index comes once per motor revolution
};

struct MotorHoming {
  enum class State : std::uint8_t { idle, searching, found, failed };
  State state = State::idle;
  double start_rev = 0;
  double index_rev = 0;  // the offset (valid when found)
};
const char* to_string(MotorHoming::State s) noexcept;

}  // namespace axon::blmc::host
