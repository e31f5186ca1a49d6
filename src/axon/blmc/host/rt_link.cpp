#include "axon/blmc/host/rt_link.hpp"

#include "axon/core/error.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

namespace axon::blmc::host {

namespace {
int make_bell() {
  const int fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (fd < 0) throw Exception(Error(CoreErrc::io, fmt::format("eventfd: {}", std::strerror(errno))));
  return fd;
}
void ring(int fd) noexcept {
  const std::uint64_t one = 1;
  // A full counter (never in practice) or EAGAIN still leaves the fd readable: nothing to do.
  [[maybe_unused]] const auto n = ::write(fd, &one, sizeof one);
}
void clear(int fd) noexcept {
  std::uint64_t v = 0;
  [[maybe_unused]] const auto n = ::read(fd, &v, sizeof v);
}
}  // namespace

RtLink::RtLink(std::size_t capacity) : rx_(capacity), tx_(capacity) {
  rx_bell_ = make_bell();
  try {
    tx_bell_ = make_bell();
  } catch (...) {
    ::close(rx_bell_);
    throw;
  }
}

RtLink::~RtLink() {
  ::close(rx_bell_);
  ::close(tx_bell_);
}

bool RtLink::send(const can::Frame& f) noexcept {
  if (!tx_.push(f)) {
    tx_dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  ring(tx_bell_);
  return true;
}

bool RtLink::receive(can::Frame& out) noexcept { return rx_.pop(out); }

bool RtLink::wait_rx(core::Duration timeout) noexcept {
  pollfd p{rx_bell_, POLLIN, 0};
  // poll() has millisecond resolution; ppoll takes a timespec.
  const auto ns = std::max<std::int64_t>(0, timeout.count());
  timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  const int r = ::ppoll(&p, 1, &ts, nullptr);
  if (r > 0) {
    clear(rx_bell_);
    return true;
  }
  return false;
}

void RtLink::clear_rx_doorbell() noexcept { clear(rx_bell_); }

bool RtLink::deliver(const can::Frame& f) noexcept {
  if (!rx_.push(f)) {
    rx_dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  ring(rx_bell_);
  return true;
}

bool RtLink::take(can::Frame& out) noexcept { return tx_.pop(out); }

void RtLink::clear_tx_doorbell() noexcept { clear(tx_bell_); }

}  // namespace axon::blmc::host
