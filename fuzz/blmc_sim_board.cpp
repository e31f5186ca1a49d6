// Fuzzes the simulated blmc board's firmware with arbitrary frames, time steps, faults, power
// cycles and shaft states.
//
// Input: operations, each led by one byte (op % 4):
//   0  a frame: one byte picks the identifier (values below 0x0A are the host's messages, the rest
//      become 0x0A..0x7FF or, with op bit 2, an extended identifier), one byte the length (% 10,
//      lengths above 8 are rejected by can::Frame and skipped), then that many payload bytes
//   1  time step: one byte of milliseconds (x 16 when op bit 2 is set)
//   2  fault: one byte (kind % 5; bit 4 a one-second cause, bit 5 persistent); op bit 2 power-cycles instead
//   3  shaft state of a motor: one byte (bit 0 motor), one byte position, one byte velocity
// Nothing may crash, every frame the board sends must decode as a board message (a status with
// the undocumented error code 6 decodes to ProtocolErrc::unknown_error_code, and only after that
// fault was injected), and the motors' state must stay finite with readings within +-100
// revolutions.
#include "axon/blmc/protocol/error.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/sim/board.hpp"
#include "axon/can/frame.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

using namespace axon;
using namespace axon::blmc;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sim::BoardConfig config;
  config.alignment_time = std::chrono::milliseconds(20);
  config.over_current_trip_a = 15;
  sim::Board board(config);
  sim::BoardTime now{0};
  std::vector<can::Frame> out;
  std::size_t i = 0;
  bool undocumented = false;  // the undocumented error code was injected (it stays latched)
  const auto next = [&]() -> std::uint8_t { return i < size ? data[i++] : 0; };
  while (i < size) {
    const std::uint8_t op = next();
    switch (op % 4) {
      case 0: {
        const std::uint8_t pick = next();
        const std::size_t len = next() % 10;
        std::uint8_t bytes[9] = {};
        for (std::size_t k = 0; k < len; ++k) bytes[k] = next();
        std::uint32_t id = pick < 0x0A ? pick : 0x0A + (pick * 8u) % 0x7F6u;
        const auto fmt = (op & 4) != 0 ? can::IdFormat::extended : can::IdFormat::standard;
        if ((op & 4) != 0) id |= 0x10000u;
        auto f = can::Frame::data(id, fmt, std::span<const std::uint8_t>(bytes, len));
        if (f) (void)board.receive(f.value(), now);
        break;
      }
      case 1:
        now += std::chrono::milliseconds(next()) * ((op & 4) != 0 ? 16 : 1);
        break;
      case 2: {
        const std::uint8_t b = next();
        if ((op & 4) != 0) {
          board.power_cycle();
        } else {
          undocumented = undocumented || static_cast<sim::FaultKind>(b % 5) == sim::FaultKind::undocumented;
          board.inject(static_cast<sim::FaultKind>(b % 5), (b & 16) != 0 ? std::chrono::seconds(1) : sim::BoardTime{0},
                       (b & 32) != 0);
        }
        break;
      }
      case 3: {
        const std::uint8_t m = next() & 1;
        const double pos = (static_cast<double>(next()) - 128.0) * 0.78;
        const double vel = (static_cast<double>(next()) - 128.0) * 2.0;
        board.motor(m).set_state(pos, vel);
        break;
      }
    }
    out.clear();
    board.advance(now, out);
    for (const auto& f : out) {
      const auto decoded = protocol::decode_from_board(f);
      require(decoded.has_value() || (undocumented && decoded.error().code == protocol::ProtocolErrc::unknown_error_code));
    }
    for (std::size_t m = 0; m < 2; ++m) {
      const auto& motor = board.motor(m);
      require(std::isfinite(motor.continuous_position_rev()) && std::isfinite(motor.velocity_rev_s()));
      require(motor.position_rev() >= -100.0 && motor.position_rev() < 100.0);
      require(std::abs(motor.current_a()) <= motor.config().current_limit_a);
    }
  }
  return 0;
}
