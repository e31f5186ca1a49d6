// FocalPlaneArray: the whole focal plane of a layout driven as one fps::Array.
//
// connect() opens one CAN@net connection per gateway of the layout (all at once) with the
// channels its robots use, and builds one Array over every bus, on one executor. Bus i of the
// array is bus_ref(i) of the layout. The layout's robots (all but the offline ones) are known to
// the array from the start, each on its own bus; discover() and check_layout() compare that with
// what answers.
//
// With a PLC endpoint, the PLC is reached through AsyncPlc (its own thread): trajectories can be
// started by the sync line instead of the START_TRAJECTORY broadcast (run_trajectories with
// by_sync_line), and sextants powered off and on.
//
// Faults: the array already stops every bus on a collision anywhere. Here, besides, a channel that
// goes bus-off stops everything (it is then restarted at once and its robots are sent the abort;
// link_stops() says so), and a gateway whose connection drops stops everything too
// (TRAJECTORY_ABORT broadcast on every bus still reachable, array locked, the reason naming the
// gateway and why its connection ended): a watch checks the connections every `connection_poll`.
//
// The robots behind the lost gateway cannot hear that stop. When some of them were moving under
// this host, it reconnects to that gateway at once (reconnect_to_stop) and broadcasts
// TRAJECTORY_ABORT on its channels. Why: their neighbours behind the other gateways have just been
// stopped, and paths planned to be collision-free together are no longer so when half the plane
// stops and the other half follows its trajectories to the end. The price is that a client that
// took the gateway over (a CAN@net NT serves one client at a time) loses its connection; stopping
// moving robots comes first. What was done is in link_stops(), one line per loss.
//
// Links come back by themselves. The buses of the array survive a lost connection (they are
// opened reconnectable): a gateway whose connection failed (reset, keep-alive timeout: power cycled,
// network cut) is tried again every restore_interval, doubling up to restore_max_interval, and once
// it answers its channels are set up again and its robots are reachable through the same array.
// A gateway that closed the connection in order (another client took it over) is left to that
// client unless restore_after_takeover; restore_link() takes it back on request. A restored link
// leaves the array locked: the stop stands until unlock(), as after a collision.
#pragma once

#include "axon/can/cannet_client.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/layout/layout_check.hpp"
#include "axon/fps/plc/async_client.hpp"

#include <boost/asio/awaitable.hpp>

#include <map>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace axon::fps::host {

struct FocalPlaneArrayOptions {
  ArrayOptions array;
  can::CanNetOptions gateway;
  core::Duration check_window = 500ms;      // GET_ID collection of check_layout()
  std::optional<net::Endpoint> plc;         // the PLC, if any
  plc::RegisterMap plc_map;
  plc::PlcClientOptions plc_client;
  // The sync line is held high this long for a start, then dropped. Robots start only on a level
  // that is still high a few ms after the rising edge (interface document 6); hosts in service
  // hold it about 0.5 s (FIELD-NOTES).
  core::Duration sync_hold = 500ms;
  core::Duration connection_poll = 20ms;    // how often the gateway connections are checked
  // Replaces the layout's gateway addresses (e.g. emulators on other ports), by gateway id.
  std::map<std::uint16_t, net::Endpoint> addresses;
  // A lost gateway behind which robots were moving: reconnect at once to stop them (see above).
  bool reconnect_to_stop = true;
  core::Duration reconnect_timeout = 1s;    // connect and set-up of each reconnection attempt
  core::Duration reconnect_window = 300ms;  // collecting the robots' acknowledgements of the abort
  // Bringing lost links back (see above).
  bool restore_links = true;
  core::Duration restore_interval = 500ms;   // first wait before another attempt
  core::Duration restore_max_interval = 8s;  // the wait doubles up to this
  bool restore_after_takeover = false;       // also take back a gateway another client took over
};

struct GatewayLink {
  std::uint16_t id = 0;
  net::Endpoint endpoint;
  std::shared_ptr<can::CanNetGateway> gateway;
  std::vector<std::size_t> buses;  // array bus indices
  bool down = false;               // lost and not (yet) restored
  std::uint32_t losses = 0;
  std::uint32_t restorations = 0;  // reconnections that brought it back (the stop's one included)
};

class FocalPlaneArray {
 public:
  // Errors: a gateway that cannot be reached (named), a layout without robots.
  static asio::awaitable<Result<std::unique_ptr<FocalPlaneArray>>> connect(asio::any_io_executor executor,
                                                                         const FocalPlane& plane,
                                                                         FocalPlaneArrayOptions options = {});
  ~FocalPlaneArray();
  FocalPlaneArray(const FocalPlaneArray&) = delete;
  FocalPlaneArray& operator=(const FocalPlaneArray&) = delete;

  [[nodiscard]] Array& array() noexcept { return *array_; }
  [[nodiscard]] const FocalPlane& plane() const noexcept { return plane_; }
  [[nodiscard]] const FocalPlaneArrayOptions& options() const noexcept { return options_; }
  [[nodiscard]] std::size_t bus_count() const noexcept { return refs_.size(); }
  [[nodiscard]] const BusRef& bus_ref(std::size_t index) const { return refs_.at(index); }
  [[nodiscard]] std::optional<std::size_t> bus_index(const BusRef& ref) const;
  [[nodiscard]] const std::vector<GatewayLink>& gateways() const noexcept { return gateways_; }
  // nullptr without a PLC endpoint.
  [[nodiscard]] plc::AsyncPlc* plc() noexcept { return plc_.get(); }

  // GET_ID on every bus at once, checked against the layout (missing, unexpected, wrong bus...).
  asio::awaitable<LayoutCheck> check_layout();
  // Array::discover, each bus collecting until the layout's robots there answered (or the window).
  asio::awaitable<Result<DiscoveryReport>> discover();
  // Array::run_trajectories; with by_sync_line the start is a pulse of the PLC's sync line
  // (HostErrc::invalid_argument without a PLC). Returns once the stops through a reconnection to
  // gateways lost during the run have ended too (link_stops() then says what they did).
  asio::awaitable<Result<TrajectoryReport>> run_trajectories(std::map<std::uint16_t, protocol::Trajectory> trajectories,
                                                             TrajectoryOptions options = {}, bool by_sync_line = false);

  // Reconnects a lost gateway now (e.g. one another client took over) and sets its channels up
  // again. Already connected: nothing to do. Errors: invalid_argument (not a gateway of the
  // layout), the connection's (CanErrc: connect_failed, timeout, device_error ...).
  asio::awaitable<Result<void>> restore_link(std::uint16_t gateway);

  // Bus-offs handled: each stopped every robot and made one restart attempt of its channel
  // (link_stops() says whether the restart worked).
  [[nodiscard]] std::uint64_t bus_off_restarts() const noexcept { return bus_off_count_; }

  // Gateways whose connection dropped (by id), in the order noticed (again for each loss).
  [[nodiscard]] const std::vector<std::uint16_t>& lost_gateways() const noexcept { return lost_; }
  // What was done for the robots behind each lost gateway (one line each): the stop sent through
  // a reconnection, or why they could not be stopped.
  [[nodiscard]] const std::vector<std::string>& link_stops() const noexcept { return link_stops_; }

  // Stops the watch, closes the array and every gateway connection.
  asio::awaitable<void> close();

 private:
  FocalPlaneArray(const FocalPlane& plane, FocalPlaneArrayOptions options);
  static asio::awaitable<void> watch(FocalPlaneArray* self, std::shared_ptr<bool> alive);
  void check_links();  // link_lost() for each gateway newly disconnected
  void link_lost(std::size_t link);
  asio::awaitable<void> link_stops_done();  // once every stop_behind() has ended
  asio::awaitable<void> stop_behind(std::size_t link, std::size_t robots, std::size_t moving, bool restore_after);
  struct LinkBroadcast {
    std::size_t acknowledged = 0;       // known robots of the link's buses that answered
    std::vector<std::string> failures;  // buses where the broadcast failed
  };
  asio::awaitable<LinkBroadcast> broadcast_on(std::vector<std::size_t> buses, protocol::CommandId c);
  asio::awaitable<void> restart_bus(std::size_t link, std::size_t bus);
  void spawn_restore(std::size_t link);
  asio::awaitable<void> restore_loop(std::size_t link, std::shared_ptr<bool> alive);
  void link_up(std::size_t link, std::string_view how);
  // Waits `d` in short slices, returning early (false) once the array closes.
  asio::awaitable<bool> wait_unless_closed(core::Duration d, std::shared_ptr<bool> alive);

  FocalPlane plane_;
  FocalPlaneArrayOptions options_;
  std::vector<GatewayLink> gateways_;
  std::vector<BusRef> refs_;
  std::vector<std::unique_ptr<can::Bus>> buses_;
  std::unique_ptr<Array> array_;
  std::unique_ptr<plc::AsyncPlc> plc_;
  std::vector<std::uint16_t> lost_;
  std::vector<std::string> link_stops_;
  std::size_t reconnecting_ = 0;  // stop_behind() coroutines running
  std::size_t restoring_ = 0;     // restore_loop() coroutines running
  std::vector<bool> bus_off_;      // per bus: a bus-off being handled
  std::uint64_t bus_off_count_ = 0;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
  bool closed_ = false;
};

}  // namespace axon::fps::host
