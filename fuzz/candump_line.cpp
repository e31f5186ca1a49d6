// Fuzzes parse_candump_line: it must never crash, refuse only with its two documented codes, and
// whatever it accepts must survive format_candump_line and a second parse unchanged (timestamps
// to the microsecond, which is what the format keeps).
#include "axon/can/candump_log.hpp"

#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

using axon::can::CanErrc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  auto first = axon::can::parse_candump_line(line);
  if (!first) {
    if (first.error() != CanErrc::parse_error && first.error() != CanErrc::not_supported) std::abort();
    if (first.error().detail.empty()) std::abort();
    return 0;
  }
  const auto& a = first.value();
  const std::string text = axon::can::format_candump_line(a);
  auto second = axon::can::parse_candump_line(text);
  if (!second) std::abort();
  const auto& b = second.value();
  if (!(b.frame == a.frame) || b.frame.to_string() != a.frame.to_string()) std::abort();
  if (b.iface != a.iface || b.error_frame != a.error_frame) std::abort();
  if (b.frame.timestamp().count() != a.frame.timestamp().count() / 1000 * 1000) std::abort();
  if (axon::can::format_candump_line(b) != text) std::abort();
  return 0;
}
