// An emulated Ixxat CAN@net NT 420 gateway: a TCP server speaking the CAN@net ASCII protocol
// (can/cannet_codec.hpp) in front of up to four channels taken from a BusProvider (virtual buses
// in tests and simulations). Hosts written for the real gateway run against it unchanged.
//
// Behaviour (docs/can-cannet.md has the details):
// - One client at a time. A new connection replaces the current one, whose socket is closed, and
//   resets the per-connection state: every channel back to uninitialised, stopped, filters cleared,
//   no bus-off or error-warning.
// - Commands are answered as the device does: "R ok", "R ERR <n> <text>" for anything refused or
//   unreadable (the connection stays up), "R CAN b <BEOTI> <free>" for CAN b STATUS, the identify
//   and version texts for DEV IDENTIFY / DEV VERSION.
// - Frames flow only on started channels that are not bus-off; a frame from the host on another
//   channel is discarded (counted), as the device does.
// - Transmit FIFO: each channel's bus endpoint is opened with tx_capacity = tx_fifo (100). A frame
//   the endpoint refuses (tx_overflow) is dropped and counted, and, unless report_tx_overflow is
//   off, reported to the client as "E b TXOVERFLOW 1" (a real gateway drops silently; only CAN b
//   STATUS shows its FIFO filling up).
// - Receive filters (CAN b FILTER ...): entries are kept per id format; a frame passes when its
//   format has no entries or one entry matches. The field set-up (CLEAR, ADD EXT 0 0) passes all.
// - Fault hooks put a channel bus-off or in error-warning and send the device's events.
//
// Hostile peers (docs/reliability.md): the bytes queued for the client stay within
// max_output_bytes plus one line. Bus frames beyond it are dropped (output_drops, flag O of the
// status); a client that sends commands without reading the answers is not read from (its
// commands wait in the kernel) until it has read. A partial line is held up to kMaxLineLength;
// a longer one is answered with one R ERR and skipped. The first R ERR of a connection is logged
// at warning level, the next ones at debug level. Connections replacing each other (the newest
// wins, as on the device) cost nothing: the old socket is closed at once; a takeover is a warning
// when the replaced client had said anything, else a debug line (a flood of connections that
// say nothing does not flood the log).
//
// Threading: everything runs on the executor given to the constructor (the provider's buses must
// live on it too).
#pragma once

#include "axon/can/cannet_codec.hpp"
#include "axon/can/provider.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/any_io_executor.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace axon::can {

struct CanNetEmulatorOptions {
  std::string bind_address = "127.0.0.1";
  std::uint16_t port = cannet::kDefaultPort;  // 0: an ephemeral port (see local_endpoint())
  std::string identify = "CAN@net NT 420";    // answer to DEV IDENTIFY
  std::string version = "V1.5.0";             // answer to DEV VERSION
  std::uint32_t tx_fifo = cannet::kTxFifoCapacity;
  bool report_tx_overflow = true;             // "E b TXOVERFLOW n" on drops (false: silent, like the device)
  std::size_t rx_capacity = 65536;            // frames each channel endpoint queues from the bus
  std::size_t max_output_bytes = 1 << 20;     // queued for a slow client before bus frames are dropped (flag O)
};

struct CanNetEmulatorStats {
  std::uint64_t connections = 0;        // accepted
  std::uint64_t replaced = 0;           // closed because a newer client connected
  std::uint64_t commands = 0;           // command lines answered
  std::uint64_t error_replies = 0;      // of which with R ERR
  std::uint64_t frames_to_bus = 0;      // client frames handed to a channel's bus
  std::uint64_t frames_to_client = 0;   // bus frames sent to the client
  std::uint64_t bus_frames_discarded = 0;  // bus frames while no client, or the channel stopped or bus-off
  std::uint64_t tx_overflow_drops = 0;  // client frames dropped: transmit FIFO full
  std::uint64_t not_running_drops = 0;  // client frames discarded: channel stopped or bus-off
  std::uint64_t output_drops = 0;       // bus frames dropped: the client did not read fast enough
  std::uint64_t filtered = 0;           // bus frames the channel's filters held back
  std::uint64_t output_high_water = 0;  // most bytes ever queued for a client's socket
};

class CanNetGatewayEmulator {
 public:
  // channels[i] is the provider channel behind gateway channel i + 1 (at most 4; an empty name
  // leaves that channel out). Nothing is opened or bound until start().
  CanNetGatewayEmulator(asio::any_io_executor executor, BusProvider& provider, std::vector<std::string> channels,
                        CanNetEmulatorOptions options = {});
  ~CanNetGatewayEmulator();
  CanNetGatewayEmulator(const CanNetGatewayEmulator&) = delete;
  CanNetGatewayEmulator& operator=(const CanNetGatewayEmulator&) = delete;

  // Opens the channel endpoints, binds and starts accepting. Errors: bad_spec (channel names),
  // io (bind/listen).
  Result<void> start();
  // Closes the client connection, the listening socket and the channel endpoints.
  void stop();
  // The same as the device losing power: the client's connection is reset (RST), not closed in
  // order. A host sees a read error (a real gateway's host sees it once it sends, or by TCP
  // keep-alive), not the orderly close by which a gateway hands itself to a newer client.
  void power_off();

  // Where it listens (the actual port when options.port was 0).
  [[nodiscard]] net::Endpoint local_endpoint() const;
  [[nodiscard]] bool has_client() const noexcept;
  [[nodiscard]] const CanNetEmulatorStats& stats() const noexcept;
  // The state CAN b STATUS would report.
  [[nodiscard]] cannet::ReplyStatus status(int channel) const;

  // Fault hooks. bus_off: the channel stops forwarding both ways until restarted (CAN b START or
  // INIT) and the client gets "E b BUSOFF SET". error_warning: "E b ERRORWARNING SET|RESET".
  void inject_bus_off(int channel);
  void inject_error_warning(int channel, bool set);
  // Sends a raw line to the client (a '\n' is added): for tests of hosts facing a misbehaving
  // gateway.
  void send_raw(std::string_view line);

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace axon::can
