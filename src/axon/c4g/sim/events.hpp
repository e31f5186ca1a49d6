// What the simulated controller reports while it runs: mode changes, drive state, the manual's
// C4G Open error messages by name (ERR_C4GOPEN_*), and scenario progress.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace axon::c4g::sim {

// The manual's error names (error table of the open interface) and the simulator's own event names.
namespace event {
inline constexpr std::string_view kCommunicationError = "ERR_C4GOPEN_UDP";        // 10 consecutive misses
inline constexpr std::string_view kReceiveDebug = "ERR_C4GOPEN_UDP_DEBUG";        // one packet not received
inline constexpr std::string_view kTransmitError = "ERR_C4GOPEN_TX_UDP";          // send failed
inline constexpr std::string_view kSocketError = "ERR_C4GOPEN_SKT_UDP";           // socket could not be opened
inline constexpr std::string_view kConfigurationError = "ERR_C4GOPEN";            // bad axis configuration
inline constexpr std::string_view kFollowErrorFromPc = "ERR_C4GOPEN_FOLLOW_ERROR";  // 508 from the PC
inline constexpr std::string_view kDriveOffFromPc = "ERR_C4GOPEN_DRIVEOFF_SERVER";  // 505 from the PC
// The state selector moved between AUTO and PROG while an arm was in an open mode: mode 0 forced.
inline constexpr std::string_view kForcedMode0 = "ERR_C4GOPEN_SET_0_MODALITY";
// The open modality configured on an axis that is not open (a start-up mode on a closed axis).
inline constexpr std::string_view kAxisNotPresent = "ERR_C4GOPEN_CONFIGURATION_AX";
// Not in the table: the maximum offset between a reference position and the one scheduled before
// it (the controller's check in modes 7, 8 and 9, chapter 14.17); the drives go off.
inline constexpr std::string_view kOffsetLimit = "OFFSET_LIMIT";
// Not in the table: an open mode left without its exit (forced mode 0, drive off) while the PC's
// accumulated positions (pos_k) differed from the trajectory generator's (pos_i): the reference
// jumps by the difference (the manual's warning in mode 5).
inline constexpr std::string_view kPositionJump = "POSITION_JUMP";
// Not in the open interface's table: the controller's own following-error check (the DSA's).
inline constexpr std::string_view kFollowErrorController = "DSA_FOLLOWING_ERROR";
// Not in the table either: the robot moved during soft control switching (T1, T2 or T3), which the
// manual forbids; the controller switches the drives off.
inline constexpr std::string_view kSoftSwitchMotion = "SCS_ROBOT_MOVED";
inline constexpr std::string_view kModeChange = "MODE_CHANGE";
inline constexpr std::string_view kDrivesOn = "DRIVES_ON";
inline constexpr std::string_view kDrivesOff = "DRIVES_OFF";
inline constexpr std::string_view kSynchronised = "SYNCHRONISED";
inline constexpr std::string_view kInitSent = "INIT_PACKET_SENT";
inline constexpr std::string_view kRequestRefused = "REQUEST_REFUSED";
inline constexpr std::string_view kFreezing = "FREEZING";
inline constexpr std::string_view kOpenEnd = "OPEN_END";  // an arm's open modality ended (type, which event came last)
inline constexpr std::string_view kStep = "STEP";
inline constexpr std::string_view kScenarioDone = "SCENARIO_DONE";
inline constexpr std::string_view kScenarioError = "SCENARIO_ERROR";
inline constexpr std::string_view kCommunicationEnd = "COMMUNICATION_END";
}  // namespace event

enum class EventLevel { info, warning, error };
std::string_view to_string(EventLevel l) noexcept;

struct Event {
  double time_s = 0;         // simulated time since the first packet
  std::uint64_t cycle = 0;   // controller ticks since the first packet
  EventLevel level = EventLevel::info;
  std::string name;          // one of the names above
  std::string text;          // the message in words (the manual's text for its errors)
};

}  // namespace axon::c4g::sim
