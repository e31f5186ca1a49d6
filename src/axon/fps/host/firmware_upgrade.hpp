// Firmware upgrade of robots already in their bootloader (powered up with the sync line low):
// options, progress and the per-robot report of Array::upgrade_firmware.
//
// Per robot: GET_FIRMWARE_VERSION must show the bootloader (YY == 80), then START_FIRMWARE_UPGRADE
// with the image's size and zlib CRC-32, then the image in 8-byte FIRMWARE_DATA frames with at
// most `window` waiting for replies (the robot buffers 16 frames; more overflow it), every reply
// checked, then the bootloader status is polled until it shows the image received and its CRC
// check passed or failed. Robots run concurrently; the command client bounds what is in flight on
// each bus.
//
// A transfer that stops part-way leaves a partial image in the robot. The bootloader only
// switches to a new image whose CRC matches, so the robot keeps its previous firmware (and boots
// it after its 10 s bootloader timeout); the report says so explicitly (half_written).
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/protocol/bootloader_status.hpp"
#include "axon/fps/protocol/firmware_version.hpp"

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::host {

using namespace std::chrono_literals;

struct UpgradeProgress {
  std::uint16_t positioner = 0;
  std::size_t chunks_acked = 0;  // data frames accepted in order
  std::size_t chunks_total = 0;
};

struct UpgradeOptions {
  std::size_t window = 8;               // data frames in flight per robot (8..16 in service)
  core::Duration verify_timeout = 5s;   // for the bootloader's CRC verdict after the last frame
  core::Duration verify_poll = 100ms;
  std::size_t progress_every = 64;      // call `progress` after this many more chunks (and at the end)
  std::function<void(const UpgradeProgress&)> progress;
};

enum class UpgradeOutcome : std::uint8_t { ok, failed, not_attempted };
const char* to_string(UpgradeOutcome o) noexcept;

struct UpgradeRobotReport {
  std::uint16_t id = 0;
  UpgradeOutcome outcome = UpgradeOutcome::not_attempted;
  std::string reason;          // why it failed or was not attempted ("" when ok)
  std::size_t chunks_acked = 0;
  std::size_t chunks_total = 0;
  bool half_written = false;   // part of the image went out before the failure
  std::optional<protocol::FirmwareVersion> version_before;  // the bootloader's version
  std::optional<protocol::BootloaderStatus> final_status;
};

struct UpgradeReport {
  std::uint32_t size = 0;
  std::uint32_t crc32 = 0;
  std::vector<UpgradeRobotReport> robots;  // in the order asked

  [[nodiscard]] bool ok() const noexcept;  // every robot upgraded
  [[nodiscard]] std::vector<std::uint16_t> with(UpgradeOutcome o) const;
  [[nodiscard]] const UpgradeRobotReport* find(std::uint16_t id) const noexcept;
  [[nodiscard]] std::string summary() const;
};

}  // namespace axon::fps::host
