// Test support for the hostile-peer tests of every server (docs/reliability.md): a raw TCP peer
// on loopback that sends exactly what a test says and reads only when told (so it can play the
// client that never reads, the one that goes silent half-way, the one that sends garbage), plus a
// capture counting the warnings logged, the process figures the tests check (open descriptors,
// resident memory) and a bounded wait.
// Plain POSIX and blocking: the server under test runs on a thread of its own.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace axon::hostile {

using namespace std::chrono_literals;

// Waits until pred() holds or `limit` passes (polling every few ms); returns pred().
template <class Pred>
bool wait_until(Pred pred, std::chrono::milliseconds limit = 5000ms) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!pred()) {
    if (std::chrono::steady_clock::now() >= end) return pred();
    std::this_thread::sleep_for(2ms);
  }
  return true;
}

// The median of n calls of f() (a round trip in microseconds, say).
template <class F>
double median_of(int n, F f) {
  std::vector<double> t;
  for (int i = 0; i < n; ++i) t.push_back(f());
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

class RawPeer {
 public:
  // Connects to 127.0.0.1:port. `receive_buffer` > 0 shrinks the socket's receive buffer first,
  // so a peer that never reads fills up quickly.
  explicit RawPeer(std::uint16_t port, int receive_buffer = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (receive_buffer > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    const int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL, 0) | O_NONBLOCK);
  }
  ~RawPeer() { close(); }
  RawPeer(const RawPeer&) = delete;
  RawPeer& operator=(const RawPeer&) = delete;

  [[nodiscard]] bool connected() const noexcept { return connected_; }
  [[nodiscard]] int fd() const noexcept { return fd_; }

  // Sends what the socket takes right now; the number of bytes taken (0 when full or broken).
  std::size_t send_some(std::string_view bytes) {
    const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n < 0) broken_ = broken_ || (errno != EAGAIN && errno != EWOULDBLOCK);
    return n > 0 ? static_cast<std::size_t>(n) : 0;
  }
  // Sends all of it, waiting up to `limit` for room; false if the connection broke or stayed full.
  bool send_all(std::string_view bytes, std::chrono::milliseconds limit = 5000ms) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!bytes.empty()) {
      bytes.remove_prefix(send_some(bytes));
      if (broken_ || std::chrono::steady_clock::now() >= end) return bytes.empty();
      if (!bytes.empty()) wait(POLLOUT, 10ms);
    }
    return true;
  }
  // Whether an earlier send found the connection broken (reset or closed by the server).
  [[nodiscard]] bool broken() const noexcept { return broken_; }

  // Reads until `until` is in what arrived (or the connection ends, or `limit` passes); all read.
  std::string read_until(std::string_view until, std::chrono::milliseconds limit = 5000ms) {
    std::string got;
    const auto end = std::chrono::steady_clock::now() + limit;
    while (got.find(until) == std::string::npos && std::chrono::steady_clock::now() < end) {
      if (!read_some(got, 10ms)) break;
    }
    return got;
  }
  // Reads until at least `n` bytes arrived (or the connection ends, or `limit` passes); all read.
  std::string read_at_least(std::size_t n, std::chrono::milliseconds limit = 5000ms) {
    std::string got;
    const auto end = std::chrono::steady_clock::now() + limit;
    while (got.size() < n && std::chrono::steady_clock::now() < end) {
      if (!read_some(got, 10ms)) break;
    }
    return got;
  }
  // Whether the server closed the connection within `limit` (what arrives meanwhile is dropped).
  bool closed_by_server(std::chrono::milliseconds limit = 5000ms) {
    std::string ignored;
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      ignored.clear();
      if (!read_some(ignored, 10ms)) return true;
    }
    return false;
  }

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  // Appends what arrives within `limit`; false once the connection has ended.
  bool read_some(std::string& out, std::chrono::milliseconds limit) {
    wait(POLLIN, limit);
    char buf[4096];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n > 0) out.append(buf, static_cast<std::size_t>(n));
    return n > 0 || (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK));
  }
  void wait(short events, std::chrono::milliseconds limit) {
    pollfd p{fd_, events, 0};
    ::poll(&p, 1, static_cast<int>(limit.count()));
  }

  int fd_ = -1;
  bool connected_ = false;
  bool broken_ = false;
};

// Collects the warnings logged while it lives (on the default logger).
struct WarningLog {
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(4096);
  WarningLog() { spdlog::default_logger()->sinks().push_back(sink); }
  ~WarningLog() { std::erase(spdlog::default_logger()->sinks(), sink); }
  WarningLog(const WarningLog&) = delete;
  WarningLog& operator=(const WarningLog&) = delete;
  // How many contain `part`.
  [[nodiscard]] std::size_t count(std::string_view part) const {
    std::size_t n = 0;
    for (const auto& m : sink->last_raw()) {
      const std::string_view text(m.payload.data(), m.payload.size());
      if (m.level == spdlog::level::warn && text.find(part) != std::string_view::npos) ++n;
    }
    return n;
  }
};

// Descriptors this process has open now.
inline std::size_t open_descriptors() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

// This process's resident memory in kB (VmRSS), 0 if unknown.
inline long resident_kb() {
  std::ifstream in("/proc/self/status");
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") {
      long kb = 0;
      in >> kb;
      return kb;
    }
    in.ignore(4096, '\n');
  }
  return 0;
}

}  // namespace axon::hostile
