// Fuzzes the simulated positioner's firmware model with arbitrary request sequences, time steps,
// power cycles, sync line edges and forced collisions.
//
// Input: byte 0 picks the starting state (bit 0 motors uncalibrated, bit 1 datums uncalibrated,
// bit 2 datum lost, bit 3 start in the bootloader, bit 4 read an empty 112 as a get, bit 5 cogging
// uncalibrated). Then operations, each led by one byte (op % 8):
//   0..3  a request: command number, flags (bit 0 broadcast, bit 1 addressed to another robot,
//         bits 2..7 uid), length (% 9), that many payload bytes
//   4     time step: two bytes (little-endian) in milliseconds, or in seconds when op bit 3 is set
//   5     power: one byte (bit 0 sync line low, bit 1 lose the position, bit 2 off only)
//   6     sync line: high when op bit 3 is set, else low
//   7     forced collision: one byte (bit 0: beta)
// Nothing may crash, and everything the robot sends must be a well-formed frame from its own id
// whose accepted replies have the size the command table declares.
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/sim/positioner_model.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

using namespace axon::fps;
using namespace axon::fps::sim;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

void check(const PositionerModel& m, const Outbox& out) {
  for (const auto& msg : out) {
    require(msg.id.positioner == m.id());
    require(msg.id.uid <= protocol::kMaxUid);
    require(protocol::to_frame(msg).has_value());
    const auto* info = protocol::find_command(msg.id.command);
    if (info == nullptr || msg.id.response != protocol::ResponseCode::accepted) {
      require(msg.payload.empty());
      continue;
    }
    const auto mode = m.run_state() == RunState::bootloader ? protocol::Mode::bootloader : protocol::Mode::application;
    if (info->valid_in(mode) && info->host_sends) {
      require(protocol::check_reply(*info, mode, msg.id.response, msg.payload.size()).has_value() ||
              msg.id.command == 112);  // 112 read as a get answers with 113's layout
    }
  }
  for (Arm a : kArms) {
    require(std::isfinite(m.reported_deg(a)));
    require(std::isfinite(m.physical_deg(a)));
    require(m.physical_deg(a) >= -m.config().hard_stop_lower_deg[a] - 1e-6);
    require(m.physical_deg(a) <= 360 + m.config().hard_stop_upper_deg[a] + 1e-6);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::span<const std::uint8_t> in(data, size);
  const std::uint8_t setup = in[0];
  in = in.subspan(1);
  PositionerConfig c;
  c.id = 9;
  c.motors_calibrated = (setup & 1) == 0;
  c.datums_calibrated = (setup & 2) == 0;
  c.datums_initialized = (setup & 4) == 0;
  c.sync_line_low_at_power_on = (setup & 8) != 0;
  c.device_options.get_holding_current_on_112 = (setup & 16) != 0;
  c.cogging_calibrated = (setup & 32) == 0;
  c.max_firmware_size = 64;  // small enough for the fuzzer to finish an upload
  PositionerModel m(c);
  SimTime now{};
  const auto take = [&](std::size_t n) {
    auto s = in.first(std::min(n, in.size()));
    in = in.subspan(s.size());
    return s;
  };
  while (!in.empty()) {
    const std::uint8_t op = take(1)[0];
    switch (op % 8) {
      case 0:
      case 1:
      case 2:
      case 3: {
        const auto head = take(3);
        if (head.size() < 3) return 0;
        const auto body = take(head[2] % 9);
        protocol::Message msg;
        msg.id.command = head[0];
        msg.id.uid = static_cast<std::uint8_t>(head[1] >> 2);
        msg.id.positioner = (head[1] & 1) ? protocol::kBroadcastId : ((head[1] & 2) ? 10 : 9);
        msg.payload = protocol::Payload::from(body).value();
        check(m, m.handle(msg, now));
        break;
      }
      case 4: {
        const auto b = take(2);
        if (b.size() < 2) return 0;
        const std::int64_t v = b[0] | (b[1] << 8);
        now += (op & 8) ? SimDuration(std::chrono::seconds(v)) : SimDuration(std::chrono::milliseconds(v));
        check(m, m.advance(now));
        break;
      }
      case 5: {
        const auto b = take(1);
        if (b.empty()) return 0;
        m.power_off(now, (b[0] & 2) == 0);
        if ((b[0] & 4) == 0) m.power_on(now, (b[0] & 1) != 0);
        check(m, {});
        break;
      }
      case 6: check(m, m.set_sync_line((op & 8) != 0, now)); break;
      case 7: {
        const auto b = take(1);
        if (b.empty()) return 0;
        check(m, m.inject_collision((b[0] & 1) ? Arm::beta : Arm::alpha, now));
        break;
      }
    }
  }
  return 0;
}
