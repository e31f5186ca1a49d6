// A trajectory for one positioner: a list of (position, time) points per arm, and its upload as
// the exact frame sequence the positioner expects.
//
// The firmware prepends each arm's current position at time 0 by itself, so the host sends at most
// 1023 points per arm and every time must be later than 0. Times count from the start of the move
// and must increase strictly within each arm (checked after rounding to 0.5 ms steps, so two points
// that round to the same step are rejected rather than silently merged). An arm may have no points
// (it stays where it is), but not both.
//
// Upload order: SEND_NEW_TRAJECTORY (alpha count, beta count), then SEND_TRAJECTORY_DATA for every
// alpha point in order, then every beta point in order, then TRAJECTORY_DATA_END. The move starts
// with START_TRAJECTORY (usually broadcast) or the sync line.
#pragma once

#include "axon/can/frame.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/payloads.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace axon::fps::protocol {

// A point in physical units, before quantisation.
struct ArmPoint {
  double degrees = 0;  // arm angle
  double seconds = 0;  // time after the start
};

class Trajectory {
 public:
  static constexpr std::size_t kMaxPointsPerArm = TrajectorySize::kMaxPoints;  // 1023

  // Quantises every point (units.hpp: nearest step, errors for out-of-range values), then validates.
  static Result<Trajectory> from_physical(std::span<const ArmPoint> alpha, std::span<const ArmPoint> beta);
  // Validates wire points.
  static Result<Trajectory> make(std::vector<TrajectoryPoint> alpha, std::vector<TrajectoryPoint> beta);

  [[nodiscard]] const std::vector<TrajectoryPoint>& alpha() const noexcept { return alpha_; }
  [[nodiscard]] const std::vector<TrajectoryPoint>& beta() const noexcept { return beta_; }
  [[nodiscard]] TrajectorySize size() const noexcept {
    return {static_cast<std::uint32_t>(alpha_.size()), static_cast<std::uint32_t>(beta_.size())};
  }
  // The time of the last point of either arm.
  [[nodiscard]] Time duration() const noexcept;

  // Frames needed for the upload: 2 + all points.
  [[nodiscard]] std::size_t request_count() const noexcept { return 2 + alpha_.size() + beta_.size(); }
  // The upload, in order, not yet addressed.
  [[nodiscard]] std::vector<Request> requests() const;

 private:
  std::vector<TrajectoryPoint> alpha_;
  std::vector<TrajectoryPoint> beta_;
};

// The upload as frames to one positioner (1..2047; trajectories cannot be broadcast). Each command
// numbers its own frames with uids counting up from first_uid (1..63) and wrapping from 63 back to 1,
// so uid 0, which marks broadcasts and unsolicited frames, is never used. A host that keeps more than
// 63 frames of one command in flight must wait for replies first.
Result<std::vector<can::Frame>> upload_frames(std::uint16_t positioner, const Trajectory& t,
                                              std::uint8_t first_uid = 1);

}  // namespace axon::fps::protocol
