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

namespace {
template <class T>
void store(Stamped<T>& s, const T& v, core::TimePoint now) noexcept {
  s.value = v;
  s.at = now;
  ++s.count;
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
      // Error code 6 is undefined: check the bits here so the common path never builds an error.
      if ((f.payload()[0] >> 5) == 6) break;
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
      store(m.index[e.value().motor], e.value().position_rev, now);
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
      store(*dst, v.value(), now);
      ++m.frames;
      return FrameOutcome::measurement;
    }
  }
  ++m.rejected;
  return FrameOutcome::rejected;
}

}  // namespace axon::blmc::host
