// The host side of a layout check: a GET_ID broadcast on every bus at once, collected into a
// BusSweep for check_layout() (layout_check.hpp).
#pragma once

#include "axon/core/clock.hpp"
#include "axon/fps/host/command_client.hpp"
#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/layout/layout_check.hpp"

#include <boost/asio/awaitable.hpp>

#include <utility>
#include <vector>

namespace axon::fps {

// The command client of each bus, named by the layout's (gateway, channel).
using LayoutBuses = std::vector<std::pair<BusRef, host::CommandClient*>>;

// Broadcasts GET_ID on every bus concurrently and collects for the whole `window` (so robots that
// should not be there are seen too; hosts in service wait 0.5 s). A bus whose broadcast fails is
// listed in BusSweep::failed. The clients must live on the current executor.
boost::asio::awaitable<BusSweep> sweep_buses(LayoutBuses buses, core::Duration window);

// sweep_buses, then check_layout.
boost::asio::awaitable<LayoutCheck> check_layout_on_buses(const FocalPlane& plane, LayoutBuses buses,
                                                          core::Duration window);

}  // namespace axon::fps
