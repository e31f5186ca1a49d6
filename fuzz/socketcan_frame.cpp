// Fuzzes the struct can_frame decoder: any bytes either decode or give a typed error; frames
// re-encode to a record that decodes to the same frame; error reports always describe themselves.
#include "axon/can/socketcan_frame.hpp"

#include <cstdint>
#include <cstdlib>
#include <span>
#include <variant>

using axon::can::CanErrc;
namespace sc = axon::can::socketcan;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto decoded = sc::decode(std::span<const std::uint8_t>(data, size));
  if (!decoded) {
    const auto& e = decoded.error();
    if (e != CanErrc::invalid_length && e != CanErrc::invalid_id && e != CanErrc::not_supported) std::abort();
    return 0;
  }
  if (size != sc::kFrameSize) std::abort();
  if (const auto* frame = std::get_if<axon::can::Frame>(&decoded.value())) {
    const auto record = sc::encode(*frame);
    auto again = sc::decode(record);
    if (!again || !std::holds_alternative<axon::can::Frame>(again.value())) std::abort();
    if (!(std::get<axon::can::Frame>(again.value()) == *frame)) std::abort();
  } else {
    const auto& report = std::get<sc::ErrorReport>(decoded.value());
    if (report.describe().empty()) std::abort();
    (void)report.state();
    auto again = sc::decode(sc::encode(report));
    if (!again || !std::holds_alternative<sc::ErrorReport>(again.value())) std::abort();
    if (std::get<sc::ErrorReport>(again.value()).classes != report.classes) std::abort();
  }
  return 0;
}
