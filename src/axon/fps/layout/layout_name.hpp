// Layouts by name, as a program or the command line names them: a file path, a directory of
// calibration tables (calibration_tables.hpp: positionerTable.csv and its companions), or `default` /
// `benchtop`, the two layouts axon ships (data/layouts). Without the data folder, `default` is
// generated (layout_generator.hpp) and `benchtop` comes from a copy built into the library, so a
// program that never saw the source tree can still start a simulated plane of either.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <cstdint>
#include <map>
#include <string>

namespace axon::fps {

// `data_dir`: where the shipped layouts live (their folder's parent, i.e. `data`); empty: the built-in
// ones. Errors: the file's (located by file:line), or CoreErrc::invalid_argument for a name that is
// neither a file nor a shipped layout.
[[nodiscard]] Result<FocalPlane> resolve_layout(const std::string& name, const std::string& data_dir = {});

// The layout with the listed gateways' addresses (HOST:PORT, by gateway id) replaced: where a
// simulated plane's emulators listen, or a site's gateways behind other addresses.
[[nodiscard]] Result<FocalPlane> with_gateway_addresses(const FocalPlane& plane,
                                                        const std::map<std::uint16_t, std::string>& addresses);

}  // namespace axon::fps
