// For `axon fps` subcommands defined outside fps.cpp: run a job on the array that the group's bus
// options (--gateway, --socketcand, --bus, --config, --timeout) select, after discovery.
#pragma once

#include "axon/fps/host/array.hpp"

#include <boost/asio/awaitable.hpp>

#include <functional>

namespace axon::app {

using FpsArrayJob = std::function<boost::asio::awaitable<int>(fps::host::Array&)>;
// Opens the buses, discovers, runs `job`, closes; returns the job's exit code. With `moves`, SIGINT,
// SIGTERM and SIGHUP stop every robot (fps_stop.hpp).
int with_fps_array(const FpsArrayJob& job, bool moves = false);

}  // namespace axon::app
