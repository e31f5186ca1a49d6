// Your robot, not only the manual's: the simulated controller's robot from a file.
//
// Two forms:
//   - an initialization packet as captured: exactly 1200 bytes (the payload `axon c4g init-info`
//     reads; `--from-pcap` captures hold it as the first 1200-byte datagram);
//   - YAML naming the packet's fields as the controller's struct does, the form `axon c4g
//     init-info --json` prints under "fields": scalars (period: 2, nblip: 10, ...) and per-arm
//     lists of up to 10 values (arm1OpenAx: [1, 2, 3, 4, 5, 6], arm1TxRate: [...], arm1CalData,
//     arm1AzLim, arm1AxInfo, arm1FollowError, arm1OpenMask); plus `name:`. Fields left out are 0,
//     except nFieldPck/nFieldAx and the field types (the manual's values), period (2 ms) and
//     nAxOpen (counted from the open-axis lists).
// The physical data of each axis (inertia, friction, loop gains) are the simulator's defaults
// (AxisParams); its current limit and following-error threshold are the packet's.
//
// Checked on load, with the manual's limits of the open interface (table 5.1): at most 4 arms,
// 20 open axes, 10 per arm of which at most 4 auxiliary; each arm's open axes listed once; a
// non-zero transmission ratio on every axis of an arm up to its last open one (the transform); the packet's own format checks. The
// table's 2 DSAs cannot be checked: the packet does not say which DSA drives an axis.
// Errors: Result with CoreErrc::invalid_argument (or the packet's ProtocolErrc), the text naming
// the file, the field and the limit.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "axon/core/error.hpp"

#include <string>
#include <string_view>

namespace axon::c4g::sim {

// The manual's table 5.1 (limits of the open interface).
inline constexpr std::size_t kTableMaxArms = 4;
inline constexpr std::size_t kTableMaxAxes = 20;
inline constexpr std::size_t kTableMaxAxesPerArm = 10;
inline constexpr std::size_t kTableMaxAuxiliaryAxesPerArm = 4;
inline constexpr std::size_t kTableMaxDsas = 2;

// Reads a robot from a file (either form above).
Result<RobotConfig> load_robot_file(const std::string& path);
// The YAML form from text; `where` names it in errors.
Result<protocol::InitPacket> init_from_yaml(std::string_view yaml, std::string where = "<robot>");
// A robot around an initialization packet, after the checks above.
Result<RobotConfig> robot_from_init(protocol::InitPacket init, std::string name);
// The table 5.1 checks and the axis map's consistency.
Result<void> check_table_limits(const protocol::InitPacket& init);

}  // namespace axon::c4g::sim
