#include "axon/c4g/apps/sensor_feed.hpp"

#include "axon/net/error.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <numbers>

namespace axon::c4g::apps {

Result<void> parse_feed_datagram(std::string_view text, std::span<double> out, bool degrees) {
  auto separator = [](char c) { return c == ' ' || c == ',' || c == ';' || c == '\t' || c == '\n' || c == '\r'; };
  std::size_t count = 0, i = 0;
  while (i < text.size()) {
    while (i < text.size() && separator(text[i])) ++i;
    if (i == text.size()) break;
    std::size_t end = i;
    while (end < text.size() && !separator(text[end])) ++end;
    const std::string_view token = text.substr(i, end - i);
    if (count == out.size())
      return Error(CoreErrc::invalid_argument, fmt::format("more than {} values in \"{}\"", out.size(), text.substr(0, 80)));
    double v = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc{} || ptr != token.data() + token.size())
      return Error(CoreErrc::invalid_argument, fmt::format("value {} \"{}\" is not a number", count + 1, token.substr(0, 40)));
    if (degrees) v *= std::numbers::pi / 180.0;  // one factor: 1e308 deg stays finite in rad
    if (!std::isfinite(v)) return Error(CoreErrc::invalid_argument, fmt::format("value {} is not finite", count + 1));
    out[count++] = v;
    i = end;
  }
  if (count != out.size())
    return Error(CoreErrc::invalid_argument, fmt::format("{} values, the arm has {} axes", count, out.size()));
  return ok();
}

Result<std::unique_ptr<SensorFeed>> SensorFeed::open(const SensorFeedOptions& options) {
  if (options.axes == 0 || options.axes > kMaxAxes)
    return Error(CoreErrc::invalid_argument, fmt::format("sensor feed: {} axes (1..{})", options.axes, kMaxAxes));
  net::SocketAddress source;  // anyone
  if (!options.source.host.empty()) {
    auto resolved = net::resolve_ipv4(options.source);
    if (!resolved) return Error(resolved.error().code, "sensor feed source: " + resolved.error().detail);
    if (resolved.value().ip == 0)
      return Error(CoreErrc::invalid_argument, fmt::format("sensor feed: the source '{}' names no host", options.source.to_string()));
    source = resolved.value();
  }
  net::UdpOptions uo;
  uo.kernel_timestamps = false;
  auto socket = net::UdpSocket::open(options.listen, uo);
  if (!socket) return Error(socket.error().code, "sensor feed: " + socket.error().detail);
  return std::unique_ptr<SensorFeed>(new SensorFeed(std::move(socket).value(), options, source));
}

SensorFeed::SensorFeed(net::UdpSocket socket, SensorFeedOptions options, net::SocketAddress source)
    : socket_(std::move(socket)), options_(std::move(options)), source_(source) {
  for (auto& v : values_) v.store(0, std::memory_order_relaxed);
  thread_ = std::thread([this] { run(); });
}

SensorFeed::~SensorFeed() {
  stopping_.store(true, std::memory_order_relaxed);
  socket_.interrupt();
  if (thread_.joinable()) thread_.join();
}

void SensorFeed::run() {
  std::array<std::byte, 1500> buffer{};
  std::array<double, kMaxAxes> values{};
  while (!stopping_.load(std::memory_order_relaxed)) {
    auto got = socket_.receive(buffer, std::chrono::nanoseconds(-1));
    if (!got) {
      if (got.error() == net::NetErrc::interrupted || got.error() == net::NetErrc::closed) return;
      continue;  // counted by the socket (receive_errors)
    }
    const auto& d = got.value();
    if (!source_.admits(d.from)) {
      foreign_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    const std::string_view text(reinterpret_cast<const char*>(buffer.data()), d.size);
    auto parsed = d.truncated() ? Result<void>(Error(CoreErrc::invalid_argument, "datagram longer than 1500 bytes"))
                                : parse_feed_datagram(text, std::span<double>(values.data(), options_.axes), options_.degrees);
    if (!parsed) {
      rejected_.fetch_add(1, std::memory_order_relaxed);
      const std::lock_guard lock(error_mutex_);
      last_error_ = fmt::format("from {}: {}", d.from.to_string(), parsed.error().detail);
      continue;
    }
    publish(std::span<const double>(values.data(), options_.axes), d.steady_ns);
  }
}

void SensorFeed::publish(std::span<const double> values, std::int64_t steady_ns) noexcept {
  const std::uint64_t s = seq_.load(std::memory_order_relaxed);
  seq_.store(s + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  for (std::size_t i = 0; i < values.size(); ++i) values_[i].store(values[i], std::memory_order_relaxed);
  stamp_.store(steady_ns, std::memory_order_relaxed);
  seq_.store(s + 2, std::memory_order_release);
  accepted_.fetch_add(1, std::memory_order_relaxed);
}

bool SensorFeed::latest(Reading& out) const noexcept {
  for (int attempt = 0; attempt < 4; ++attempt) {
    const std::uint64_t s1 = seq_.load(std::memory_order_acquire);
    if (s1 & 1u) continue;
    Reading r;
    for (std::size_t i = 0; i < options_.axes; ++i) r.values[i] = values_[i].load(std::memory_order_relaxed);
    r.steady_ns = stamp_.load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (seq_.load(std::memory_order_relaxed) != s1) continue;
    r.sequence = s1 / 2;
    out = r;
    return true;
  }
  return false;
}

std::string SensorFeed::last_error() const {
  const std::lock_guard lock(error_mutex_);
  return last_error_;
}

}  // namespace axon::c4g::apps
