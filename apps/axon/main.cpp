// axon: command-line entry point. Subcommand groups live in their own files (can.cpp, demo.cpp, ...).
#include "commands.hpp"
#include "axon/core/error.hpp"
#include "axon/core/log.hpp"
#include "exit_codes.hpp"

#include <fmt/format.h>

#include <csignal>
#include <cstdio>
#include <exception>

namespace axon::app {
// Errors that mean "the input was wrong" (option values, files): nothing was done. Each layer's
// error category maps its bad-input codes to std::errc::invalid_argument.
bool is_usage_error(std::error_code ec) { return ec == std::errc::invalid_argument; }
}  // namespace axon::app

int main(int argc, char** argv) {
  using namespace axon::app;
  // A closed pipe (`axon ... | head`) must not kill a command that has devices to make safe: writes
  // fail with EPIPE instead, and the command stops its devices and exits.
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"axon: host-side control of CAN and real-time UDP actuators (fps, blmc, c4g)", "axon"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "axon 0.1.0");
  GlobalOptions global;
  int verbose = 0;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbose, "more log output (-vv for trace)");
  app.add_flag("-q,--quiet", quiet, "only warnings and errors");
  app.parse_complete_callback([&] {
    global.verbosity = quiet ? -1 : verbose;
    axon::core::init_logging(global.verbosity);
  });
  add_can_commands(app, global);
  add_sim_commands(app, global);
  add_fps_commands(app, global);
  add_c4g_commands(app, global);
  add_fps_layout_commands(app, global);
  add_fps_plc_commands(app, global);
  add_sim_plc_command(app, global);
  add_blmc_commands(app, global);
  add_fps_plane_commands(app, global);
  add_demo_command(app, global);
  add_actor_commands(app, global);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here too (CLI11 gives them code 0); every parse error is a usage error.
    return app.exit(e) == 0 ? exit_code_value::ok : exit_code_value::usage;
  } catch (const axon::Exception& e) {
    std::fprintf(stderr, "axon: error: %s\n", e.what());
    return is_usage_error(e.code()) ? exit_code_value::usage : exit_code_value::failed;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "axon: internal error: %s\n", e.what());
    return exit_code_value::internal;
  }
  return global.exit_code;
}
