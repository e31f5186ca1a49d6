#include "commands.hpp"

#include <cstdio>

namespace axon::app {
void add_demo_command(CLI::App& app, GlobalOptions&) {
  auto* cmd = app.add_subcommand("demo", "run what axon can do today against the embedded simulators");
  cmd->callback([] { std::puts("axon demo: under construction"); });
}
}  // namespace axon::app
