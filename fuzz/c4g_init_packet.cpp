// Fuzzes the c4g initialization packet decoder and what is built from it (axis map, transforms).
//
// Input: the datagram itself (1200 bytes decode; anything else must be a wrong_size error). Nothing
// may crash; a rejection must carry a c4g protocol code; a decoded packet must re-encode to the
// identical 1200 bytes, print, and either build an axis map and per-arm transforms or reject them
// with a c4g code.
#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/error.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/transform.hpp"

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
template <class R>
void require_c4g_error(const R& r) {
  if (!r) require(r.error().code.category() == protocol_category());
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> in(reinterpret_cast<const std::byte*>(data), size);
  const auto init = decode_init(in);
  require_c4g_error(init);
  if (size != kInitPacketSize) require(!init.has_value() && init.error() == ProtocolErrc::wrong_size);
  if (!init) return 0;

  std::array<std::byte, kInitPacketSize> out{};
  require(encode_init(init.value(), out).has_value());
  require(std::memcmp(out.data(), data, kInitPacketSize) == 0);
  (void)to_string(init.value());

  const auto map = AxisMap::from_init(init.value());
  require_c4g_error(map);
  if (map) {
    require(map.value().count() == static_cast<std::size_t>(init.value().open_axes));
    for (std::size_t i = 0; i < map.value().count(); ++i) {
      const AxisRef r = map.value().logical(i);
      require(map.value().open_index(r.arm, r.axis) == i);
    }
  }
  for (std::size_t arm = 1; arm <= kMaxArms; ++arm) {
    const auto t = ArmTransform::from_init(init.value(), arm);
    require_c4g_error(t);
    if (t) {
      const ArmTransform::Vector q = ArmTransform::Vector::Zero(static_cast<Eigen::Index>(t.value().axes()));
      (void)t.value().link_position(t.value().motor_position(q));
    }
  }
  return 0;
}
