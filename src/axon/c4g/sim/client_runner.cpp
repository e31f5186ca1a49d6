#include "axon/c4g/sim/client_runner.hpp"

#include <algorithm>
#include <array>
#include <ctime>

namespace axon::c4g::sim {
namespace {

using Clock = UdpClient::Clock;

void sleep_until(Clock::time_point t) {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(ns / 1000000000);
  ts.tv_nsec = static_cast<long>(ns % 1000000000);
  // steady_clock is CLOCK_MONOTONIC with libstdc++ on Linux.
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

// A reply that arrived after its window: handed to the controller once the tick is closed, where
// it counts as late.
struct LateReply {
  std::array<std::byte, 2048> bytes{};
  std::size_t size = 0;
};

// Sends this tick's packet and collects the replies that arrive within the window.
void exchange(Controller& c, UdpClient& udp, std::span<const std::byte> d, Clock::duration window, RunReport& report,
              std::array<std::byte, 2048>& buf, LateReply& late) {
  // The round trip is timed from just before the send: on loopback the PC's reply can arrive (and
  // be stamped by the kernel) while sendto() is still returning, so a clock read after the send
  // would make every round trip 0.
  const auto sending_at = Clock::now();
  if (auto r = udp.send(d); !r) c.on_send_failed(r.error().detail);
  // The window starts once the datagram is out: a simulator preempted before or inside the send
  // must not charge its own delay to the PC.
  const auto sent_at = Clock::now();
  const auto deadline = sent_at + window;
  while (c.awaiting_reply() && !c.reply_received()) {
    auto got = udp.receive(buf, deadline);
    if (!got || got.value().size == 0) break;
    const std::size_t n = std::min(got.value().size, buf.size());
    if (got.value().arrived > deadline) {
      std::copy_n(buf.begin(), n, late.bytes.begin());
      late.size = n;
      break;
    }
    c.on_datagram(std::span<const std::byte>(buf.data(), n));
    if (c.reply_received())
      report.rtt.add(std::max<std::int64_t>(0, std::chrono::duration_cast<std::chrono::nanoseconds>(got.value().arrived - sending_at).count()));
  }
}

}  // namespace

RunReport run_client(Controller& c, UdpClient& udp, const RunOptions& o) {
  RunReport report;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(c.period_s()));
  const auto window = reply_window(o.window, o.reply_deadline, c.period_s());
  report.window_ns = window.count();
  std::array<std::byte, 2048> buf{};
  LateReply late;
  const auto start = Clock::now();
  auto next = start;
  for (;;) {
    if (o.stop && o.stop->load(std::memory_order_relaxed)) {
      report.stopped = true;
      break;
    }
    if (c.finished()) break;
    if (o.duration_s > 0 && std::chrono::duration<double>(Clock::now() - start).count() >= o.duration_s) {
      report.stopped = true;
      break;
    }
    sleep_until(next);
    const auto d = c.begin_cycle();
    late.size = 0;
    if (!d.empty()) exchange(c, udp, d, std::chrono::duration_cast<Clock::duration>(window), report, buf, late);
    c.end_cycle();
    if (late.size > 0) c.on_datagram(std::span<const std::byte>(late.bytes.data(), late.size));
    if (o.on_event)
      for (const auto& e : c.take_events()) o.on_event(e);
    if (o.on_tick) o.on_tick(c, report);
    next += period;
    const auto now = Clock::now();
    if (now > next + period) {
      ++report.overruns;
      next = now;
    }
  }
  if (o.on_event)
    for (const auto& e : c.take_events()) o.on_event(e);
  report.elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  return report;
}

}  // namespace axon::c4g::sim
