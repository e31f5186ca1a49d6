// The latest state a board reported: every quantity with the time it arrived and how many frames
// carried it. One Measurements lives per board, preallocated; decoding a frame overwrites one
// field in place and never allocates (except to describe a malformed frame, see apply_frame).
#pragma once

#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/protocol/status.hpp"
#include "axon/can/frame.hpp"
#include "axon/core/clock.hpp"

#include <array>
#include <cstdint>

namespace axon::blmc::host {

using protocol::MotorPair;

// A value and the host's monotonic time when its frame was decoded. count == 0: never received.
template <class T>
struct Stamped {
  T value{};
  core::TimePoint at{};
  std::uint64_t count = 0;
  [[nodiscard]] bool received() const noexcept { return count > 0; }
};

// Which board message a stale check or a fault refers to.
enum class Quantity : std::uint8_t { status, current, position, velocity, adc, encoder_index };
const char* to_string(Quantity q) noexcept;

// The board's position counter rolls over at +-100 rev (protocol::kPositionRolloverRev): a shaft
// turning past +100 reads -100 on the next frame. The host counts those wraps per motor, so that
// `position` is continuous and PD laws, homing and the position limits never see a 200 rev jump. A
// change of more than half the counter's range between two frames can only be a wrap (as motion it
// would be 100 rev within one frame period, 6 million rpm at 1 kHz). Encoder index positions are
// unwrapped the same way, to the turn nearest the current position.
struct PositionUnwrap {
  std::array<double, 2> last_raw{};      // the last reading, as the board sent it
  std::array<std::int64_t, 2> wraps{};   // +1 for each wrap from +100 to -100, -1 the other way
  [[nodiscard]] double offset_rev(std::size_t motor) const noexcept;
};

struct Measurements {
  Stamped<protocol::Status> status;  // the latest status frame that decoded
  // The byte of the latest status frame of any kind, including one whose error code the spec
  // does not define (6), which `status` cannot hold: Safety faults on such a byte at once.
  Stamped<std::uint8_t> status_byte;
  Stamped<MotorPair> current;   // A
  Stamped<MotorPair> position;  // motor revolutions, unwrapped across the counter's rollover
  Stamped<MotorPair> velocity;  // krpm
  Stamped<MotorPair> adc;       // 0..1 (A6, B6)
  // Position at the last encoder index tick, per motor (index 0 = motor 1), unwrapped.
  std::array<Stamped<double>, 2> index;
  PositionUnwrap unwrap;

  std::uint64_t frames = 0;    // board frames decoded
  std::uint64_t rejected = 0;  // frames with a board identifier that failed to decode
  std::uint64_t undocumented_errors = 0;  // status frames carrying error code 6 (not in `rejected`)
  std::uint64_t foreign = 0;   // frames that are not board messages (host ids, other devices)

  [[nodiscard]] const Stamped<MotorPair>& pair(Quantity q) const noexcept;
  // The time of the last frame of this quantity (any motor for the encoder index).
  [[nodiscard]] core::TimePoint last(Quantity q) const noexcept;
  [[nodiscard]] std::uint64_t count(Quantity q) const noexcept;
  // The latest status frame carried an error code the spec does not define (6).
  [[nodiscard]] bool undocumented_error() const noexcept {
    return status_byte.received() && protocol::error_bits(status_byte.value) == protocol::kUndocumentedErrorCode;
  }
};

// Convenience conversions of the wire units.
constexpr double krpm_to_rev_per_s(double krpm) noexcept { return krpm * 1000.0 / 60.0; }
constexpr double rev_per_s_to_krpm(double rev_s) noexcept { return rev_s * 60.0 / 1000.0; }

enum class FrameOutcome : std::uint8_t {
  status,       // a status frame was stored
  measurement,  // current, position, velocity or ADC stored
  index,        // an encoder index tick stored
  foreign,      // not a board message: ignored
  rejected,     // a board identifier whose frame did not decode: counted, nothing stored
  undocumented_error,  // a status frame with error code 6: status_byte stored, counted; a fault
};

// Decodes one frame from the bus into `m`, stamping it with `now`. The common checks (format,
// identifier, length) run without allocating; only a frame that passes them and still fails the
// codec's value checks (ADC outside 0..1, motor number above 1) builds the codec's error text, a
// rare path for a broken board. A status frame with the undefined error code 6 is not rejected:
// it is the board reporting an error, kept in status_byte and counted in undocumented_errors.
FrameOutcome apply_frame(Measurements& m, const can::Frame& f, core::TimePoint now);

}  // namespace axon::blmc::host
