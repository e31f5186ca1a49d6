// Fuzzes the c4g cyclic packet decoder with arbitrary datagrams.
//
// Input: byte 0 picks the axis count the decoder is told to expect (0..21; values past 21 mean "take
// the size's count"); the rest is the datagram. Nothing may crash; a rejection must carry a c4g
// protocol code; whatever decodes must re-encode to the identical bytes (except -0.0/NaN payload
// differences, which cannot occur since non-finite floats are rejected) and pass the mode and safety
// helpers without trouble.
#include "axon/c4g/protocol/error.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/protocol/safety.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

using namespace axon::c4g::protocol;

namespace {
void require(bool ok) {
  if (!ok) __builtin_trap();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::size_t want = data[0];
  const std::span<const std::byte> in(reinterpret_cast<const std::byte*>(data + 1), size - 1);

  Packet pkt;
  const Fault f = want <= 21 ? decode_packet(in, pkt, want) : decode_packet(in, pkt);
  require(f.ok() == (to_result(f).has_value()));
  if (!f.ok()) {
    require(to_error(f).code.category() == protocol_category());
    return 0;
  }
  require(pkt.count >= 1 && pkt.count <= kMaxAxes);
  require(in.size() == packet_size(pkt.count));
  require(classify(in.size()) == DatagramKind::cyclic);

  std::array<std::byte, kMaxPacketSize> out{};
  require(encode_packet(pkt, out).ok());
  require(std::memcmp(out.data(), in.data(), in.size()) == 0);

  (void)to_string(pkt);
  (void)check_modes(pkt);
  for (const Axis& a : pkt.open_axes()) (void)mode_name(a.mode);
  std::array<float, kMaxAxes> limits{};
  limits.fill(1.0f);
  (void)first_following_error(pkt, limits);
  saturate_currents(pkt, limits);
  for (const Axis& a : pkt.open_axes()) require(a.d5 >= -1.0f && a.d5 <= 1.0f);
  return 0;
}
