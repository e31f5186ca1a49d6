#include "axon/fps/host/error.hpp"

namespace axon::fps::host {
namespace {
class HostCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.fps.host"; }
  std::string message(int c) const override {
    switch (static_cast<HostErrc>(c)) {
      case HostErrc::timeout:
        return "no reply from the positioner in time; check power, wiring, the bus and the positioner id";
      case HostErrc::cancelled: return "request cancelled because the command client stopped";
      case HostErrc::closed: return "the CAN bus closed; reconnect to the gateway";
      case HostErrc::locked:
        return "the array is locked and every robot was stopped (the reason comes first); inspect the robots, then "
               "unlock (sends STOP_TRAJECTORY, which clears any collision flags)";
      case HostErrc::collision: return "a positioner reported a collision; every robot was stopped";
      case HostErrc::unknown_positioner: return "no such positioner on the array's buses; run discovery first";
      case HostErrc::bad_reply: return "a positioner's reply does not fit its command (firmware mismatch or corruption)";
      case HostErrc::position_mismatch:
        return "the move ended away from its target; check for slip, collisions or offsets";
      case HostErrc::not_ready:
        return "the positioner is not ready (moving, datum lost, collision flag or calibration running)";
      case HostErrc::sequence_failed: return "the sequence did not complete for every positioner; see its report";
      case HostErrc::start_failed:
        return "a positioner did not acknowledge the trajectory start; every robot was stopped";
      case HostErrc::not_in_bootloader:
        return "the positioner runs its main application; power it up with the sync line low to enter the bootloader";
      case HostErrc::upgrade_failed: return "firmware upgrade failed; see the per-positioner report";
      case HostErrc::wrong_executor: return "all buses of one array must run on the same executor";
      case HostErrc::invalid_argument: return "invalid argument";
      case HostErrc::firmware_lacks: return "the robot's firmware version lacks this command or status layout";
    }
    return "unknown fps host error";
  }
  // A bad option or input from the caller compares equal to std::errc::invalid_argument (the CLI's
  // exit code 2; core/error.cpp).
  std::error_condition default_error_condition(int c) const noexcept override {
    if (static_cast<HostErrc>(c) == HostErrc::invalid_argument) return std::errc::invalid_argument;
    return {c, *this};
  }
};
}  // namespace

const std::error_category& host_category() noexcept {
  static const HostCategory c;
  return c;
}

}  // namespace axon::fps::host
