#include "axon/blmc/host/measurements.hpp"

#include "axon/blmc/protocol/message_id.hpp"

namespace axon::blmc::host {

using protocol::MessageId;

const char* to_string(Quantity q) noexcept {
  switch (q) {
    case Quantity::status: return "status";
    case Quantity::current: return "current";
    case Quantity::position: return "position";
    case Quantity::velocity: return "velocity";
    case Quantity::adc: return "adc";
    case Quantity::encoder_index: return "encoder index";
  }
  return "?";
}

const Stamped<MotorPair>& Measurements::pair(Quantity q) const noexcept {
  switch (q) {
    case Quantity::current: return current;
    case Quantity::position: return position;
    case Quantity::velocity: return velocity;
    default: return adc;
  }
}

core::TimePoint Measurements::last(Quantity q) const noexcept {
  switch (q) {
    case Quantity::status: return status.at;
    case Quantity::encoder_index: return std::max(index[0].at, index[1].at);
    default: return pair(q).at;
  }
}

std::uint64_t Measurements::count(Quantity q) const noexcept {
  switch (q) {
    case Quantity::status: return status.count;
    case Quantity::encoder_index: return index[0].count + index[1].count;
    default: return pair(q).count;
  }
}

double PositionUnwrap::offset_rev(std::size_t motor) const noexcept {
  return 2 * protocol::kPositionRolloverRev * static_cast<double>(wraps[motor]);
}

namespace {
template <class T>
void store(Stamped<T>& s, const T& v, core::TimePoint now) noexcept {
  s.value = v;
  s.at = now;
  ++s.count;
}

// The unwrapped reading of one motor's position (see PositionUnwrap).
double unwrap_position(PositionUnwrap& u, std::size_t motor, double raw, bool first) noexcept {
  const double delta = raw - u.last_raw[motor];
  if (!first && delta < -protocol::kPositionRolloverRev) ++u.wraps[motor];
  if (!first && delta > protocol::kPositionRolloverRev) --u.wraps[motor];
  u.last_raw[motor] = raw;
  return raw + u.offset_rev(motor);
}

MotorPair unwrap_pair(Measurements& m, const MotorPair& raw) noexcept {
  const bool first = !m.position.received();
  return {unwrap_position(m.unwrap, 0, raw.motor1, first), unwrap_position(m.unwrap, 1, raw.motor2, first)};
}

// An index tick's position on the turn of the counter nearest the motor's current position.
double unwrap_index(const Measurements& m, std::size_t motor, double raw) noexcept {
  double p = raw + m.unwrap.offset_rev(motor);
  if (!m.position.received()) return p;
  const double now = motor == 0 ? m.position.value.motor1 : m.position.value.motor2;
  const double range = 2 * protocol::kPositionRolloverRev;
  if (p - now > protocol::kPositionRolloverRev) p -= range;
  if (now - p > protocol::kPositionRolloverRev) p += range;
  return p;
}
}  // namespace

FrameOutcome apply_frame(Measurements& m, const can::Frame& f, core::TimePoint now) {
  const auto id = f.is_extended() ? std::nullopt : protocol::message_id_from_raw(f.id());
  if (!id || protocol::direction(*id) != protocol::Direction::from_board) {
    ++m.foreign;
    return FrameOutcome::foreign;
  }
  if (f.is_remote() || f.payload().size() != protocol::payload_size(*id)) {
    ++m.rejected;
    return FrameOutcome::rejected;
  }
  switch (*id) {
    case MessageId::status: {
      // Error code 6 is undefined, but it is still the board reporting an error (see Safety).
      store(m.status_byte, f.payload()[0], now);
      if (protocol::error_bits(f.payload()[0]) == protocol::kUndocumentedErrorCode) {
        ++m.undocumented_errors;
        ++m.frames;
        return FrameOutcome::undocumented_error;
      }
      auto s = protocol::decode_status(f);
      if (!s) break;
      store(m.status, s.value(), now);
      ++m.frames;
      return FrameOutcome::status;
    }
    case MessageId::encoder_index: {
      if (f.payload()[4] > 1) break;
      auto e = protocol::decode_encoder_index(f);
      if (!e) break;
      const std::size_t motor = e.value().motor;
      store(m.index[motor], unwrap_index(m, motor, e.value().position_rev), now);
      ++m.frames;
      return FrameOutcome::index;
    }
    default: {
      auto v = protocol::decode_pair(*id, f);
      if (!v) break;
      Stamped<MotorPair>* dst = &m.adc;
      if (*id == MessageId::current) dst = &m.current;
      else if (*id == MessageId::position) dst = &m.position;
      else if (*id == MessageId::velocity) dst = &m.velocity;
      store(*dst, dst == &m.position ? unwrap_pair(m, v.value()) : v.value(), now);
      ++m.frames;
      return FrameOutcome::measurement;
    }
  }
  ++m.rejected;
  return FrameOutcome::rejected;
}

}  // namespace axon::blmc::host
