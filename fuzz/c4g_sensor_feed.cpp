// Fuzzes the datagram parser of the c4g live correction feed (c4g/apps/sensor_feed.hpp), which
// reads whatever arrives on its UDP port. The first byte picks the axis count (1..10) and degrees
// or radians; the rest is the datagram. It must parse to that many finite values or be refused
// with a message; nothing may crash, and nothing beyond the axis count is written.
#include "axon/c4g/apps/sensor_feed.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

using namespace axon::c4g::apps;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::size_t axes = data[0] % SensorFeed::kMaxAxes + 1;
  const bool degrees = (data[0] & 0x80) != 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  std::array<double, SensorFeed::kMaxAxes> out{};
  out.fill(42.0);
  auto r = parse_feed_datagram(text, std::span<double>(out.data(), axes), degrees);
  if (!r) {
    if (r.error().detail.empty()) __builtin_trap();
    return 0;
  }
  for (std::size_t i = 0; i < axes; ++i)
    if (!std::isfinite(out[i])) __builtin_trap();
  for (std::size_t i = axes; i < out.size(); ++i)
    if (out[i] != 42.0) __builtin_trap();
  return 0;
}
