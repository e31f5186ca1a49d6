// Records every datagram the server receives and sends into a pcap file, without slowing the
// real-time cycle.
//
// The cycle thread calls record(): it copies the payload, addresses and wall-clock time into a
// fixed-size slot of a preallocated single-producer/single-consumer queue and returns; nothing
// is allocated, nothing locks, nothing touches the disk. A writer thread drains the queue every
// few milliseconds and writes each datagram with synthetic Ethernet/IPv4/UDP headers (correct
// lengths and checksums) so that capture tools show the real addresses and ports. When the queue
// is full the datagram is dropped and counted, never waited for.
//
// The file uses nanosecond timestamps (pcap magic 0xa1b23c4d) and link type Ethernet.
#pragma once

#include "axon/core/error.hpp"
#include "axon/core/rotating_file.hpp"
#include "axon/net/udp_socket.hpp"

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace axon::c4g::host {

struct PcapOptions {
  std::size_t queue_capacity = 4096;            // datagrams in flight between the cycle and the writer
  std::chrono::milliseconds drain_interval{2};  // how often the writer wakes up when idle
  // A size or age limit (none by default): the writer closes the full capture, renames it PATH.1
  // (older ones PATH.2 ...: core::RotatingFile's naming) and goes on in a fresh PATH, each a
  // complete pcap file with its own header. Never on the cycle thread.
  core::RotationLimits rotation;
};

class PcapRecorder {
 public:
  // Payload bytes kept per datagram: a full Ethernet MTU's worth. Longer datagrams are cut
  // (the capture then shows their true length and the bytes kept).
  static constexpr std::size_t kSnapPayload = 1472;

  // Creates (truncates) the file and starts the writer thread.
  static Result<std::unique_ptr<PcapRecorder>> open(const std::string& path, const PcapOptions& options = {});
  ~PcapRecorder();  // close()
  PcapRecorder(const PcapRecorder&) = delete;
  PcapRecorder& operator=(const PcapRecorder&) = delete;

  // Cycle thread only (single producer). Queues one datagram; false if the queue was full (the
  // datagram is dropped and counted). `wall_ns` is the time to stamp, ns since the epoch.
  bool record(const net::SocketAddress& src, const net::SocketAddress& dst, std::span<const std::byte> payload,
              std::int64_t wall_ns) noexcept;

  // Waits until every datagram queued before the call is in the file (and the file flushed).
  // Not from the cycle thread.
  void flush();
  // Drains the queue, stops the writer and closes the file. Idempotent. Call it once the cycle
  // thread no longer records (after CycleThread::stop()); record() after close() counts a drop.
  void close();

  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] std::uint64_t queued() const noexcept { return queued_.load(std::memory_order_relaxed); }
  // Datagrams in the file(s); queued ones are written, dropped (queue full) or write failures.
  [[nodiscard]] std::uint64_t written() const noexcept {
    const auto failed = write_failures_.load(std::memory_order_relaxed);  // may run ahead of handled_ in a batch
    const auto handled = handled_.load(std::memory_order_acquire);
    return handled > failed ? handled - failed : 0;
  }
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t cut() const noexcept { return cut_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t rotations() const noexcept { return rotations_.load(std::memory_order_relaxed); }
  // Datagrams not written because a rotation failed (the file could not be renamed or reopened).
  [[nodiscard]] std::uint64_t write_failures() const noexcept { return write_failures_.load(std::memory_order_relaxed); }

 private:
  struct Impl;
  PcapRecorder() = default;
  void run();
  // Before writing a frame of `bytes`: a new file when the limits say so. False when no file is open.
  bool rotate_if_due(std::size_t bytes);
  // Renames the files (PATH -> PATH.1 ...) and opens a fresh PATH. False when either failed.
  bool reopen();

  std::string path_;
  PcapOptions options_;
  std::unique_ptr<Impl> impl_;
  std::atomic<std::uint64_t> queued_{0};
  std::atomic<std::uint64_t> handled_{0};  // taken from the queue by the writer
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> cut_{0};
  std::atomic<std::uint64_t> rotations_{0};
  std::atomic<std::uint64_t> write_failures_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> closed_{false};
};

// The first 1200-byte UDP payload of a capture (Ethernet or raw IPv4, UDP): the controller's
// initialization packet as PcapRecorder or tcpdump on an Ethernet interface recorded it.
// invalid_argument naming the file when it cannot be read or holds none.
Result<std::vector<std::byte>> read_init_packet(const std::string& pcap_path);

}  // namespace axon::c4g::host
