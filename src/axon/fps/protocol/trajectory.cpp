#include "axon/fps/protocol/trajectory.hpp"

#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/identifier.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

namespace axon::fps::protocol {
namespace {

Result<void> validate_arm(const std::vector<TrajectoryPoint>& points, std::string_view arm) {
  if (points.size() > Trajectory::kMaxPointsPerArm) {
    return Error(ProtocolErrc::invalid_trajectory,
                 fmt::format("{} arm: {} points (at most {})", arm, points.size(), Trajectory::kMaxPointsPerArm));
  }
  std::uint32_t previous = 0;  // the firmware's own first point is at time 0
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto t = points[i].time.ticks();
    if (t <= previous) {
      return Error(ProtocolErrc::invalid_trajectory,
                   fmt::format("{} arm point {}: time {} s is not after {} s", arm, i, points[i].time.seconds(),
                               Time::from_ticks(previous).seconds()));
    }
    previous = t;
  }
  return ok();
}

Result<std::vector<TrajectoryPoint>> quantise(std::span<const ArmPoint> points, std::string_view arm) {
  if (points.size() > Trajectory::kMaxPointsPerArm) {
    return Error(ProtocolErrc::invalid_trajectory,
                 fmt::format("{} arm: {} points (at most {})", arm, points.size(), Trajectory::kMaxPointsPerArm));
  }
  std::vector<TrajectoryPoint> out;
  out.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto a = Angle::from_degrees(points[i].degrees);
    if (!a) return Error(a.error().code, fmt::format("{} arm point {}: {}", arm, i, a.error().detail));
    auto t = Time::from_seconds(points[i].seconds);
    if (!t) return Error(t.error().code, fmt::format("{} arm point {}: {}", arm, i, t.error().detail));
    out.push_back(TrajectoryPoint{a.value(), t.value()});
  }
  return out;
}

}  // namespace

Result<Trajectory> Trajectory::from_physical(std::span<const ArmPoint> alpha, std::span<const ArmPoint> beta) {
  AXON_TRY(a, quantise(alpha, "alpha"));
  AXON_TRY(b, quantise(beta, "beta"));
  return make(std::move(a), std::move(b));
}

Result<Trajectory> Trajectory::make(std::vector<TrajectoryPoint> alpha, std::vector<TrajectoryPoint> beta) {
  if (alpha.empty() && beta.empty()) {
    return Error(ProtocolErrc::invalid_trajectory, "no points for either arm");
  }
  AXON_TRY(validate_arm(alpha, "alpha"));
  AXON_TRY(validate_arm(beta, "beta"));
  Trajectory t;
  t.alpha_ = std::move(alpha);
  t.beta_ = std::move(beta);
  return t;
}

Time Trajectory::duration() const noexcept {
  Time d;
  if (!alpha_.empty()) d = std::max(d, alpha_.back().time);
  if (!beta_.empty()) d = std::max(d, beta_.back().time);
  return d;
}

std::vector<Request> Trajectory::requests() const {
  std::vector<Request> out;
  out.reserve(request_count());
  out.push_back({CommandId::send_new_trajectory, size().encode()});
  for (const auto& p : alpha_) out.push_back({CommandId::send_trajectory_data, p.encode()});
  for (const auto& p : beta_) out.push_back({CommandId::send_trajectory_data, p.encode()});
  out.push_back({CommandId::trajectory_data_end, Payload()});
  return out;
}

Result<std::vector<can::Frame>> upload_frames(std::uint16_t positioner, const Trajectory& t, std::uint8_t first_uid) {
  if (first_uid == 0 || first_uid > kMaxUid) {
    return Error(ProtocolErrc::uid_out_of_range, fmt::format("first uid {} (must be 1..63)", first_uid));
  }
  std::array<std::uint8_t, 256> next_uid{};
  next_uid.fill(first_uid);
  std::vector<can::Frame> frames;
  frames.reserve(t.request_count());
  for (const auto& r : t.requests()) {
    auto& uid = next_uid[number(r.command)];
    AXON_TRY(f, make_request(positioner, r, uid));
    frames.push_back(f);
    uid = uid == kMaxUid ? 1 : static_cast<std::uint8_t>(uid + 1);
  }
  return frames;
}

}  // namespace axon::fps::protocol
