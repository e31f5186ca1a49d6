#include "axon/can/bus.hpp"

#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <charconv>

namespace axon::can {

Result<Filter> Filter::parse(std::string_view text) {
  const auto colon = text.find(':');
  auto bad = [&](std::string_view why) {
    return Error(CanErrc::parse_error, fmt::format("filter '{}': {} (expected ID:MASK in hex, e.g. 123:7FF)", text, why));
  };
  if (colon == std::string_view::npos) return bad("no ':'");
  Filter f;
  const std::string_view id = text.substr(0, colon), mask = text.substr(colon + 1);
  auto parse_hex = [](std::string_view s, std::uint32_t& out) {
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out, 16);
    return !s.empty() && ec == std::errc() && p == s.data() + s.size();
  };
  if (!parse_hex(id, f.id) || !parse_hex(mask, f.mask)) return bad("not hexadecimal");
  if (f.id > Frame::kMaxExtendedId || f.mask > Frame::kMaxExtendedId) return bad("id or mask wider than 29 bits");
  f.format = id.size() == 8 ? Format::extended : Format::any;
  return f;
}

const char* to_string(BusState s) noexcept {
  switch (s) {
    case BusState::active: return "active";
    case BusState::error_warning: return "error-warning";
    case BusState::error_passive: return "error-passive";
    case BusState::bus_off: return "bus-off";
    case BusState::closed: return "closed";
  }
  return "?";
}

double BusStats::load(core::TimePoint now, std::uint32_t bitrate) const noexcept {
  const double elapsed = std::chrono::duration<double>(now - opened).count();
  if (elapsed <= 0 || bitrate == 0) return 0.0;
  return static_cast<double>(bits_in + bits_out) / (elapsed * bitrate);
}

Bus::Bus(executor_type ex, std::string name, BusOptions options)
    : executor_(std::move(ex)), name_(std::move(name)), options_(options) {
  stats_.opened = core::SteadyClock::instance().now();
}

// Whoever still waits in receive() or flush() wakes up and finds the bus gone.
Bus::~Bus() {
  waiters_->bus_gone = true;
  wake_receivers();
}

Bus::WaiterRegistration::WaiterRegistration(std::shared_ptr<Waiters> w, asio::steady_timer& t)
    : waiters(std::move(w)), timer(&t) {
  waiters->timers.push_back(timer);
}

Bus::WaiterRegistration::~WaiterRegistration() {
  auto& v = waiters->timers;
  v.erase(std::remove(v.begin(), v.end(), timer), v.end());
}

void Bus::set_filters(std::vector<Filter> filters) { filters_ = std::move(filters); }

void Bus::deliver(Frame frame, std::uint32_t wire_bits) {
  if (state_ == BusState::closed) return;
  if (!filters_.empty() && std::none_of(filters_.begin(), filters_.end(), [&](const Filter& f) { return f.matches(frame); })) {
    ++stats_.rx_filtered;
    return;
  }
  if (rx_.size() >= options_.rx_capacity) {
    ++stats_.rx_dropped;
    return;
  }
  ++stats_.frames_in;
  stats_.bits_in += wire_bits;
  rx_.push_back(frame);
  wake_receivers();
}

void Bus::count_sent(const Frame&, std::uint32_t wire_bits) noexcept {
  ++stats_.frames_out;
  stats_.bits_out += wire_bits;
}

void Bus::set_state(BusState s) noexcept {
  if (s == state_ || state_ == BusState::closed) return;
  if (s == BusState::bus_off) ++stats_.bus_off_events;
  if (s == BusState::error_warning) ++stats_.error_warning_events;
  state_ = s;
  if (s == BusState::closed) wake_receivers();
}

void Bus::close() { set_state(BusState::closed); }

void Bus::wake_receivers() noexcept {
  for (auto* t : waiters_->timers) t->cancel();
}

std::optional<Frame> Bus::try_receive() {
  if (rx_.empty()) return std::nullopt;
  Frame f = rx_.front();
  rx_.pop_front();
  return f;
}

asio::awaitable<Result<void>> Bus::flush(core::Duration timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const auto waiters = waiters_;  // `this` may be gone when the timer fires: see ~Bus
  asio::steady_timer timer(executor_);
  const WaiterRegistration registered(waiters, timer);
  while (tx_pending() > 0) {
    if (state_ == BusState::closed) co_return Error(CanErrc::closed, fmt::format("bus {}: closed while flushing", name_));
    if (std::chrono::steady_clock::now() >= deadline)
      co_return Error(CanErrc::timeout, fmt::format("bus {}: {} frames still waiting to leave", name_, tx_pending()));
    timer.expires_after(std::chrono::microseconds(200));
    boost::system::error_code ec;
    co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    if (waiters->bus_gone) co_return Error(CanErrc::closed, "the bus was destroyed while flushing");
  }
  co_return ok();
}

asio::awaitable<Result<Frame>> Bus::receive() { return receive_until(std::nullopt); }

asio::awaitable<Result<Frame>> Bus::receive(core::Duration timeout) {
  return receive_until(std::chrono::steady_clock::now() + timeout);
}

asio::awaitable<Result<Frame>> Bus::receive_until(std::optional<core::TimePoint> deadline) {
  const auto waiters = waiters_;  // `this` may be gone when the timer fires: see ~Bus
  for (;;) {
    if (auto f = try_receive()) co_return *f;
    if (state_ == BusState::closed) co_return Error(CanErrc::closed, fmt::format("bus {}", name_));
    if (deadline && std::chrono::steady_clock::now() >= *deadline)
      co_return Error(CanErrc::timeout, fmt::format("bus {}", name_));
    asio::steady_timer timer(executor_, deadline ? *deadline : core::TimePoint::max());
    const WaiterRegistration registered(waiters, timer);
    boost::system::error_code ec;
    co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    if (waiters->bus_gone) co_return Error(CanErrc::closed, "the bus was destroyed while a receive() waited");
  }
}

}  // namespace axon::can
