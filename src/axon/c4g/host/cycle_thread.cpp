#include "axon/c4g/host/cycle_thread.hpp"
#include "axon/core/counter.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <time.h>

#include <cstring>
#include <future>
#include <iterator>

namespace axon::c4g::host {

namespace {

std::int64_t clock_ns(clockid_t id) noexcept {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Touches a stack region once so that the cycle never page-faults on it (with mlockall it stays).
void prefault_stack() noexcept {
  volatile unsigned char block[64 * 1024];
  for (std::size_t i = 0; i < sizeof block; i += 4096) block[i] = 0;
}

using core::bump;

}  // namespace

CycleThread::CycleThread(net::UdpSocket socket, CycleHandler& handler, const CycleOptions& options,
                         PcapRecorder* recorder)
    : socket_(std::move(socket)),
      handler_(handler),
      options_(options),
      recorder_(recorder),
      rx_(options.max_datagram),
      tx_(options.max_reply),
      timing_(options.timing),
      wakeup_(options.timing.bucket_width_ns, options.timing.buckets),
      reply_latency_(options.timing.bucket_width_ns, options.timing.buckets) {}

CycleThread::~CycleThread() { stop(); }

core::RealtimeReport CycleThread::start() {
  if (thread_.joinable()) return report_;
  stop_.store(false, std::memory_order_release);
  socket_.clear_interrupt();
  std::promise<core::RealtimeReport> ready;
  auto done = ready.get_future();
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this, &ready] {
    auto report = core::apply_realtime(options_.realtime);
    prefault_stack();
    ready.set_value(std::move(report));
    run();
    running_.store(false, std::memory_order_release);
  });
  report_ = done.get();
  return report_;
}

void CycleThread::stop() {
  stop_.store(true, std::memory_order_release);
  socket_.interrupt();
  if (thread_.joinable()) thread_.join();
}

Result<net::Datagram> CycleThread::receive_until(std::int64_t deadline_ns) {
  if (deadline_ns < 0) return socket_.receive(rx_, std::chrono::nanoseconds(-1));
  const std::int64_t left = deadline_ns - clock_ns(CLOCK_MONOTONIC);
  // Past the deadline: a timeout even if datagrams are queued (a flood of refused ones must not
  // hide the silence of the accepted sender).
  if (left <= 0) return Error(net::NetErrc::timeout);
  return socket_.receive(rx_, std::chrono::nanoseconds(left));
}

void CycleThread::run() {
  bool first = true;
  auto deadline_after = [&](std::int64_t from_ns) -> std::int64_t {
    const auto wait = first ? options_.first_packet_timeout : options_.cycle_timeout;
    return wait.count() < 0 ? -1 : from_ns + wait.count();
  };
  std::int64_t deadline = deadline_after(clock_ns(CLOCK_MONOTONIC));
  while (!stop_.load(std::memory_order_acquire)) {
    auto r = receive_until(deadline);
    if (!r) {
      if (r.error() == net::NetErrc::interrupted) break;
      if (r.error() == net::NetErrc::timeout) {
        bump(counters_.timeouts);
        // A silence is not a jitter sample: the next inter-step series starts afresh.
        timing_.restart_inter_step();
        handler_.on_timeout(first);
        deadline = deadline_after(clock_ns(CLOCK_MONOTONIC));
      } else {
        bump(counters_.receive_errors);
      }
      continue;
    }
    const net::Datagram& d = r.value();
    if (!handler_.accepts(std::span<const std::byte>(rx_.data(), d.size), d)) {
      bump(counters_.refused);
      continue;
    }
    first = false;
    deadline = deadline_after(d.steady_ns);
    serve(d);
  }
}

void CycleThread::serve(const net::Datagram& d) {
  const std::span<const std::byte> request(rx_.data(), d.size);
  if (recorder_) recorder_->record(d.from, d.to, request, d.wall_ns);
  if (d.kernel_timestamp) wakeup_.add(d.wakeup_latency_ns);

  const std::size_t n = std::min(handler_.on_packet(request, d, tx_), tx_.size());
  bump(counters_.cycles);
  if (n == 0) {
    bump(counters_.silent);
    return;
  }
  const std::span<const std::byte> reply(tx_.data(), n);
  // The capture stamps the answer as it leaves: before the send, so that it never appears after
  // a next request the peer sent in reaction to it.
  const std::int64_t wall_send = recorder_ ? clock_ns(CLOCK_REALTIME) : 0;
  auto sent = socket_.send_to(reply, d.from);
  const std::int64_t t2 = clock_ns(CLOCK_MONOTONIC);
  const std::int64_t wall2 = clock_ns(CLOCK_REALTIME);
  if (!sent) {
    bump(counters_.send_errors);
    return;
  }
  bump(counters_.replies);
  timing_.record(d.steady_ns, t2);
  reply_latency_.add(wall2 - d.wall_ns);
  if (recorder_) recorder_->record(d.to, d.from, reply, wall_send);
}

std::string CycleThread::summary() const {
  std::string out = timing_.summary();
  auto it = std::back_inserter(out);
  auto pct = [&](const char* name, const core::LatencyHistogram& h) {
    fmt::format_to(it, "{:<34}= p50 {:.6f} p99 {:.6f} p99.9 {:.6f} max {:.6f} ms (n {})\n", name,
                   static_cast<double>(h.percentile(50)) * 1e-6, static_cast<double>(h.percentile(99)) * 1e-6,
                   static_cast<double>(h.percentile(99.9)) * 1e-6, static_cast<double>(h.max()) * 1e-6, h.count());
  };
  pct("Wake-up latency (arrival to user)", wakeup_);
  pct("Reply latency (arrival to sent)", reply_latency_);
  fmt::format_to(it, "Packets {} answered {} unanswered {} refused {} timeouts {} send errors {} receive errors {}\n",
                 counters_.cycles.load(), counters_.replies.load(), counters_.silent.load(), counters_.refused.load(),
                 counters_.timeouts.load(), counters_.send_errors.load(), counters_.receive_errors.load());
  return out;
}

}  // namespace axon::c4g::host
