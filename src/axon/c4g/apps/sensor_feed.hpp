// A live correction feed for `correct` (mode 7): an external sensor sends one UDP datagram per
// measurement, and the cycle thread reads the latest values without locks.
//
// Datagram format (text, what a script or `nc -u` produces): the link-side correction of each axis
// of the arm, separated by spaces, commas, semicolons or tabs, optionally ending in a newline, e.g.
// "0.001 0 -0.0005 0 0 0". Units are radians, or degrees when the feed is opened with
// `degrees = true`. A datagram with the wrong number of values, something that is not a number, or
// a non-finite value is rejected and counted (last_error() says why); the previous values stay.
// With `source` set, datagrams from any other sender are foreign: counted (foreign()) and dropped
// unread, as the server does with a stranger's packets.
//
// Threads: a receive thread owns the socket and publishes through a sequence lock (atomics only).
// latest() runs on the cycle thread: no allocation, no lock, bounded retries.
#pragma once

#include "axon/c4g/host/session_peer.hpp"
#include "axon/core/error.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/net/udp_socket.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <thread>

namespace axon::c4g::apps {

struct SensorFeedOptions {
  net::Endpoint listen{"127.0.0.1", 0};
  net::Endpoint source{"", 0};  // the sensor's HOST[:PORT]: only it is read (empty host: anyone; port 0: any port)
  std::size_t axes = 6;       // values per datagram
  bool degrees = false;
};

// Parses one datagram into `out` (size = expected count), converting degrees when asked.
// invalid_argument naming the problem otherwise.
Result<void> parse_feed_datagram(std::string_view text, std::span<double> out, bool degrees);

class SensorFeed {
 public:
  static constexpr std::size_t kMaxAxes = 10;

  // Binds and starts the receive thread. Errors: bad axis count, bind failure.
  static Result<std::unique_ptr<SensorFeed>> open(const SensorFeedOptions& options);
  ~SensorFeed();
  SensorFeed(const SensorFeed&) = delete;
  SensorFeed& operator=(const SensorFeed&) = delete;

  struct Reading {
    std::array<double, kMaxAxes> values{};  // link side [rad]
    std::int64_t steady_ns = 0;             // CLOCK_MONOTONIC at arrival; 0: nothing yet
    std::uint64_t sequence = 0;             // accepted datagrams so far
  };
  // The latest accepted values. Cycle thread: lock-free; false when a consistent copy could not be
  // taken in a few tries (the writer was busy): keep the previous reading then.
  bool latest(Reading& out) const noexcept;

  [[nodiscard]] std::uint16_t port() const noexcept { return socket_.local_port(); }
  [[nodiscard]] std::size_t axes() const noexcept { return options_.axes; }
  [[nodiscard]] std::uint64_t accepted() const noexcept { return accepted_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t rejected() const noexcept { return rejected_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t foreign() const noexcept { return foreign_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::string last_error() const;

 private:
  SensorFeed(net::UdpSocket socket, SensorFeedOptions options, net::SocketAddress source);
  void run();
  void publish(std::span<const double> values, std::int64_t steady_ns) noexcept;

  net::UdpSocket socket_;
  SensorFeedOptions options_;
  std::atomic<std::uint64_t> seq_{0};  // odd while the writer is in the middle of an update
  std::array<std::atomic<double>, kMaxAxes> values_{};
  std::atomic<std::int64_t> stamp_{0};
  std::atomic<std::uint64_t> accepted_{0}, rejected_{0}, foreign_{0};
  host::SessionPeer source_;  // only its admits(): the allowed sender
  mutable std::mutex error_mutex_;  // receive thread and readers of last_error(), never the cycle
  std::string last_error_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace axon::c4g::apps
