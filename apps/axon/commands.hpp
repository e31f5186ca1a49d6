// Subcommand groups of the axon CLI; one file each.
#pragma once

#include <CLI/CLI.hpp>

namespace axon::app {

// Options every subcommand sees, and what the subcommand that ran hands back. Owned by main for the
// whole run; each setup function keeps a reference for its callbacks.
struct GlobalOptions {
  int verbosity = 0;  // -v / -vv raise, -q lowers
  int exit_code = 0;  // set by the subcommand that ran (exit_codes.hpp); main returns it
};

void add_can_commands(CLI::App& app, GlobalOptions& global);
void add_demo_command(CLI::App& app, GlobalOptions& global);
void add_sim_commands(CLI::App& app, GlobalOptions& global);
// `axon sim c4g`, registered by add_sim_commands under `sim` (apps/axon/sim_c4g.cpp).
void add_sim_c4g_command(CLI::App& sim_cmd, GlobalOptions& global);
// `axon sim blmc`, registered by add_sim_commands under `sim` (apps/axon/sim_blmc.cpp).
void add_sim_blmc_command(CLI::App& sim_cmd, GlobalOptions& global);
void add_fps_commands(CLI::App& app, GlobalOptions& global);
void add_c4g_commands(CLI::App& app, GlobalOptions& global);
// These add to the groups above (call after them): `fps layout`, `fps plc`, `sim plc`.
void add_fps_layout_commands(CLI::App& app, GlobalOptions& global);
void add_fps_plc_commands(CLI::App& app, GlobalOptions& global);
void add_sim_plc_command(CLI::App& app, GlobalOptions& global);
void add_blmc_commands(CLI::App& app, GlobalOptions& global);
// `fps plane` (after add_fps_commands).
void add_fps_plane_commands(CLI::App& app, GlobalOptions& global);
// `actor fps` and `tell` (apps/axon/actor.cpp).
void add_actor_commands(CLI::App& app, GlobalOptions& global);
// `actor blmc`, registered by add_actor_commands under `actor` (apps/axon/actor_blmc.cpp).
void add_actor_blmc_command(CLI::App& actor_group, GlobalOptions& global);
// `actor c4g`, registered by add_actor_commands under `actor` (apps/axon/actor_c4g.cpp).
void add_actor_c4g_command(CLI::App& actor_group, GlobalOptions& global);

}  // namespace axon::app
