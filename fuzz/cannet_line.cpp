// Fuzzes the CAN@net line parser: the input is split at '\n' and every piece parsed. A piece that
// parses must format to text that parses back to the same value; anything else traps.
#include "can/cannet_codec.hpp"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace axon::can::cannet;
  std::string_view input(reinterpret_cast<const char*>(data), size);
  while (!input.empty()) {
    const auto nl = input.find('\n');
    const std::string_view line = input.substr(0, nl);
    input = nl == std::string_view::npos ? std::string_view() : input.substr(nl + 1);
    auto parsed = parse_line(line);
    if (!parsed) {
      if (parsed.error().code != axon::can::CanErrc::parse_error || parsed.error().detail.empty()) __builtin_trap();
      continue;
    }
    const std::string text = format_line(parsed.value());
    auto again = parse_line(text);
    if (!again || !(again.value() == parsed.value())) __builtin_trap();
    // The formatted text is canonical: formatting again gives the same characters.
    if (format_line(again.value()) != text) __builtin_trap();
  }
  return 0;
}
