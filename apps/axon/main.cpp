// axon: command-line entry point. Subcommand groups live in their own files (can.cpp, demo.cpp, ...).
#include "commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <exception>

namespace axon::app {
int& exit_code() {
  static int code = 0;
  return code;
}
}  // namespace axon::app

int main(int argc, char** argv) {
  using namespace axon::app;
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
  add_fps_plan_commands(app, global);
  add_sim_plc_command(app, global);
  add_blmc_commands(app, global);
  add_fps_plane_commands(app, global);
  add_demo_command(app, global);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const axon::Exception& e) {
    std::fprintf(stderr, "axon: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "axon: internal error: %s\n", e.what());
    return 2;
  }
  return exit_code();
}
