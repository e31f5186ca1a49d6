#include "axon/c4g/sim/client_runner.hpp"

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

}  // namespace

RunReport run_client(Controller& c, UdpClient& udp, const RunOptions& o) {
  RunReport report;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(c.period_s()));
  const auto deadline_after = o.reply_deadline.count() > 0 ? std::chrono::duration_cast<Clock::duration>(o.reply_deadline) : period;
  std::array<std::byte, 2048> buf{};
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
    if (!d.empty()) {
      const auto sent_at = Clock::now();
      if (auto r = udp.send(d); !r) c.on_send_failed(r.error().detail);
      const auto deadline = sent_at + deadline_after;
      while (c.awaiting_reply() && !c.reply_received()) {
        auto n = udp.receive(buf, deadline);
        if (!n || n.value() == 0) break;
        c.on_datagram(std::span<const std::byte>(buf.data(), std::min(n.value(), buf.size())));
        if (c.reply_received()) report.rtt.add(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - sent_at).count());
      }
    }
    c.end_cycle();
    if (o.on_event)
      for (const auto& e : c.take_events()) o.on_event(e);
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
