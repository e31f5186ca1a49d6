// How long after its send the simulated controller waits for the PC's reply.
//
// The manual's timing chapter gives T_CYCLE1, the longest the PC may take to answer a packet, as
// 500-600 us after the controller's send (at 1 ms per cycle). A reply that comes later is not used
// for that cycle: the controller counts a miss (ERR_C4GOPEN_UDP_DEBUG), the late reply is counted
// when it arrives, and 10 misses in a row raise the communication error (ERR_C4GOPEN_UDP). The
// simulator holds the PC to the lower figure, 500 us, by default: a server that meets it meets
// every controller. The lenient window (a whole period) is for slow or loaded test machines.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string_view>

namespace axon::c4g::sim {

// T_CYCLE1, the lower figure of the manual's 500-600 us.
inline constexpr std::chrono::microseconds kManualReplyWindow{500};

enum class ReplyWindow : std::uint8_t {
  manual,  // kManualReplyWindow (never more than the period)
  period,  // lenient: the reply may come up to the next send (more than the controller allows)
};

constexpr std::string_view to_string(ReplyWindow w) noexcept { return w == ReplyWindow::manual ? "manual" : "period"; }

// The window for a controller of this period; an explicit window (> 0) wins over the choice.
inline std::chrono::nanoseconds reply_window(ReplyWindow window, std::chrono::nanoseconds explicit_window,
                                             double period_s) noexcept {
  const auto period = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(period_s));
  if (explicit_window.count() > 0) return explicit_window;
  if (window == ReplyWindow::period) return period;
  return std::min<std::chrono::nanoseconds>(kManualReplyWindow, period);
}

}  // namespace axon::c4g::sim
