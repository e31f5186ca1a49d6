// For `axon fps` subcommands defined outside fps.cpp: run a job on the array that the group's bus
// options (--gateway, --socketcand, --bus, --config, --timeout) select, after discovery.
#pragma once

#include "commands.hpp"
#include "axon/fps/host/array.hpp"

#include <CLI/CLI.hpp>
#include <boost/asio/awaitable.hpp>

#include <functional>

namespace axon::app {

using FpsArrayJob = std::function<boost::asio::awaitable<int>(fps::host::Array&)>;
// Opens the buses, discovers, runs `job`, closes; returns the job's exit code. With `moves`, SIGINT,
// SIGTERM and SIGHUP stop every robot (fps_stop.hpp).
using FpsArrayRunner = std::function<int(const FpsArrayJob& job, bool moves)>;

// `fps plan`, `fps plot`, `fps goto-all` (fps_plan.cpp), under the `fps` group, whose options
// `with_array` uses (add_fps_commands calls this).
void add_fps_plan_commands(CLI::App& fps_cmd, GlobalOptions& global, FpsArrayRunner with_array);

}  // namespace axon::app
