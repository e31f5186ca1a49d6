#include "fps/protocol/status.hpp"

#include "fps/protocol/error.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>

namespace axon::fps::protocol {


namespace {
bool eq_nocase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(a[i])) != std::toupper(static_cast<unsigned char>(b[i]))) return false;
  }
  return true;
}
}  // namespace

std::string_view status_bit_name(StatusBit b) noexcept {
  for (const auto& i : kStatusBits) {
    if (i.bit == b) return i.name;
  }
  return "UNKNOWN";
}

std::optional<StatusBit> status_bit_from_name(std::string_view name) noexcept {
  if (eq_nocase(name, "SYSTEM_INITIALIZED")) return StatusBit::system_initialized;
  for (const auto& i : kStatusBits) {
    if (eq_nocase(i.name, name)) return i.bit;
  }
  return std::nullopt;
}

std::vector<std::string> PositionerStatus::names() const {
  std::vector<std::string> out;
  for (unsigned bit = 0; bit < 64; ++bit) {
    if ((raw_ & (std::uint64_t{1} << bit)) == 0) continue;
    const auto b = static_cast<StatusBit>(bit);
    if ((kKnownMask & mask(b)) != 0) {
      out.emplace_back(status_bit_name(b));
    } else {
      out.push_back(fmt::format("BIT_{}", bit));
    }
  }
  return out;
}

std::string PositionerStatus::to_string() const { return fmt::format("{}", fmt::join(names(), "|")); }

Payload PositionerStatus::encode() const { return Payload().put_u64(raw_); }

Result<PositionerStatus> PositionerStatus::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kWireSize, "status word"));
  return PositionerStatus(read_u64(bytes, 0));
}

}  // namespace axon::fps::protocol
