#include "axon/can/socketcan_bus.hpp"

#include "axon/can/socketcan_frame.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

namespace axon::can {

namespace {

std::string errno_text(int err) { return fmt::format("{} ({})", std::strerror(err), err); }

// Closes a file descriptor unless released.
class FdGuard {
 public:
  explicit FdGuard(int fd) noexcept : fd_(fd) {}
  FdGuard(const FdGuard&) = delete;
  FdGuard& operator=(const FdGuard&) = delete;
  ~FdGuard() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int get() const noexcept { return fd_; }
  int release() noexcept { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

template <class T>
bool set_option(int fd, int level, int name, const T& value) {
  return ::setsockopt(fd, level, name, &value, sizeof value) == 0;
}

constexpr std::size_t kMaxReadsPerWakeup = 256;
constexpr auto kFirstBackoff = std::chrono::microseconds(100);
constexpr auto kMaxBackoff = std::chrono::milliseconds(5);

}  // namespace

// The socket, shared with the receive coroutine so that it outlives the bus if the coroutine is
// still suspended when the bus goes away. `tx` is a duplicate of the same socket: waiting for
// writability on it can be cancelled (send timeout) without cancelling the receive wait.
struct SocketCanBus::Io {
  explicit Io(const executor_type& ex) : rx(ex), tx(ex) {}
  asio::posix::stream_descriptor rx;
  asio::posix::stream_descriptor tx;
  SocketCanBus* owner = nullptr;
};

SocketCanBus::SocketCanBus(executor_type ex, std::string name, BusOptions options, SocketCanOptions socket_options)
    : Bus(ex, std::move(name), options), socket_options_(std::move(socket_options)), io_(std::make_shared<Io>(ex)) {}

SocketCanBus::~SocketCanBus() {
  close();
  io_->owner = nullptr;
}

Result<std::unique_ptr<SocketCanBus>> SocketCanBus::open(executor_type ex, std::string iface, BusOptions options,
                                                         SocketCanOptions socket_options) {
  if (iface.empty() || iface.size() >= IFNAMSIZ)
    return Error(CanErrc::bad_spec,
                 fmt::format("SocketCAN interface name '{}': must be 1..{} characters", iface, IFNAMSIZ - 1));

  FdGuard fd(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (fd.get() < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPFNOSUPPORT)
      return Error(CanErrc::not_supported,
                   fmt::format("{}: this kernel has no SocketCAN (AF_CAN); load the can/can-raw modules or use a "
                               "CAN@net/socketcand transport",
                               iface));
    if (err == EPROTONOSUPPORT || err == ESOCKTNOSUPPORT)
      return Error(CanErrc::not_supported,
                   fmt::format("{}: this kernel has AF_CAN but no raw CAN sockets (CAN_RAW); load the can-raw "
                               "module or use a CAN@net/socketcand transport",
                               iface));
    return Error(CanErrc::io, fmt::format("{}: cannot create a CAN_RAW socket: {}", iface, errno_text(err)));
  }

  int ifindex = 0;  // 0: every CAN interface
  if (iface != "any") {
    ifindex = static_cast<int>(::if_nametoindex(iface.c_str()));
    if (ifindex == 0)
      return Error(CanErrc::io, fmt::format("no network interface named '{}' (see `ip link show`; a virtual one for "
                                            "tests: ip link add dev {} type vcan && ip link set {} up)",
                                            iface, iface, iface));
  }

  // Options before bind, so that nothing unwanted arrives in between.
  if (socket_options.error_reports) {
    const can_err_mask_t mask = CAN_ERR_MASK;
    if (!set_option(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, mask))
      return Error(CanErrc::io, fmt::format("{}: cannot subscribe to error reports: {}", iface, errno_text(errno)));
  }
  if (socket_options.receive_own) {
    const int on = 1;
    if (!set_option(fd.get(), SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, on))
      return Error(CanErrc::io, fmt::format("{}: cannot enable own-message reception: {}", iface, errno_text(errno)));
  }

  struct sockaddr_can addr {};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(fd.get(), reinterpret_cast<const struct sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    if (err == ENODEV)
      return Error(CanErrc::io, fmt::format("interface '{}' is not a CAN interface", iface));
    return Error(CanErrc::io, fmt::format("{}: cannot bind the CAN socket: {}", iface, errno_text(err)));
  }
  return start(std::move(ex), fd.release(), std::move(iface), options, std::move(socket_options), true, false);
}

Result<std::unique_ptr<SocketCanBus>> SocketCanBus::adopt(executor_type ex, int fd_in, std::string name,
                                                          BusOptions options, SocketCanOptions socket_options) {
  if (fd_in < 0) return Error(CanErrc::io, fmt::format("{}: invalid file descriptor {}", name, fd_in));
  FdGuard fd(fd_in);
  int type = 0, domain = 0;
  socklen_t len = sizeof type;
  if (::getsockopt(fd.get(), SOL_SOCKET, SO_TYPE, &type, &len) != 0)
    return Error(CanErrc::io, fmt::format("{}: fd {} is not a socket: {}", name, fd.get(), errno_text(errno)));
  if (type == SOCK_STREAM)
    return Error(CanErrc::not_supported,
                 fmt::format("{}: fd {} is a stream socket; SocketCAN records need a datagram or seqpacket socket",
                             name, fd.get()));
  len = sizeof domain;
  const bool can_socket = ::getsockopt(fd.get(), SOL_SOCKET, SO_DOMAIN, &domain, &len) == 0 && domain == AF_CAN;
  const int flags = ::fcntl(fd.get(), F_GETFL);
  if (flags < 0 || ::fcntl(fd.get(), F_SETFL, flags | O_NONBLOCK) != 0)
    return Error(CanErrc::io, fmt::format("{}: cannot make fd {} non-blocking: {}", name, fd.get(), errno_text(errno)));
  if (can_socket && socket_options.error_reports) {
    const can_err_mask_t mask = CAN_ERR_MASK;
    (void)set_option(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, mask);
  }
  return start(std::move(ex), fd.release(), std::move(name), options, std::move(socket_options), can_socket,
               type == SOCK_SEQPACKET);
}

Result<std::unique_ptr<SocketCanBus>> SocketCanBus::start(executor_type ex, int fd_in, std::string name,
                                                          BusOptions options, SocketCanOptions socket_options,
                                                          bool can_socket, bool stream_like) {
  FdGuard fd(fd_in);
  FdGuard tx_fd(::fcntl(fd.get(), F_DUPFD_CLOEXEC, 0));
  if (tx_fd.get() < 0) return Error(CanErrc::io, fmt::format("{}: cannot duplicate the socket: {}", name, errno_text(errno)));

  // Receive timestamps: nanoseconds if the kernel has them, else microseconds, else the host clock.
  const int on = 1;
  bool stamps = set_option(fd.get(), SOL_SOCKET, SO_TIMESTAMPNS, on);
  if (!stamps) stamps = set_option(fd.get(), SOL_SOCKET, SO_TIMESTAMP, on);
  // Tell us how many frames the kernel dropped because our receive buffer was full.
  (void)set_option(fd.get(), SOL_SOCKET, SO_RXQ_OVFL, on);

  std::vector<Filter> initial_filters = socket_options.filters;
  std::unique_ptr<SocketCanBus> bus(new SocketCanBus(ex, std::move(name), options, std::move(socket_options)));
  bus->can_socket_ = can_socket;
  bus->stream_like_ = stream_like;
  bus->kernel_timestamps_ = stamps;
  boost::system::error_code ec;
  bus->io_->rx.assign(fd.get(), ec);
  if (ec) return Error(CanErrc::io, fmt::format("{}: cannot watch the socket: {}", bus->name(), ec.message()));
  fd.release();
  bus->io_->tx.assign(tx_fd.get(), ec);
  if (ec) return Error(CanErrc::io, fmt::format("{}: cannot watch the socket: {}", bus->name(), ec.message()));
  tx_fd.release();
  bus->io_->owner = bus.get();
  bus->set_filters(std::move(initial_filters));
  asio::co_spawn(ex, read_loop(bus->io_), asio::detached);
  spdlog::debug("socketcan {}: open ({}{})", bus->name(), can_socket ? "CAN_RAW socket" : "adopted socket",
                stamps ? ", kernel timestamps" : "");
  return bus;
}

void SocketCanBus::close() {
  if (!is_open()) return;
  Bus::close();
  boost::system::error_code ec;
  io_->rx.close(ec);
  io_->tx.close(ec);
  for (auto* t : tx_queue_) t->cancel();
  if (tx_backoff_) tx_backoff_->cancel();
}

void SocketCanBus::set_filters(std::vector<Filter> filters) {
  Bus::set_filters(std::move(filters));
  if (can_socket_ && is_open()) apply_kernel_filters();
}

void SocketCanBus::apply_kernel_filters() {
  const auto wanted = socketcan::to_kernel_filters(filters());
  std::vector<struct can_filter> raw(wanted.size());
  std::transform(wanted.begin(), wanted.end(), raw.begin(),
                 [](const socketcan::KernelFilter& k) { return can_filter{k.id, k.mask}; });
  const auto size = static_cast<socklen_t>(raw.size() * sizeof(struct can_filter));
  if (::setsockopt(io_->rx.native_handle(), SOL_CAN_RAW, CAN_RAW_FILTER, raw.data(), size) != 0)
    spdlog::warn("socketcan {}: the kernel refused {} receive filter(s) ({}); filtering in user space only", name(),
                 raw.size(), errno_text(errno));
}

asio::awaitable<void> SocketCanBus::read_loop(std::shared_ptr<Io> io) {
  for (;;) {
    boost::system::error_code ec;
    co_await io->rx.async_wait(asio::posix::stream_descriptor::wait_read, asio::redirect_error(asio::use_awaitable, ec));
    SocketCanBus* bus = io->owner;
    if (bus == nullptr || !bus->is_open()) co_return;
    if (ec) {
      ++bus->sc_stats_.io_errors;
      spdlog::error("socketcan {}: waiting for frames failed: {}; closing", bus->name(), ec.message());
      bus->close();
      co_return;
    }
    if (!bus->drain()) co_return;
  }
}

bool SocketCanBus::drain() {
  const int fd = io_->rx.native_handle();
  for (std::size_t i = 0; i < kMaxReadsPerWakeup; ++i) {
    // Room for more than a CAN FD record, so that any oversized record is seen whole and refused.
    std::array<std::uint8_t, 128> buf;
    alignas(struct cmsghdr) std::array<char, CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(struct timeval)) +
                                                 CMSG_SPACE(sizeof(std::uint32_t)) + 64>
        control;
    struct iovec iov {buf.data(), buf.size()};
    struct msghdr msg {};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control.data();
    msg.msg_controllen = control.size();
    const ssize_t n = ::recvmsg(fd, &msg, MSG_DONTWAIT);
    if (n < 0) {
      const int err = errno;
      if (err == EAGAIN || err == EWOULDBLOCK) return true;
      if (err == EINTR) continue;
      ++sc_stats_.io_errors;
      if (err == ENETDOWN) {
        // Reported once when the interface goes down; it may come back up.
        spdlog::warn("socketcan {}: interface went down (ip link set {} up)", name(), name());
        continue;
      }
      spdlog::error("socketcan {}: receive failed: {}; closing", name(), errno_text(err));
      close();
      return false;
    }
    if (n == 0 && stream_like_) {
      spdlog::info("socketcan {}: peer closed the socket", name());
      close();
      return false;
    }

    std::optional<core::WallTime> stamp;
    for (struct cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SCM_TIMESTAMPNS && c->cmsg_len >= CMSG_LEN(sizeof(struct timespec))) {
        struct timespec ts {};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        stamp = std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec);
      } else if (c->cmsg_type == SCM_TIMESTAMP && c->cmsg_len >= CMSG_LEN(sizeof(struct timeval))) {
        struct timeval tv {};
        std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
        stamp = std::chrono::seconds(tv.tv_sec) + std::chrono::microseconds(tv.tv_usec);
      } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
        std::uint32_t drops = 0;
        std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
        const std::uint32_t fresh = drops - kernel_drops_seen_;  // the kernel's counter wraps
        if (fresh != 0) {
          kernel_drops_seen_ = drops;
          sc_stats_.kernel_rx_dropped += fresh;
          mutable_stats().rx_dropped += fresh;
          spdlog::warn("socketcan {}: the kernel dropped {} frame(s): this process reads too slowly", name(), fresh);
        }
      }
    }
    if (stamp && stamp->count() == 0) stamp.reset();

    // The buffer holds more than a CAN FD record, so anything truncated is too long to be one.
    auto decoded = (msg.msg_flags & MSG_TRUNC)
                       ? Result<socketcan::Decoded>(Error(CanErrc::invalid_length,
                                                          fmt::format("SocketCAN record over {} bytes", buf.size())))
                       : socketcan::decode(std::span<const std::uint8_t>(buf.data(), static_cast<std::size_t>(n)));
    handle_record(std::move(decoded), stamp, (msg.msg_flags & MSG_DONTROUTE) != 0);
    if (!is_open()) return false;
  }
  return true;
}

void SocketCanBus::handle_record(Result<socketcan::Decoded> decoded, std::optional<core::WallTime> stamp,
                                 bool local_origin) {
  if (!decoded) {
    ++mutable_stats().protocol_errors;
    if (!bad_record_logged_) {
      bad_record_logged_ = true;
      spdlog::warn("socketcan {}: dropped a bad record: {} (further ones are only counted)", name(),
                   decoded.error().message());
    }
    return;
  }
  if (auto* frame = std::get_if<Frame>(&decoded.value())) {
    if (!stamp) {
      ++sc_stats_.timestamp_fallbacks;
      stamp = core::SteadyClock::instance().wall();
    }
    frame->set_timestamp(*stamp);
    // A frame from another node shows the controller is back on the bus, even if the restart
    // report was lost. Frames looped back from this host (MSG_DONTROUTE) prove nothing.
    if (state() == BusState::bus_off && !local_origin) {
      spdlog::info("socketcan {}: receiving again after bus-off", name());
      set_state(BusState::active);
    }
    deliver(*frame);
    return;
  }
  handle_error_report(std::get<socketcan::ErrorReport>(decoded.value()));
}

void SocketCanBus::handle_error_report(const socketcan::ErrorReport& report) {
  using socketcan::ErrorClass;
  ++mutable_stats().error_frames;
  if (report.controller_rx_overflow()) {
    ++sc_stats_.controller_rx_overflows;
    ++mutable_stats().rx_dropped;
  }
  if (report.controller_tx_overflow()) {
    ++sc_stats_.controller_tx_overflows;
    ++mutable_stats().tx_dropped;
  }
  if (report.has(ErrorClass::lost_arbitration)) ++sc_stats_.lost_arbitration;
  if (report.has(ErrorClass::bus_error)) ++sc_stats_.bus_errors;
  if (report.has(ErrorClass::no_ack)) ++sc_stats_.no_ack;
  if (report.has(ErrorClass::tx_timeout)) ++sc_stats_.tx_timeout_reports;
  if (report.has(ErrorClass::restarted)) ++sc_stats_.restarts;
  if (auto c = report.tx_error_counter()) sc_stats_.tx_error_counter = c;
  if (auto c = report.rx_error_counter()) sc_stats_.rx_error_counter = c;

  const BusState before = state();
  if (auto s = report.state()) set_state(*s);
  if (state() != before) {
    const auto level = state() == BusState::active ? spdlog::level::info : spdlog::level::warn;
    spdlog::log(level, "socketcan {}: {} -> {} ({})", name(), to_string(before), to_string(state()), report.describe());
  } else {
    spdlog::debug("socketcan {}: error report: {}", name(), report.describe());
  }
}

void SocketCanBus::release_tx() noexcept {
  if (tx_queue_.empty()) {
    tx_busy_ = false;
    return;
  }
  // Hand the turn straight to the next sender: it stays busy, so no newcomer overtakes.
  asio::steady_timer* next = tx_queue_.front();
  tx_queue_.pop_front();
  next->cancel();
}

asio::awaitable<Result<void>> SocketCanBus::send(const Frame& frame_in) {
  const Frame frame = frame_in;
  if (!is_open()) co_return Error(CanErrc::closed, fmt::format("socketcan {}: send {}", name(), frame.to_string()));
  if (state() == BusState::bus_off)
    co_return Error(CanErrc::bus_off, fmt::format("socketcan {}: send {}", name(), frame.to_string()));
  const socketcan::Record record = socketcan::encode(frame);
  const auto deadline = std::chrono::steady_clock::now() + socket_options_.tx_timeout;

  struct Waiting {
    std::size_t& n;
    explicit Waiting(std::size_t& count) : n(count) { ++n; }
    ~Waiting() { --n; }
  } waiting{tx_waiting_};

  auto overflow = [&](std::string_view why) {
    ++sc_stats_.tx_timeouts;
    ++mutable_stats().tx_dropped;
    const auto code = state() == BusState::bus_off ? CanErrc::bus_off : CanErrc::tx_overflow;
    return Error(code, fmt::format("socketcan {}: {} not sent within {} ms: {}", name(), frame.to_string(),
                                   std::chrono::duration_cast<std::chrono::milliseconds>(socket_options_.tx_timeout).count(),
                                   why));
  };

  // Take our turn behind the senders already waiting, so frames leave in call order.
  if (tx_busy_) {
    asio::steady_timer turn(get_executor(), deadline);
    tx_queue_.push_back(&turn);
    boost::system::error_code ec;
    co_await turn.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    const auto it = std::find(tx_queue_.begin(), tx_queue_.end(), &turn);
    if (it != tx_queue_.end()) {  // not handed the turn: timed out or closed
      tx_queue_.erase(it);
      if (!is_open()) co_return Error(CanErrc::closed, fmt::format("socketcan {}: send {}", name(), frame.to_string()));
      co_return overflow("frames queued before it did not leave");
    }
  } else {
    tx_busy_ = true;
  }
  struct Turn {
    SocketCanBus& bus;
    ~Turn() { bus.release_tx(); }
  } turn{*this};

  const int fd = io_->rx.native_handle();
  core::Duration backoff = kFirstBackoff;
  for (;;) {
    if (!is_open()) co_return Error(CanErrc::closed, fmt::format("socketcan {}: send {}", name(), frame.to_string()));
    ssize_t n = ::send(fd, record.data(), record.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n < 0 && errno == ENOTSOCK) n = ::write(fd, record.data(), record.size());
    if (n == static_cast<ssize_t>(record.size())) {
      count_sent(frame);
      co_return ok();
    }
    const int err = n < 0 ? errno : EMSGSIZE;
    if (err == EINTR) continue;
    if (err != EAGAIN && err != EWOULDBLOCK && err != ENOBUFS) {
      ++sc_stats_.io_errors;
      if (err == ENETDOWN)
        co_return Error(CanErrc::io, fmt::format("socketcan {}: interface is down (ip link set {} up)", name(), name()));
      co_return Error(CanErrc::io, fmt::format("socketcan {}: send {}: {}", name(), frame.to_string(), errno_text(err)));
    }
    // The kernel queue is full.
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) co_return overflow(err == ENOBUFS ? "interface transmit queue full (ENOBUFS)" : "socket buffer full");
    ++sc_stats_.tx_retries;
    asio::steady_timer timer(get_executor());
    tx_backoff_ = &timer;
    struct Clear {
      asio::steady_timer*& slot;
      ~Clear() { slot = nullptr; }
    } clear{tx_backoff_};
    boost::system::error_code ec;
    if (err == ENOBUFS) {
      // The interface queue is full; the socket itself still looks writable, so poll with backoff.
      timer.expires_after(std::min<core::Duration>(backoff, deadline - now));
      backoff = std::min<core::Duration>(backoff * 2, kMaxBackoff);
      co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    } else {
      // The socket buffer is full: wait until it drains, or the deadline.
      timer.expires_at(deadline);
      timer.async_wait([io = io_](const boost::system::error_code& e) {
        if (!e) {
          boost::system::error_code ignored;
          io->tx.cancel(ignored);
        }
      });
      co_await io_->tx.async_wait(asio::posix::stream_descriptor::wait_write,
                                  asio::redirect_error(asio::use_awaitable, ec));
      timer.cancel();
    }
  }
}

}  // namespace axon::can
