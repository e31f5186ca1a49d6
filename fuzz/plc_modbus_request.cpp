// Fuzzes what the PLC emulator does with the bytes a Modbus TCP client sends: the request framer
// (fps/plc/request_framer.hpp) cuts the stream, libmodbus answers every request against the
// register map of the instrument, as the emulator does (answers go into a socket pair and are
// drained). Nothing may crash; the framer must cut the input the same way whether it comes in one
// piece or two (cut where the first byte says), hold less than one request once it has nothing
// to give, give only requests request_problem() accepts, and report a broken stream as PlcErrc::io.
#include "axon/fps/plc/error.hpp"
#include "axon/fps/plc/register_map.hpp"
#include "axon/fps/plc/request_framer.hpp"

#include <modbus/modbus.h>

#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

using namespace axon::fps::plc;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

// The requests a framer gives for these pieces, then whether it ended broken.
std::pair<std::vector<std::vector<std::uint8_t>>, bool> frame(std::initializer_list<std::span<const std::uint8_t>> pieces) {
  RequestFramer framer;
  std::vector<std::vector<std::uint8_t>> out;
  bool broken = false;
  for (const auto piece : pieces) {
    framer.feed(piece);
    while (auto r = framer.next()) {
      if (!*r) {
        require(r->error() == PlcErrc::io && !r->error().detail.empty());
        broken = true;
        break;
      }
      require(request_problem(r->value()).empty());
      out.emplace_back(r->value().begin(), r->value().end());
    }
    if (broken) break;
    require(framer.buffered() < kMaxRequestSize);
  }
  return {out, broken};
}

// A server context and the instrument's register map, made once.
struct Server {
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", 0);
  modbus_mapping_t* mapping = nullptr;
  int pair[2] = {-1, -1};
  Server() {
    RegisterMap map;
    mapping = modbus_mapping_new_start_address(0, map.coil_span(), 0, 0, 0, 0, 0, map.input_register_span());
    socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, pair);
    modbus_set_socket(ctx, pair[0]);
    modbus_set_response_timeout(ctx, 0, 1);  // as the emulator: exceptions do not sleep
  }
  void answer(const std::vector<std::uint8_t>& adu) {
    std::array<std::uint8_t, kMaxRequestSize> query{};
    std::copy(adu.begin(), adu.end(), query.begin());
    (void)modbus_reply(ctx, query.data(), static_cast<int>(adu.size()), mapping);
    std::array<std::uint8_t, 1024> sink{};
    while (read(pair[1], sink.data(), sink.size()) > 0) {
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Server server;
  const std::span<const std::uint8_t> input(data, size);
  const auto [whole, whole_broken] = frame({input});
  const std::size_t cut = size == 0 ? 0 : data[0] % (size + 1);
  const auto [split, split_broken] = frame({input.first(cut), input.subspan(cut)});
  require(whole == split && whole_broken == split_broken);
  for (const auto& adu : whole) server.answer(adu);
  return 0;
}
