// What a firmware version has: the version gates the host and the simulator share.
//
// The interface document describes one application firmware (its table 6 is that of 04.01.13) and
// tells the bootloader apart by its middle number 80 (sections 5.2.2, 5.3.2); it gives no history
// of versions. The field notes add two gates: the 64-bit status word of section 5 applies from
// 04.01.00 on (older layouts are described nowhere: neither side models them), and hosts in
// service send the precise-move switches 128..131 only from 04.01.17 on. FirmwareHistory picks
// whether the second gate holds (field) or every command of table 6 is in every modelled version
// (document, the default).
#pragma once

#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/firmware_version.hpp"

#include <cstdint>
#include <string>

namespace axon::fps::protocol {

enum class FirmwareHistory : std::uint8_t {
  document,  // every command of table 6 in every application version modelled
  field,     // as above, but 128..131 only from 04.01.17 on (older versions answer 13, unknown)
};

// The oldest application firmware modelled: from 04.01.00 on the status word is the 64-bit one.
inline constexpr FirmwareVersion kOldestModelledFirmware{4, 1, 0};

// Does application firmware `version` know command `c` at all? (The bootloader's commands are
// the document's section 5.2 and are not gated by version.)
[[nodiscard]] bool firmware_takes(CommandId c, FirmwareVersion version, FirmwareHistory history) noexcept;

// Empty when application firmware `version` takes `c` under `history`; otherwise why not, for an
// error message ("firmware 04.01.13 lacks SWITCH_ON_PRECISE_MOVE_ALPHA (128): from 04.01.17 on").
[[nodiscard]] std::string firmware_lacks(CommandId c, FirmwareVersion version, FirmwareHistory history);

// Empty when the status word of `version` is the 64-bit layout the project decodes; otherwise why
// not.
[[nodiscard]] std::string status_layout_unknown(FirmwareVersion version);

}  // namespace axon::fps::protocol
