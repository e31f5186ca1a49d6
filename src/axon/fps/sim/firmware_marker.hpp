// How a simulated positioner reads a firmware image it received.
//
// Real images are machine code; the simulator cannot run them, so it looks for a tag in the bytes:
//
//   "AXON-FPS-FW:XX.YY.ZZ"  the image boots and reports version XX.YY.ZZ
//   "AXON-FPS-FW:BRICK"     the image never boots: after the watchdog time the positioner restores
//                           the previous image (interface document 5.2.5)
//   no tag                  the image boots and keeps reporting the version it replaced
//
// The first tag in the image wins. make_firmware_image() builds test images with a tag.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/firmware_version.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace axon::fps::sim {

inline constexpr std::string_view kFirmwareTag = "AXON-FPS-FW:";
inline constexpr std::string_view kBrickTag = "BRICK";

struct FirmwareMarker {
  bool bootable = true;
  std::optional<protocol::FirmwareVersion> version;  // nullopt: no tag, keep the old number
};

FirmwareMarker read_firmware_marker(std::span<const std::uint8_t> image);

// An image of `size` bytes (at least the tag's length) of deterministic filler with the tag for
// `version` near the start. Errors: CoreErrc::invalid_argument when size is too small.
Result<std::vector<std::uint8_t>> make_firmware_image(protocol::FirmwareVersion version, std::size_t size);
// The same with the BRICK tag: an image that passes its CRC but never boots.
Result<std::vector<std::uint8_t>> make_bricked_firmware_image(std::size_t size);

}  // namespace axon::fps::sim
