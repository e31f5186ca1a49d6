#include "axon/blmc/host/error.hpp"

namespace axon::blmc::host {
namespace {
class HostCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.blmc.host"; }
  std::string message(int c) const override {
    switch (static_cast<HostErrc>(c)) {
      case HostErrc::timeout: return "no frame from the motor driver board in time; check power, wiring and the bus";
      case HostErrc::not_ready:
        return "the motors did not finish alignment in time; check that they can turn freely and the encoders";
      case HostErrc::board_error: return "the motor driver board reports an error; it disabled itself";
      case HostErrc::stale_data:
        return "no measurement from the board within the stale limit; the bus or the board stopped";
      case HostErrc::safety_fault: return "a safety check tripped: currents were zeroed and the motors disabled";
      case HostErrc::cyclic_active: return "the real-time loop owns the board; stop it first";
      case HostErrc::not_cyclic: return "the board is not in cyclic mode; call start_cyclic first";
      case HostErrc::link_overflow: return "a queue between the real-time thread and the bus thread overflowed";
      case HostErrc::closed: return "the CAN bus closed under the board";
      case HostErrc::invalid_argument: return "invalid argument";
      case HostErrc::homing_failed: return "homing found no encoder index; check the encoder and the homing range";
      case HostErrc::interrupted: return "stopped on request while waiting for the board";
      case HostErrc::not_enabled: return "the motors are not enabled; call enable() first";
    }
    return "unknown blmc host error";
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

}  // namespace axon::blmc::host
