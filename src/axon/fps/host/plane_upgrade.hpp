// Firmware upgrade of a whole focal plane, one sextant after the other, through the PLC.
//
// For each sextant (in order; one at a time because of the power supplies):
//   1. TRAJECTORY_ABORT on every bus (nothing loaded may start on a sync edge), then the sextant's
//      positioner power off, the sync line low, a pause (`power_off_time`), power on: the robots
//      come up in their bootloader (waited for, up to `bootloader_wait`);
//   2. every robot of the sextant that answers from its bootloader is upgraded at once
//      (Array::upgrade_firmware: all buses of the sextant concurrently, every reply checked);
//   3. robots that failed get `retries` more attempts (default one); when a failed robot has left
//      its bootloader meanwhile (its 10 s timeout), the sextant is power-cycled into it again first;
//   4. the sextant is power-cycled back into the application (sync line high while the power comes
//      back, then low again) and every robot's version is read (up to `boot_wait`): a robot is ok
//      only when it runs the new image (`expected_version` when given, else any application that
//      came up after a verified transfer).
// A robot whose transfer stopped part-way is reported `half_written`: the bootloader kept the
// partial image out of use, so the robot runs its previous firmware and needs another upgrade.
// At the end the cold policy (speed, holding current) is applied again to every robot, since the
// power cycles left them at the firmware's volatile defaults (PlaneUpgradeOptions::reapply_cold).
// Whatever fails, the sextant is always powered back into the application and the sync line left
// low before the next sextant starts; a PLC that fails stops the whole upgrade and every robot not
// yet reached is reported `not_attempted` with the reason.
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/host/cold_control.hpp"
#include "axon/fps/host/firmware_upgrade.hpp"
#include "axon/fps/protocol/firmware_version.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::host {

class FocalPlaneArray;

// Where the upgrade of one sextant stands (reported while transferring and once at its end).
struct SextantProgress {
  int sextant = 0;
  std::size_t total = 0;        // robots of the sextant known to the array
  std::size_t done = 0;         // upgraded and verified so far (transferred, while not finished)
  std::size_t failed = 0;       // failed (after their retries) or not attempted
  std::uint64_t bytes = 0;      // image bytes acknowledged, every attempt counted
  double seconds = 0;           // since the sextant started
  bool finished = false;

  [[nodiscard]] double bytes_per_second() const noexcept { return seconds > 0 ? static_cast<double>(bytes) / seconds : 0; }
  // "sextant 2: 83/84 robots, 1 failed, 4.13 MB in 12.1 s (341.2 kB/s)"
  [[nodiscard]] std::string to_text() const;
};

struct PlaneUpgradeOptions {
  UpgradeOptions transfer;                     // per-robot transfer (its `progress` is ours)
  std::optional<protocol::FirmwareVersion> expected_version;  // what the robots must run afterwards
  std::vector<int> sextants;                   // empty: every sextant with robots, ascending
  unsigned retries = 1;                        // extra attempts per failed robot
  core::Duration power_off_time = 1s;          // positioner power off this long
  core::Duration bootloader_wait = 3s;         // for robots to answer from the bootloader
  core::Duration boot_wait = 5s;               // for robots to answer from the application
  core::Duration poll = 50ms;                  // while waiting for either
  core::Duration progress_interval = 1s;       // progress calls while transferring (0: only at the end)
  std::function<void(const SextantProgress&)> progress;
  // Speed and holding current are volatile in the robots, so after the power cycles they run the
  // firmware's defaults: at the end the cold policy is applied again from the PLC's temperatures
  // (ColdControl::step(true)) unless this is false.
  bool reapply_cold = true;
  plc::ColdPolicyConfig cold_policy;
};

enum class PlaneRobotOutcome : std::uint8_t { ok, failed, not_attempted };
const char* to_string(PlaneRobotOutcome o) noexcept;

struct PlaneRobotReport {
  std::uint16_t id = 0;
  int sextant = 0;
  PlaneRobotOutcome outcome = PlaneRobotOutcome::not_attempted;
  unsigned attempts = 0;        // transfers started
  std::string reason;           // why it failed or was not attempted; notes when ok
  bool half_written = false;    // the last transfer stopped part-way (the robot keeps its old firmware)
  std::optional<protocol::FirmwareVersion> before;  // application version before the upgrade
  std::optional<protocol::FirmwareVersion> after;   // what it runs at the end (nullopt: no answer)
};

struct PlaneUpgradeReport {
  std::uint32_t size = 0;
  std::uint32_t crc32 = 0;
  std::vector<PlaneRobotReport> robots;      // by sextant, then id
  std::vector<SextantProgress> sextants;     // final figures per sextant
  std::vector<std::string> notes;            // PLC failures, buses that missed an abort, ...
  std::optional<ColdApplyReport> cold;       // the cold policy applied at the end (reapply_cold)

  [[nodiscard]] bool ok() const noexcept;
  [[nodiscard]] std::vector<std::uint16_t> with(PlaneRobotOutcome o) const;
  [[nodiscard]] const PlaneRobotReport* find(std::uint16_t id) const noexcept;
  // One line per sextant, then one per robot that is not plainly ok.
  [[nodiscard]] std::string summary() const;
};

// Errors (nothing was switched): HostErrc::invalid_argument without a PLC, for an unknown sextant
// or one without robots; an unusable image (protocol errors). Everything else is in the report.
// `image` must stay alive until this completes.
boost::asio::awaitable<Result<PlaneUpgradeReport>> upgrade_plane(FocalPlaneArray& plane,
                                                                 std::span<const std::uint8_t> image,
                                                                 PlaneUpgradeOptions options = {});

}  // namespace axon::fps::host
