// The state of every robot of an array in one table: what discovery finds and what `axon fps
// status` prints. Rows carry what was read (firmware, status word, position) and the read that
// failed, if any, so a table is always complete even when some robots do not answer.
#pragma once

#include "axon/fps/host/positioner.hpp"
#include "axon/fps/protocol/bootloader_status.hpp"
#include "axon/fps/protocol/firmware_version.hpp"
#include "axon/fps/protocol/status.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::host {

struct StatusRow {
  std::uint16_t id = 0;
  std::size_t bus = 0;  // index into the array's buses
  std::string bus_name;
  std::optional<protocol::FirmwareVersion> firmware;
  std::optional<protocol::PositionerStatus> status;               // main application
  std::optional<protocol::BootloaderStatus> bootloader_status;    // bootloader
  std::optional<ArmAngles> position;
  std::string error;  // the first read that failed ("" when every read worked)

  [[nodiscard]] bool in_bootloader() const noexcept {
    return bootloader_status.has_value() || (firmware && firmware->is_bootloader());
  }
  // Datums known, not moving, no collision flag: a move may start.
  [[nodiscard]] bool ready() const noexcept {
    return status && status->ready_to_move() && status->initialized() && !status->collided();
  }
  // One word for the table: ready, moving, collision, calibrating, no-datum, bootloader, no-reply.
  [[nodiscard]] std::string state() const;
};

struct StatusTable {
  std::vector<StatusRow> rows;  // sorted by id

  [[nodiscard]] const StatusRow* find(std::uint16_t id) const noexcept;
  [[nodiscard]] std::size_t count_ready() const noexcept;
  // A fixed-width text table, one line per robot, with a header.
  [[nodiscard]] std::string to_text() const;
};

}  // namespace axon::fps::host
