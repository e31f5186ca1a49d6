#include "axon/can/socketcan_frame.hpp"

#include <fmt/format.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>

#include <cstddef>
#include <cstring>

namespace axon::can::socketcan {

// Our constants must be the kernel's.
static_assert(sizeof(struct can_frame) == kFrameSize);
static_assert(sizeof(struct canfd_frame) == kFdFrameSize);
static_assert(offsetof(struct can_frame, data) == 8);
static_assert(kExtendedFlag == CAN_EFF_FLAG && kRemoteFlag == CAN_RTR_FLAG && kErrorFlag == CAN_ERR_FLAG);
static_assert(kIdMask == CAN_EFF_MASK);
static_assert(kMaxKernelFilters == CAN_RAW_FILTER_MAX);
static_assert(static_cast<std::uint32_t>(ErrorClass::tx_timeout) == CAN_ERR_TX_TIMEOUT);
static_assert(static_cast<std::uint32_t>(ErrorClass::lost_arbitration) == CAN_ERR_LOSTARB);
static_assert(static_cast<std::uint32_t>(ErrorClass::controller) == CAN_ERR_CRTL);
static_assert(static_cast<std::uint32_t>(ErrorClass::protocol) == CAN_ERR_PROT);
static_assert(static_cast<std::uint32_t>(ErrorClass::transceiver) == CAN_ERR_TRX);
static_assert(static_cast<std::uint32_t>(ErrorClass::no_ack) == CAN_ERR_ACK);
static_assert(static_cast<std::uint32_t>(ErrorClass::bus_off) == CAN_ERR_BUSOFF);
static_assert(static_cast<std::uint32_t>(ErrorClass::bus_error) == CAN_ERR_BUSERROR);
static_assert(static_cast<std::uint32_t>(ErrorClass::restarted) == CAN_ERR_RESTARTED);
static_assert(static_cast<std::uint32_t>(ErrorClass::error_counters) == 0x200U);  // CAN_ERR_CNT (newer headers)

namespace {

constexpr std::uint8_t kCtrlWarning = CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING;
constexpr std::uint8_t kCtrlPassive = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE;
constexpr std::uint8_t kCtrlActive = 0x40;  // CAN_ERR_CRTL_ACTIVE (since Linux 3.x)

Record to_record(const struct can_frame& cf) noexcept {
  Record r{};
  std::memcpy(r.data(), &cf, sizeof cf);
  return r;
}

}  // namespace

std::optional<BusState> ErrorReport::state() const noexcept {
  if (has(ErrorClass::bus_off)) return BusState::bus_off;
  if (has(ErrorClass::controller)) {
    const std::uint8_t status = data[1];
    if (status & kCtrlPassive) return BusState::error_passive;
    if (status & kCtrlWarning) return BusState::error_warning;
    if (status & kCtrlActive) return BusState::active;
  }
  if (has(ErrorClass::restarted)) return BusState::active;
  return std::nullopt;
}

bool ErrorReport::controller_rx_overflow() const noexcept {
  return has(ErrorClass::controller) && (data[1] & CAN_ERR_CRTL_RX_OVERFLOW) != 0;
}

bool ErrorReport::controller_tx_overflow() const noexcept {
  return has(ErrorClass::controller) && (data[1] & CAN_ERR_CRTL_TX_OVERFLOW) != 0;
}

std::optional<std::uint8_t> ErrorReport::tx_error_counter() const noexcept {
  if (!has(ErrorClass::error_counters)) return std::nullopt;
  return data[6];
}

std::optional<std::uint8_t> ErrorReport::rx_error_counter() const noexcept {
  if (!has(ErrorClass::error_counters)) return std::nullopt;
  return data[7];
}

std::string ErrorReport::describe() const {
  std::string out;
  auto add = [&](std::string_view part) {
    if (!out.empty()) out += "; ";
    out += part;
  };
  if (has(ErrorClass::bus_off)) add("bus-off");
  if (has(ErrorClass::restarted)) add("controller restarted");
  if (has(ErrorClass::controller)) {
    std::string c = "controller:";
    const std::uint8_t s = data[1];
    if (s & CAN_ERR_CRTL_RX_OVERFLOW) c += " rx-overflow";
    if (s & CAN_ERR_CRTL_TX_OVERFLOW) c += " tx-overflow";
    if (s & CAN_ERR_CRTL_RX_WARNING) c += " rx-warning";
    if (s & CAN_ERR_CRTL_TX_WARNING) c += " tx-warning";
    if (s & CAN_ERR_CRTL_RX_PASSIVE) c += " rx-passive";
    if (s & CAN_ERR_CRTL_TX_PASSIVE) c += " tx-passive";
    if (s & kCtrlActive) c += " back-to-active";
    if (s == 0) c += " unspecified";
    add(c);
  }
  if (has(ErrorClass::tx_timeout)) add("transmit timeout");
  if (has(ErrorClass::lost_arbitration)) add(fmt::format("lost arbitration at bit {}", data[0]));
  if (has(ErrorClass::protocol)) add(fmt::format("protocol violation type 0x{:02X} at 0x{:02X}", data[2], data[3]));
  if (has(ErrorClass::transceiver)) add(fmt::format("transceiver status 0x{:02X}", data[4]));
  if (has(ErrorClass::no_ack)) add("no ACK (is anyone else on the bus?)");
  if (has(ErrorClass::bus_error)) add("bus error");
  if (has(ErrorClass::error_counters)) add(fmt::format("error counters tx={} rx={}", data[6], data[7]));
  if (out.empty()) out = fmt::format("error report 0x{:08X}", classes);
  return out;
}

Record encode(const Frame& frame) noexcept {
  struct can_frame cf {};
  cf.can_id = frame.id();
  if (frame.is_extended()) cf.can_id |= CAN_EFF_FLAG;
  if (frame.is_remote()) cf.can_id |= CAN_RTR_FLAG;
  cf.len = frame.dlc();
  const auto payload = frame.payload();
  std::memcpy(cf.data, payload.data(), payload.size());
  return to_record(cf);
}

Record encode(const ErrorReport& report) noexcept {
  struct can_frame cf {};
  cf.can_id = CAN_ERR_FLAG | (report.classes & CAN_ERR_MASK);
  cf.len = CAN_ERR_DLC;
  std::memcpy(cf.data, report.data.data(), report.data.size());
  return to_record(cf);
}

Result<Decoded> decode(std::span<const std::uint8_t> bytes) {
  if (bytes.size() == kFdFrameSize)
    return Error(CanErrc::not_supported, "72-byte CAN FD record: only classic CAN frames are supported");
  if (bytes.size() != kFrameSize)
    return Error(CanErrc::invalid_length,
                 fmt::format("SocketCAN record of {} bytes (a classic frame has {})", bytes.size(), kFrameSize));
  struct can_frame cf {};
  std::memcpy(&cf, bytes.data(), sizeof cf);
  if (cf.len > CAN_MAX_DLEN)
    return Error(CanErrc::invalid_length, fmt::format("SocketCAN frame 0x{:08X} with length {}", cf.can_id, cf.len));
  if (cf.can_id & CAN_ERR_FLAG) {
    // The detail bytes beyond the reported length are not meaningful: keep them zero.
    ErrorReport report;
    report.classes = cf.can_id & CAN_ERR_MASK;
    std::memcpy(report.data.data(), cf.data, cf.len);
    return Decoded(report);
  }
  const IdFormat format = (cf.can_id & CAN_EFF_FLAG) ? IdFormat::extended : IdFormat::standard;
  const std::uint32_t id = cf.can_id & CAN_EFF_MASK;
  if (cf.can_id & CAN_RTR_FLAG) {
    AXON_TRY(frame, Frame::remote(id, format, cf.len));
    return Decoded(frame);
  }
  AXON_TRY(frame, Frame::data(id, format, std::span<const std::uint8_t>(cf.data, cf.len)));
  return Decoded(frame);
}

std::vector<KernelFilter> to_kernel_filters(const std::vector<Filter>& filters) {
  if (filters.empty() || filters.size() > kMaxKernelFilters) return {KernelFilter{0, 0}};
  std::vector<KernelFilter> out;
  out.reserve(filters.size());
  for (const Filter& f : filters) {
    KernelFilter k{f.id & CAN_EFF_MASK, f.mask & CAN_EFF_MASK};
    switch (f.format) {
      case Filter::Format::any: break;  // the format flag is not compared
      case Filter::Format::standard: k.mask |= CAN_EFF_FLAG; break;
      case Filter::Format::extended:
        k.id |= CAN_EFF_FLAG;
        k.mask |= CAN_EFF_FLAG;
        break;
    }
    out.push_back(k);
  }
  return out;
}

}  // namespace axon::can::socketcan
