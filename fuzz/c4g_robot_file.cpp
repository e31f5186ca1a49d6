// Fuzzes the YAML form of the simulated controller's robot file (c4g/sim/robot_file.hpp): the
// input is the file's text. Reading gives an initialization packet or an error with a message,
// never a crash or an exception; a packet read must encode to 1200 bytes that decode to the same
// packet, and either make a robot (the table 5.1 checks) or be refused with a message.
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/sim/robot_file.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

using namespace axon::c4g;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto init = sim::init_from_yaml(text, "<fuzz>");
  if (!init) {
    require(!init.error().detail.empty());
    return 0;
  }
  std::array<std::byte, protocol::kInitPacketSize> bytes{};
  if (protocol::encode_init(init.value(), bytes)) {
    auto decoded = protocol::decode_init(bytes);
    require(decoded && decoded.value() == init.value());
  }
  auto robot = sim::robot_from_init(init.value(), "fuzz");
  require(robot || !robot.error().detail.empty());
  return 0;
}
