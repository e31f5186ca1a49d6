// The Linux SocketCAN wire record: the 16-byte `struct can_frame` a CAN_RAW socket reads and
// writes, converted to and from can::Frame. Pure functions, no sockets, so they are tested and
// fuzzed on their own; src/axon/can/socketcan_bus.cpp uses them on the socket.
//
// Layout (host byte order, as the kernel uses it):
//   bytes 0..3  can_id: 29- or 11-bit id plus three flag bits (extended, remote, error report)
//   byte  4     len: payload length 0..8 (called can_dlc in older headers)
//   bytes 5..6  padding / reserved, written as zero
//   byte  7     len8_dlc: raw DLC 9..15 for 8-byte frames on controllers that support it
//   bytes 8..15 payload
//
// Error reports (the error flag set in can_id) are not frames: the kernel uses them to tell the
// application about controller state (bus-off, warnings, lost arbitration, missing ACK...). They
// decode into an ErrorReport, which the bus turns into state changes and counters.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/frame.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

namespace axon::can::socketcan {

// Sizes of the kernel's records: classic frame, and the CAN FD frame we do not support.
inline constexpr std::size_t kFrameSize = 16;
inline constexpr std::size_t kFdFrameSize = 72;

// Flag bits of can_id (the same values as <linux/can.h>, checked there at compile time).
inline constexpr std::uint32_t kExtendedFlag = 0x8000'0000U;
inline constexpr std::uint32_t kRemoteFlag = 0x4000'0000U;
inline constexpr std::uint32_t kErrorFlag = 0x2000'0000U;
inline constexpr std::uint32_t kIdMask = 0x1FFF'FFFFU;

// Error classes carried in the id bits of an error report (<linux/can/error.h>).
enum class ErrorClass : std::uint32_t {
  tx_timeout = 0x001,        // the driver gave up transmitting
  lost_arbitration = 0x002,  // data[0]: bit position
  controller = 0x004,        // data[1]: controller status bits (warning, passive, overflow)
  protocol = 0x008,          // data[2..3]: kind and location of a protocol violation
  transceiver = 0x010,       // data[4]: wiring problem
  no_ack = 0x020,            // nobody acknowledged our frame
  bus_off = 0x040,
  bus_error = 0x080,         // any bus error (can come in floods)
  restarted = 0x100,         // the controller restarted after bus-off
  error_counters = 0x200,    // data[6], data[7]: transmit and receive error counters
};

// An error report as it came from the kernel: error classes plus their detail bytes.
struct ErrorReport {
  std::uint32_t classes = 0;
  std::array<std::uint8_t, 8> data{};

  [[nodiscard]] bool has(ErrorClass c) const noexcept { return (classes & static_cast<std::uint32_t>(c)) != 0; }
  // The controller state this report moves the bus to, if it says anything about the state.
  // Bus-off wins over everything; a restart or "back to error active" gives active; otherwise
  // the most severe controller level reported (passive over warning).
  [[nodiscard]] std::optional<BusState> state() const noexcept;
  // The controller lost received frames (its receive FIFO overflowed).
  [[nodiscard]] bool controller_rx_overflow() const noexcept;
  // The controller dropped frames to transmit (its transmit FIFO overflowed).
  [[nodiscard]] bool controller_tx_overflow() const noexcept;
  // Transmit / receive error counters, when the report carries them.
  [[nodiscard]] std::optional<std::uint8_t> tx_error_counter() const noexcept;
  [[nodiscard]] std::optional<std::uint8_t> rx_error_counter() const noexcept;
  // One line for the log, e.g. "bus-off" or "controller: rx-warning tx-passive; no-ack".
  [[nodiscard]] std::string describe() const;
};

using Record = std::array<std::uint8_t, kFrameSize>;
using Decoded = std::variant<Frame, ErrorReport>;

// The 16 bytes to write for a frame.
Record encode(const Frame& frame) noexcept;

// An error report as the kernel would send it (for tests and simulators).
Record encode(const ErrorReport& report) noexcept;

// Decodes one record as read from the socket. Errors: invalid_length for a record that is not 16
// bytes or a length over 8; not_supported for a 72-byte CAN FD record; invalid_id for a standard
// id over 0x7FF.
Result<Decoded> decode(std::span<const std::uint8_t> bytes);

// A kernel receive filter (struct can_filter): a frame passes when
// (frame can_id & mask) == (id & mask), flags included.
struct KernelFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  friend bool operator==(const KernelFilter&, const KernelFilter&) = default;
};

// Most filters one CAN_RAW_FILTER call takes (CAN_RAW_FILTER_MAX).
inline constexpr std::size_t kMaxKernelFilters = 512;

// The kernel filters that pass exactly what the Bus filters pass. No Bus filters, or more than
// the kernel takes, give one pass-everything filter (an empty kernel list would pass nothing);
// the Bus still filters in user space in every case.
std::vector<KernelFilter> to_kernel_filters(const std::vector<Filter>& filters);

}  // namespace axon::can::socketcan
