#include "commands.hpp"

namespace axon::app {
void add_can_commands(CLI::App& app, GlobalOptions&) {
  app.add_subcommand("can", "CAN buses: dump, send, bridge, replay")->require_subcommand(1);
}
}  // namespace axon::app
