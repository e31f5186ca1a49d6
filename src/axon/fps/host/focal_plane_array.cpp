#include "axon/fps/host/focal_plane_array.hpp"

#include "axon/can/bus_spec.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/layout_sweep.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/this_coro.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <set>

namespace axon::fps::host {

FocalPlaneArray::FocalPlaneArray(const FocalPlane& plane, FocalPlaneArrayOptions options)
    : plane_(plane), options_(std::move(options)) {}

FocalPlaneArray::~FocalPlaneArray() { *alive_ = false; }

asio::awaitable<Result<std::unique_ptr<FocalPlaneArray>>> FocalPlaneArray::connect(asio::any_io_executor executor,
                                                                                   const FocalPlane& plane,
                                                                                   FocalPlaneArrayOptions options) {
  std::unique_ptr<FocalPlaneArray> self(new FocalPlaneArray(plane, std::move(options)));
  self->options_.gateway.reconnectable = true;  // the array's buses outlive a lost connection
  const auto by_bus = plane.by_bus();
  if (by_bus.empty()) co_return Error(HostErrc::invalid_argument, fmt::format("layout '{}' has no robots", plane.name()));

  // One link per gateway that carries robots, with the channels they use.
  std::map<std::uint16_t, std::vector<int>> channels;
  for (const auto& [ref, ids] : by_bus) channels[ref.gateway].push_back(ref.channel);
  for (const auto& [gw, chans] : channels) {
    GatewayLink link;
    link.id = gw;
    if (auto it = self->options_.addresses.find(gw); it != self->options_.addresses.end()) {
      link.endpoint = it->second;
    } else {
      const auto* site = plane.gateway(gw);
      auto ep = net::parse_endpoint(site != nullptr ? site->address : "", can::kCanNetPort);
      if (!ep) co_return Error(HostErrc::invalid_argument, fmt::format("gateway {}: {}", gw, ep.error().message()));
      link.endpoint = ep.value();
    }
    self->gateways_.push_back(std::move(link));
  }

  // Connect to all at once.
  std::vector<std::optional<Error>> failures(self->gateways_.size());
  FocalPlaneArray* s = self.get();
  co_await for_each_concurrently(self->gateways_.size(), [&, s](std::size_t i) -> asio::awaitable<void> {
    auto& link = s->gateways_[i];
    const net::Endpoint ep = link.endpoint;
    const std::vector<int> chans = channels[link.id];
    auto r = co_await can::CanNetGateway::connect(executor, ep, chans, s->options_.gateway);
    if (!r) {
      failures[i] = r.error();
      co_return;
    }
    link.gateway = std::move(r).value();
  });
  for (std::size_t i = 0; i < failures.size(); ++i) {
    if (!failures[i]) continue;
    for (auto& l : self->gateways_)
      if (l.gateway) l.gateway->close();
    co_return Error(failures[i]->code, fmt::format("gateway {} at {}: {}", self->gateways_[i].id,
                                                   self->gateways_[i].endpoint.to_string(), failures[i]->detail));
  }

  // Buses in layout order (by gateway, then channel).
  std::vector<can::Bus*> raw;
  for (const auto& [ref, ids] : by_bus) {
    for (auto& link : self->gateways_) {
      if (link.id != ref.gateway) continue;
      auto bus = link.gateway->bus(ref.channel);
      if (!bus) co_return Error(bus.error().code, fmt::format("gateway {} channel {}: {}", ref.gateway, int{ref.channel},
                                                              bus.error().detail));
      link.buses.push_back(self->refs_.size());
      self->refs_.push_back(ref);
      raw.push_back(bus.value().get());
      self->buses_.push_back(std::move(bus).value());
    }
  }
  self->array_ = std::make_unique<Array>(raw, self->options_.array);
  self->bus_off_.assign(self->refs_.size(), false);
  for (std::size_t i = 0; i < self->refs_.size(); ++i) {
    for (auto id : by_bus.at(self->refs_[i])) {
      const auto* site = plane.find(id);
      if (site != nullptr && site->offline) continue;
      auto added = self->array_->add(id, i);
      if (!added) co_return added.error();
    }
  }
  if (self->options_.plc) {
    self->plc_ = std::make_unique<plc::AsyncPlc>(*self->options_.plc, self->options_.plc_map, self->options_.plc_client);
  }
  asio::co_spawn(executor, watch(self.get(), self->alive_), asio::detached);
  co_return self;
}

std::optional<std::size_t> FocalPlaneArray::bus_index(const BusRef& ref) const {
  for (std::size_t i = 0; i < refs_.size(); ++i)
    if (refs_[i] == ref) return i;
  return std::nullopt;
}

asio::awaitable<void> FocalPlaneArray::watch(FocalPlaneArray* self, std::shared_ptr<bool> alive) {
  while (*alive) {
    co_await core::sleep_for(self->options_.connection_poll);
    if (!*alive || self->closed_) co_return;
    self->check_links();
  }
}

void FocalPlaneArray::check_links() {
  for (std::size_t i = 0; i < gateways_.size(); ++i) {
    const auto& link = gateways_[i];
    if (!link.down && !link.gateway->is_connected()) link_lost(i);
    if (link.down) continue;
    for (auto b : link.buses) {
      if (buses_[b]->state() != can::BusState::bus_off || bus_off_[b]) continue;
      bus_off_[b] = true;
      const auto reason = fmt::format("{} (gateway {} channel {}) went bus-off", buses_[b]->name(), link.id,
                                      int{refs_[b].channel});
      spdlog::error("fps focal plane: {}: stopping every robot", reason);
      array_->request_stop(reason);
      ++reconnecting_;
      asio::co_spawn(array_->client(0).bus().get_executor(), restart_bus(i, b), [this](std::exception_ptr) { --reconnecting_; });
    }
  }
}

// A channel that went bus-off hears nothing and says nothing: the robots on it cannot be told to
// stop until the channel is restarted (CAN b STOP, CAN b START), which is done at once, followed by
// a TRAJECTORY_ABORT broadcast there. A restart that fails is tried again on a later watch.
asio::awaitable<void> FocalPlaneArray::restart_bus(std::size_t index, std::size_t bus) {
  const auto alive = alive_;
  auto gw = gateways_[index].gateway;
  const int channel = refs_[bus].channel;
  auto r = co_await gw->restart(channel);
  if (!*alive) co_return;
  ++bus_off_count_;
  if (!r) {
    link_stops_.push_back(fmt::format("{}: bus-off; restarting the channel failed ({}): its robots are NOT stopped",
                                      buses_[bus]->name(), r.error().message()));
    spdlog::error("fps focal plane: {}", link_stops_.back());
    co_await wait_unless_closed(options_.restore_interval, alive);
    if (*alive) bus_off_[bus] = false;
    co_return;
  }
  std::vector<std::size_t> one{bus};
  const auto stops = co_await broadcast_on(std::move(one), protocol::CommandId::trajectory_abort);
  if (!*alive) co_return;
  link_stops_.push_back(fmt::format("{}: bus-off; channel restarted and TRAJECTORY_ABORT sent: {} of {} robots "
                                    "acknowledged{}{}",
                                    buses_[bus]->name(), stops.acknowledged, array_->ids_on(bus).size(),
                                    stops.failures.empty() ? "" : "; failed: ", fmt::join(stops.failures, "; ")));
  spdlog::warn("fps focal plane: {}", link_stops_.back());
  bus_off_[bus] = false;
}

asio::awaitable<void> FocalPlaneArray::link_stops_done() {
  while (reconnecting_ > 0) co_await core::sleep_for(10ms);
}

void FocalPlaneArray::link_lost(std::size_t index) {
  auto& link = gateways_[index];
  link.down = true;
  ++link.losses;
  lost_.push_back(link.id);
  const auto reason = fmt::format("gateway {} at {} disconnected ({})", link.id, link.endpoint.to_string(),
                                  link.gateway->disconnect_reason().detail);
  spdlog::error("fps focal plane: {}: stopping every robot", reason);
  array_->request_stop(reason);
  std::size_t behind = 0;
  std::size_t moving = 0;
  for (auto b : link.buses) {
    for (auto id : array_->ids_on(b)) {
      ++behind;
      moving += array_->moving().contains(id) ? 1 : 0;
    }
  }
  const bool takeover = link.gateway->disconnect_kind() == can::DisconnectKind::by_gateway;
  const bool restore = options_.restore_links && (!takeover || options_.restore_after_takeover);
  if (moving > 0 && options_.reconnect_to_stop) {
    ++reconnecting_;
    asio::co_spawn(array_->client(0).bus().get_executor(), stop_behind(index, behind, moving, restore),
                   [this](std::exception_ptr) { --reconnecting_; });
    return;
  }
  if (moving == 0)
    link_stops_.push_back(fmt::format("gateway {}: lost; none of its {} robots was moving under this host", link.id, behind));
  else
    link_stops_.push_back(fmt::format("gateway {}: lost with {} robots moving behind it: NOT stopped (no reconnection "
                                      "allowed)", link.id, moving));
  if (restore) spawn_restore(index);
}

// A reconnection to a lost gateway at once, then a TRAJECTORY_ABORT broadcast on each of its
// channels through the array's own clients (acknowledgements collected briefly).
asio::awaitable<void> FocalPlaneArray::stop_behind(std::size_t index, std::size_t robots, std::size_t moving,
                                                   bool restore_after) {
  const auto alive = alive_;
  auto& link = gateways_[index];
  spdlog::warn("fps focal plane: gateway {}: {} robots were moving behind it; reconnecting at once to stop them", link.id, moving);
  auto r = co_await link.gateway->reconnect(options_.reconnect_timeout);
  if (!*alive) co_return;
  if (!r) {
    link_stops_.push_back(fmt::format("gateway {}: {} robots were moving behind it: NOT stopped, the reconnection "
                                      "failed: {}", link.id, moving, r.error().message()));
    spdlog::error("fps focal plane: {}", link_stops_.back());
    if (restore_after) spawn_restore(index);
    co_return;
  }
  link_up(index, "reconnected to stop its robots");
  std::vector<int> channels;
  for (auto b : link.buses) channels.push_back(refs_[b].channel);
  const auto stops = co_await broadcast_on(link.buses, protocol::CommandId::trajectory_abort);
  if (!*alive) co_return;
  link_stops_.push_back(fmt::format("gateway {}: reconnected and sent TRAJECTORY_ABORT on channel(s) {}: {} of {} "
                                    "robots acknowledged ({} had been moving){}{}",
                                    link.id, fmt::join(channels, ", "), stops.acknowledged, robots, moving,
                                    stops.failures.empty() ? "" : "; failed: ", fmt::join(stops.failures, "; ")));
  spdlog::warn("fps focal plane: {}", link_stops_.back());
}

asio::awaitable<FocalPlaneArray::LinkBroadcast> FocalPlaneArray::broadcast_on(std::vector<std::size_t> buses,
                                                                          protocol::CommandId c) {
  LinkBroadcast out;
  co_await for_each_concurrently(buses.size(), [&](std::size_t k) -> asio::awaitable<void> {
    const auto ids = array_->ids_on(buses[k]);
    BroadcastOptions bo;
    bo.expected_ids = std::set<std::uint16_t>(ids.begin(), ids.end());
    bo.window = options_.reconnect_window;
    auto r = co_await array_->client(buses[k]).broadcast(c, {}, bo);
    if (!r) {
      out.failures.push_back(r.error().message());
      co_return;
    }
    for (const auto& reply : r.value().replies) out.acknowledged += bo.expected_ids->contains(reply.positioner) ? 1 : 0;
  });
  co_return out;
}

void FocalPlaneArray::spawn_restore(std::size_t index) {
  ++restoring_;
  asio::co_spawn(array_->client(0).bus().get_executor(), restore_loop(index, alive_), [this, alive = alive_](std::exception_ptr) {
    if (*alive) --restoring_;
  });
}

// Attempts to reconnect a lost gateway until it answers or the array closes, the wait between
// attempts doubling from restore_interval up to restore_max_interval.
asio::awaitable<void> FocalPlaneArray::restore_loop(std::size_t index, std::shared_ptr<bool> alive) {
  core::Duration wait = options_.restore_interval;
  const std::uint16_t id = gateways_[index].id;
  for (std::size_t attempt = 1;; ++attempt) {
    if (!co_await wait_unless_closed(wait, alive)) co_return;
    auto& link = gateways_[index];
    if (!link.down) co_return;  // restored meanwhile (restore_link())
    auto r = co_await link.gateway->reconnect(options_.reconnect_timeout);
    if (!*alive || closed_) co_return;
    if (r) {
      link_up(index, fmt::format("after {} attempt(s)", attempt));
      co_return;
    }
    if (link.gateway->disconnect_kind() == can::DisconnectKind::by_host) co_return;
    if (attempt == 1)
      spdlog::warn("fps focal plane: gateway {} not reachable yet ({}); trying again, every {} ms at most", id,
                   r.error().message(), std::chrono::duration_cast<std::chrono::milliseconds>(options_.restore_max_interval).count());
    else
      spdlog::debug("fps focal plane: gateway {}: attempt {}: {}", id, attempt, r.error().message());
    wait = std::min(wait * 2, options_.restore_max_interval);
  }
}

asio::awaitable<bool> FocalPlaneArray::wait_unless_closed(core::Duration d, std::shared_ptr<bool> alive) {
  const auto until = core::steady_now() + d;
  while (*alive && !closed_) {
    const auto now = core::steady_now();
    if (now >= until) co_return true;
    co_await core::sleep_for(std::min<core::Duration>(until - now, 50ms));
  }
  co_return false;
}

void FocalPlaneArray::link_up(std::size_t index, std::string_view how) {
  auto& link = gateways_[index];
  if (!link.down) return;
  link.down = false;
  ++link.restorations;
  spdlog::warn("fps focal plane: gateway {} at {} is back ({}){}", link.id, link.endpoint.to_string(), how,
               array_->locked() ? "; the array stays locked until unlock()" : "");
}

asio::awaitable<Result<void>> FocalPlaneArray::restore_link(std::uint16_t gateway) {
  for (std::size_t i = 0; i < gateways_.size(); ++i) {
    if (gateways_[i].id != gateway) continue;
    auto gw = gateways_[i].gateway;
    AXON_CO_TRY(co_await gw->reconnect(options_.reconnect_timeout));
    if (gateways_[i].down) link_up(i, "on request");
    co_return ok();
  }
  co_return Error(HostErrc::invalid_argument, fmt::format("gateway {} is not a gateway of layout '{}'", gateway, plane_.name()));
}

asio::awaitable<LayoutCheck> FocalPlaneArray::check_layout() {
  LayoutBuses buses;
  for (std::size_t i = 0; i < refs_.size(); ++i) buses.emplace_back(refs_[i], &array_->client(i));
  auto check = co_await check_layout_on_buses(plane_, buses, options_.check_window);
  co_return check;
}

asio::awaitable<Result<DiscoveryReport>> FocalPlaneArray::discover() {
  std::map<std::size_t, std::size_t> expected;
  for (std::size_t i = 0; i < refs_.size(); ++i) expected[i] = array_->ids_on(i).size();
  auto r = co_await array_->discover(expected);
  co_return r;
}

asio::awaitable<Result<TrajectoryReport>> FocalPlaneArray::run_trajectories(
    std::map<std::uint16_t, protocol::Trajectory> trajectories, TrajectoryOptions options, bool by_sync_line) {
  if (by_sync_line) {
    if (!plc_) co_return Error(HostErrc::invalid_argument, "start by the sync line needs the PLC (no PLC endpoint given)");
    plc::AsyncPlc* p = plc_.get();
    const core::Duration hold = options_.sync_hold;
    options.sync_line = [p, hold]() -> asio::awaitable<Result<void>> {
      auto r = co_await p->pulse_sync_line(hold);
      co_return r;
    };
  }
  auto r = co_await array_->run_trajectories(std::move(trajectories), std::move(options));
  // A gateway lost during the run (even one the watch has not polled yet): the stop of its robots
  // through a reconnection belongs to this run, so it ends before the caller reads link_stops().
  if (!closed_) check_links();
  co_await link_stops_done();
  co_return r;
}

asio::awaitable<void> FocalPlaneArray::close() {
  if (closed_) co_return;
  closed_ = true;
  co_await link_stops_done();
  while (restoring_ > 0) co_await core::sleep_for(10ms);  // each ends within one attempt's timeout
  *alive_ = false;
  co_await array_->close();
  for (auto& b : buses_) b->close();
  for (auto& l : gateways_)
    if (l.gateway) l.gateway->close();
  plc_.reset();
}

}  // namespace axon::fps::host
