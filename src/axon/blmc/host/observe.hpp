// Watching a board without driving it: the loops behind `axon blmc status`, `monitor` and
// `record`, for any program that wants to show or log a board while something else drives it.
//
// Coroutine API: call on the bus's executor with a Board in coroutine mode (not in cyclic mode).
// Each loop ends when its time is up, when the board is interrupted (Board::interrupt(), e.g. from a
// signal's callback) or closed, or when its callback returns false (a reader that went away). None
// sends anything to the board.
#pragma once

#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/protocol/status.hpp"
#include "axon/can/candump_log.hpp"

#include <boost/asio/awaitable.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace axon::blmc::host {

// Hands each status frame to `on_status` as it arrives, for `duration` (0: the first frame only).
// Returns how many were handed over. Errors: what Board::wait_status gives (timeout when the board
// sends no status within its status_timeout), except `interrupted`, which ends the loop normally.
asio::awaitable<Result<std::size_t>> watch_status(Board& board, core::Duration duration,
                                                  std::function<bool(const protocol::Status&)> on_status);

// Every `refresh`, hands the board's latest measurements to `on_sample` with the seconds since the
// start, for `duration` (0: until interrupted or closed). Returns false when `on_sample` refused one.
asio::awaitable<bool> monitor(Board& board, core::Duration refresh, core::Duration duration,
                              std::function<bool(double t_s, const Measurements& m)> on_sample);

// Writes every frame the board receives or sends to `log` (candump format, interface name `iface`)
// for `duration` (0: until interrupted or closed), then flushes it. Replaces the board's tap for that
// time and removes it at the end. Returns the number of frames written.
asio::awaitable<std::uint64_t> record(Board& board, can::CandumpWriter& log, std::string iface, core::Duration duration);

}  // namespace axon::blmc::host
