// Fuzzes the blmc protocol decoders with arbitrary frames and command text.
//
// Input: byte 0 picks the frame kind (bit 0: extended id, bit 1: remote); bytes 1..2 are a raw
// identifier (little-endian, 16 bits, so identifiers wider than 11 bits are tried too); the rest is
// the payload (more than 8 bytes is tried as well) and, read as text, a NAME=value command. Nothing
// may crash; every decoder must accept or reject with a blmc protocol error; whatever decodes must
// encode back to the identical frame or text.
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/error.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/protocol/q24.hpp"
#include "axon/blmc/protocol/status.hpp"
#include "axon/can/frame.hpp"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>

using namespace axon::blmc::protocol;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

template <class R>
void require_blmc_error(const R& r) {
  if (!r) require(r.error().code.category() == protocol_category());
}

void frames(const axon::can::Frame& f) {
  const auto from = decode_from_board(f);
  require_blmc_error(from);
  if (from) {
    require(encode(from.value()).value() == f);
    (void)to_string(from.value());
  }
  const auto to = decode_to_board(f);
  require_blmc_error(to);
  if (to) {
    require(encode(to.value()).value() == f);
    (void)to_string(to.value());
  }
  require(!(from && to));  // no identifier belongs to both directions
  require_blmc_error(decode_status(f));
  require_blmc_error(decode_command(f));
  require_blmc_error(decode_encoder_index(f));
  require_blmc_error(decode_pair(MessageId::current, f));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  const auto fmt = (data[0] & 1) ? axon::can::IdFormat::extended : axon::can::IdFormat::standard;
  const std::uint32_t raw = static_cast<std::uint32_t>(data[1]) | (static_cast<std::uint32_t>(data[2]) << 8);
  const std::span<const std::uint8_t> payload(data + 3, size - 3);

  auto frame = (data[0] & 2) ? axon::can::Frame::remote(raw, fmt, static_cast<std::uint8_t>(payload.size()))
                             : axon::can::Frame::data(raw, fmt, payload);
  if (frame) frames(frame.value());

  // The status byte: defined error codes round-trip, code 6 is rejected.
  const auto st = Status::from_byte(data[0]);
  require(st.has_value() == ((data[0] >> 5) != 6));
  if (st) require(st.value().to_byte() == data[0]);

  // Q24: every int32 converts to a double that converts back exactly.
  if (payload.size() >= 4) {
    std::int32_t q = 0;
    std::memcpy(&q, payload.data(), 4);
    require(to_q24(from_q24(q)).value() == q);
    double d = 0;
    if (payload.size() >= 8) {
      std::memcpy(&d, payload.data(), 8);
      require_blmc_error(to_q24(d));
    }
  }

  // Command text.
  const std::string_view text(reinterpret_cast<const char*>(payload.data()), payload.size());
  const auto cmd = Command::parse(text);
  require_blmc_error(cmd);
  if (cmd) {
    const auto again = Command::parse(cmd.value().to_string());
    require(again.has_value() && again.value() == cmd.value());
    require(decode_command(encode(cmd.value()).value()).value() == cmd.value());
  }
  return 0;
}
