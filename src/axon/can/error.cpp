#include "axon/can/error.hpp"

namespace axon::can {
namespace {
class CanCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.can"; }
  std::string message(int c) const override {
    switch (static_cast<CanErrc>(c)) {
      case CanErrc::invalid_id: return "invalid CAN id: standard ids are 0..0x7FF, extended ids 0..0x1FFFFFFF";
      case CanErrc::invalid_length: return "invalid CAN data length: classic CAN carries 0..8 bytes";
      case CanErrc::parse_error: return "malformed CAN text; see the format in docs/can.md";
      case CanErrc::protocol_error: return "peer broke the protocol; check that the address points at the right kind of device";
      case CanErrc::device_error: return "the device reported an error; see its message";
      case CanErrc::bus_off: return "CAN controller is bus-off; check wiring, termination and bitrate, then restart the bus";
      case CanErrc::tx_overflow: return "transmit queue full, frame dropped; send less at once or wait for replies";
      case CanErrc::rx_overflow: return "receive queue full, frame dropped; read the bus faster";
      case CanErrc::closed: return "bus closed";
      case CanErrc::timeout: return "no CAN frame in time; check that the device is powered and on this bus";
      case CanErrc::connect_failed: return "cannot connect; check the address and port and that the gateway or daemon runs";
      case CanErrc::not_supported: return "not supported on this system";
      case CanErrc::bad_spec: return "bad bus specification; use virtual:NAME, socketcand://HOST:PORT/CHANNEL, cannet://HOST:PORT/N or socketcan:IFACE";
      case CanErrc::io: return "socket or file error";
    }
    return "unknown CAN error";
  }
  // Text the user gave that is not a frame or a bus compares equal to std::errc::invalid_argument
  // (see core/error.cpp). A peer's malformed line is counted where it arrives, not thrown.
  std::error_condition default_error_condition(int c) const noexcept override {
    switch (static_cast<CanErrc>(c)) {
      case CanErrc::invalid_id:
      case CanErrc::invalid_length:
      case CanErrc::parse_error:
      case CanErrc::bad_spec: return std::errc::invalid_argument;
      default: return {c, *this};
    }
  }
};
}  // namespace

const std::error_category& can_category() noexcept {
  static const CanCategory c;
  return c;
}

}  // namespace axon::can
