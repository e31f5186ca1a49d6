#include "axon/fps/host/array.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/protocol/error.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <set>

namespace axon::fps::host {

using protocol::CommandId;
using protocol::ResponseCode;

namespace {

std::string arm_of(ResponseCode c) {
  if (c == ResponseCode::alpha_collision) return "alpha";
  if (c == ResponseCode::beta_collision) return "beta";
  return std::string(protocol::response_name(c));
}

}  // namespace

Array::Array(std::vector<can::Bus*> buses, ArrayOptions options) : options_(std::move(options)) {
  if (buses.empty()) throw Exception(Error(HostErrc::invalid_argument, "an array needs at least one bus"));
  executor_ = buses.front()->get_executor();
  for (auto* b : buses) {
    if (!b) throw Exception(Error(HostErrc::invalid_argument, "null bus"));
    if (b->get_executor() != executor_) {
      throw Exception(Error(HostErrc::wrong_executor, fmt::format("bus {}", b->name())));
    }
  }
  buses_.reserve(buses.size());
  for (std::size_t i = 0; i < buses.size(); ++i) {
    BusSlot slot;
    slot.bus = buses[i];
    slot.client = std::make_unique<CommandClient>(*buses[i], options_.client, lock_);
    slot.subscription = slot.client->subscribe([this, i](const Unsolicited& u) { on_unsolicited(i, u); });
    buses_.push_back(std::move(slot));
  }
}

Array::~Array() {
  for (auto& b : buses_) b.client->unsubscribe(b.subscription);
}

// --- robots --------------------------------------------------------------------------------------

std::vector<std::uint16_t> Array::ids() const {
  std::vector<std::uint16_t> out;
  out.reserve(robots_.size());
  for (const auto& [id, r] : robots_) out.push_back(id);
  return out;
}

std::vector<std::uint16_t> Array::ids_on(std::size_t bus) const {
  std::vector<std::uint16_t> out;
  for (const auto& [id, r] : robots_) {
    if (r.bus == bus) out.push_back(id);
  }
  return out;
}

std::vector<std::size_t> Array::all_buses() const {
  std::vector<std::size_t> out(buses_.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = i;
  return out;
}

Positioner* Array::find(std::uint16_t id) const noexcept {
  auto it = robots_.find(id);
  return it == robots_.end() ? nullptr : it->second.positioner.get();
}

Result<Positioner*> Array::positioner(std::uint16_t id) const {
  if (auto* p = find(id)) return p;
  return Error(HostErrc::unknown_positioner, fmt::format("positioner {}", id));
}

Result<std::size_t> Array::bus_of(std::uint16_t id) const {
  auto it = robots_.find(id);
  if (it == robots_.end()) return Error(HostErrc::unknown_positioner, fmt::format("positioner {}", id));
  return it->second.bus;
}

Result<Positioner*> Array::add(std::uint16_t id, std::size_t bus) {
  if (bus >= buses_.size()) {
    return Error(HostErrc::invalid_argument, fmt::format("bus index {} (the array has {})", bus, buses_.size()));
  }
  if (id == protocol::kBroadcastId || id > protocol::kMaxPositionerId) {
    return Error(protocol::ProtocolErrc::positioner_out_of_range, fmt::format("positioner {}", id));
  }
  auto& r = robots_[id];
  if (!r.positioner || r.bus != bus) {
    r.positioner = std::make_unique<Positioner>(*buses_[bus].client, id, options_.positioner, this);
    r.bus = bus;
  }
  return r.positioner.get();
}

// --- discovery and status ------------------------------------------------------------------------

asio::awaitable<std::vector<Array::BusBroadcast>> Array::broadcast_on(std::vector<std::size_t> buses, CommandId c,
                                                                      BroadcastOptions options) {
  std::vector<BusBroadcast> out(buses.size());
  co_await for_each_concurrently(buses.size(), [&](std::size_t i) -> asio::awaitable<void> {
    BroadcastOptions o = options;
    if (!o.expected && !o.expected_ids) {
      const auto ids = ids_on(buses[i]);
      o.expected_ids = std::set<std::uint16_t>(ids.begin(), ids.end());
    }
    out[i].bus = buses[i];
    out[i].result = co_await buses_[buses[i]].client->broadcast(c, {}, o);
  });
  co_return out;
}

asio::awaitable<Result<DiscoveryReport>> Array::discover(std::map<std::size_t, std::size_t> expected) {
  DiscoveryReport report;
  std::vector<BusBroadcast> found(buses_.size());
  co_await for_each_concurrently(buses_.size(), [&](std::size_t i) -> asio::awaitable<void> {
    BroadcastOptions o;
    o.window = options_.discover_window;
    if (auto it = expected.find(i); it != expected.end()) o.expected = it->second;
    found[i].bus = i;
    found[i].result = co_await buses_[i].client->broadcast(CommandId::get_id, {}, o);
  });
  std::map<std::uint16_t, std::size_t> seen;
  for (const auto& f : found) {
    if (!f.result) {
      report.failed_buses.push_back(f.bus);
      report.problems.push_back(fmt::format("bus {}: GET_ID broadcast failed: {}", bus_name(f.bus),
                                            f.result.error().message()));
      continue;
    }
    for (const auto& r : f.result.value().replies) {
      if (!r.accepted()) {
        report.problems.push_back(fmt::format("bus {}: positioner {} refused GET_ID: {}", bus_name(f.bus),
                                              r.positioner, r.error().message()));
        continue;
      }
      auto id = buses_[f.bus].client->decode_reply<protocol::PositionerIdReply>(r);
      if (!id) {
        report.problems.push_back(fmt::format("bus {}: {}", bus_name(f.bus), id.error().message()));
        continue;
      }
      if (id.value().id != r.positioner) {
        report.problems.push_back(fmt::format("bus {}: positioner {} reports id {} in its GET_ID data",
                                              bus_name(f.bus), r.positioner, id.value().id));
      }
      if (auto it = seen.find(r.positioner); it != seen.end()) {
        report.problems.push_back(fmt::format("positioner {} answered on bus {} and on bus {}; using {}", r.positioner,
                                              bus_name(it->second), bus_name(f.bus), bus_name(it->second)));
        continue;
      }
      seen.emplace(r.positioner, f.bus);
    }
    if (f.result.value().duplicates) {
      report.problems.push_back(fmt::format("bus {}: {} duplicate GET_ID replies (two robots with one id?)",
                                            bus_name(f.bus), f.result.value().duplicates));
    }
  }
  for (const auto& [id, bus] : seen) (void)add(id, bus);
  for (const auto& [id, r] : robots_) {
    if (!seen.contains(id)) {
      report.problems.push_back(fmt::format("positioner {} (bus {}) did not answer discovery", id, bus_name(r.bus)));
    }
  }
  report.table = co_await status_table(true);
  co_return report;
}

asio::awaitable<StatusTable> Array::status_table(bool positions) {
  StatusTable table;
  for (const auto& [id, r] : robots_) {
    StatusRow row;
    row.id = id;
    row.bus = r.bus;
    row.bus_name = bus_name(r.bus);
    table.rows.push_back(std::move(row));
  }
  co_await for_each_concurrently(table.rows.size(), [&](std::size_t i) -> asio::awaitable<void> {
    auto& row = table.rows[i];
    Positioner* p = find(row.id);
    auto fw = co_await p->read_firmware_version();
    if (!fw) {
      row.error = fw.error().message();
      co_return;
    }
    row.firmware = fw.value();
    if (fw.value().is_bootloader()) {
      auto bs = co_await p->read_bootloader_status();
      if (bs) {
        row.bootloader_status = bs.value();
      } else {
        row.error = bs.error().message();
      }
      co_return;
    }
    auto st = co_await p->read_status();
    if (!st) {
      row.error = st.error().message();
      co_return;
    }
    row.status = st.value();
    if (!positions) co_return;
    auto pos = co_await p->read_position();
    if (pos) {
      row.position = pos.value();
    } else {
      row.error = pos.error().message();
    }
  });
  co_return table;
}

// --- safety --------------------------------------------------------------------------------------

Result<void> Array::admit_all(CommandId c, const std::vector<std::uint16_t>& ids) const {
  for (auto id : ids) {
    if (auto a = lock_->admit(c, id); !a) return a;
  }
  return ok();
}

void Array::on_unsolicited(std::size_t bus, const Unsolicited& u) {
  if (!u.is_collision()) {
    if (u.command == protocol::number(CommandId::start_trajectory)) {
      ++counters_.sync_starts;
      spdlog::info("fps array: positioner {} on bus {} started a trajectory (sync line)", u.positioner,
                   bus_name(bus));
    }
    return;
  }
  Collision c{u.positioner, bus, u.code, u.timestamp, false};
  if (lock_->locked()) {
    lock_->record_collision(c);
    ++counters_.expected_collisions;
    spdlog::info("fps array: positioner {} on bus {} reports a collision ({}) after the stop", u.positioner,
                 bus_name(bus), arm_of(u.code));
    return;
  }
  c.caused_lock = true;
  lock_->record_collision(c);
  ++counters_.collision_locks;
  lock_for(fmt::format("collision ({}) reported by positioner {} on bus {}", arm_of(u.code), u.positioner,
                       bus_name(bus)));
  stop_in_background();
}

void Array::collision_seen(std::uint16_t positioner, const protocol::PositionerStatus& status) {
  if (lock_->locked()) return;
  Collision c;
  c.positioner = positioner;
  if (auto b = bus_of(positioner)) c.bus = b.value();
  c.code = status.has(protocol::StatusBit::collision_alpha) ? ResponseCode::alpha_collision
                                                             : ResponseCode::beta_collision;
  c.caused_lock = true;
  lock_->record_collision(c);
  ++counters_.collision_locks;
  lock_for(fmt::format("collision flag ({}) in the status of positioner {} on bus {} (its collision report was "
                       "not received)",
                       arm_of(c.code), positioner, bus_name(c.bus)));
  stop_in_background();
}

void Array::stop_in_background() {
  ++background_;
  asio::co_spawn(executor_, stop_everyone(lock_->state().reason), [this](std::exception_ptr, StopReport) {
    --background_;
    for (auto* w : background_waiters_) w->notify();
  });
}

void Array::lock_for(std::string reason) {
  if (lock_->lock(std::move(reason))) {
    spdlog::error("fps array locked: {}; stopping every robot", lock_->state().reason);
  }
}

asio::awaitable<StopReport> Array::stop_everyone(std::string reason) {
  ++counters_.emergency_stops;
  StopReport report;
  report.reason = std::move(reason);
  report.buses.resize(buses_.size());
  for (std::size_t i = 0; i < buses_.size(); ++i) {
    auto& b = report.buses[i];
    b.bus = i;
    b.name = bus_name(i);
    for (const auto& [id, r] : robots_) {
      if (r.bus != i) continue;
      ++b.robots;
      b.moving += moving_.contains(id) ? 1 : 0;
    }
  }
  co_await for_each_concurrently(buses_.size(), [&](std::size_t i) -> asio::awaitable<void> {
    Result<void> r = ok();
    for (unsigned attempt = 0; attempt < std::max(1u, options_.emergency_send_attempts); ++attempt) {
      r = co_await buses_[i].client->broadcast_now(CommandId::trajectory_abort);
      if (r) {
        report.buses[i].sent = true;
        co_return;
      }
      co_await core::sleep_for(10ms);
    }
    report.buses[i].error = r.error().message();
    const auto msg = fmt::format("bus {}: TRAJECTORY_ABORT not sent: {}", bus_name(i), r.error().message());
    spdlog::error("fps array: {}", msg);
    lock_->record_stop_error(msg);
  });
  last_stop_ = report;
  co_return report;
}

asio::awaitable<StopReport> Array::emergency_stop(std::string reason) {
  lock_for(reason);
  auto report = co_await stop_everyone(std::move(reason));
  co_return report;
}

void Array::request_stop(std::string reason) {
  lock_for(std::move(reason));
  stop_in_background();
}

// --- stop reports --------------------------------------------------------------------------------

std::size_t StopReport::robots_reached() const noexcept {
  std::size_t n = 0;
  for (const auto& b : buses) n += b.sent ? b.robots : 0;
  return n;
}

std::size_t StopReport::moving_reached() const noexcept {
  std::size_t n = 0;
  for (const auto& b : buses) n += b.sent ? b.moving : 0;
  return n;
}

std::size_t StopReport::buses_sent() const noexcept {
  return static_cast<std::size_t>(std::count_if(buses.begin(), buses.end(), [](const BusStop& b) { return b.sent; }));
}

std::string StopReport::to_text() const {
  std::vector<std::string> parts;
  for (const auto& b : buses) {
    if (b.sent) parts.push_back(fmt::format("{} {} robots", b.name, b.robots));
  }
  std::string out = fmt::format("{}: stopped {} robots ({} of them moving under this host) with TRAJECTORY_ABORT on {} of {} buses{}{}\n",
                                reason, robots_reached(), moving_reached(), buses_sent(), buses.size(),
                                parts.empty() ? "" : ": ", fmt::join(parts, ", "));
  for (const auto& b : buses) {
    if (!b.sent) out += fmt::format("  bus {}: NOT stopped ({} robots, {} moving): {}\n", b.name, b.robots, b.moving, b.error);
  }
  return out;
}

asio::awaitable<Result<UnlockReport>> Array::unlock() {
  const std::size_t collisions_before = lock_->state().collisions.size();
  auto results = co_await broadcast_on(all_buses(), CommandId::stop_trajectory);
  UnlockReport report;
  std::vector<std::string> failures;
  std::set<std::uint16_t> acked;
  for (const auto& b : results) {
    if (!b.result) {
      failures.push_back(fmt::format("bus {}: {}", bus_name(b.bus), b.result.error().message()));
      continue;
    }
    for (const auto& r : b.result.value().replies) {
      if (r.accepted()) acked.insert(r.positioner);
    }
  }
  report.acknowledged.assign(acked.begin(), acked.end());
  for (const auto& [id, r] : robots_) {
    if (!acked.contains(id)) report.silent.push_back(id);
  }
  if (!failures.empty()) {
    co_return Error(HostErrc::locked, fmt::format("STOP_TRAJECTORY could not be sent ({}); the array stays locked",
                                                  fmt::join(failures, "; ")));
  }
  if (lock_->state().collisions.size() != collisions_before) {
    co_return Error(HostErrc::locked, "a collision was reported while unlocking; the array stays locked");
  }
  if (lock_->locked()) {
    spdlog::info("fps array unlocked ({} robots acknowledged STOP_TRAJECTORY)", report.acknowledged.size());
    ++counters_.unlocks;
  }
  lock_->clear();
  co_return report;
}

// --- bus-wide switches ---------------------------------------------------------------------------

asio::awaitable<Result<void>> Array::broadcast_checked(CommandId c) {
  auto results = co_await broadcast_on(all_buses(), c);
  std::vector<std::string> problems;
  std::set<std::uint16_t> acked;
  for (const auto& b : results) {
    if (!b.result) {
      problems.push_back(fmt::format("bus {}: {}", bus_name(b.bus), b.result.error().message()));
      continue;
    }
    for (const auto& r : b.result.value().replies) {
      if (r.accepted()) {
        acked.insert(r.positioner);
      } else if (robots_.contains(r.positioner)) {
        problems.push_back(r.error().message());
      }
    }
  }
  std::vector<std::uint16_t> silent;
  for (const auto& [id, r] : robots_) {
    if (!acked.contains(id)) silent.push_back(id);
  }
  if (!silent.empty()) problems.push_back(fmt::format("no acknowledgement from positioners {}", fmt::join(silent, ", ")));
  if (!problems.empty()) {
    co_return Error(HostErrc::sequence_failed,
                    fmt::format("{} broadcast: {}", protocol::command_name(c), fmt::join(problems, "; ")));
  }
  co_return ok();
}

asio::awaitable<Result<void>> Array::set_hall(bool on) {
  co_return co_await broadcast_checked(on ? CommandId::switch_on_hall : CommandId::switch_off_hall);
}

asio::awaitable<Result<void>> Array::stop_all(bool clear_collision_flags) {
  co_return co_await broadcast_checked(clear_collision_flags ? CommandId::stop_trajectory : CommandId::trajectory_abort);
}

// --- motion --------------------------------------------------------------------------------------

asio::awaitable<Result<Array::MoveResults>> Array::goto_absolute(std::map<std::uint16_t, ArmAngles> targets) {
  return move_many(std::move(targets), false);
}

asio::awaitable<Result<Array::MoveResults>> Array::goto_relative(std::map<std::uint16_t, ArmAngles> deltas) {
  return move_many(std::move(deltas), true);
}

asio::awaitable<Result<Array::MoveResults>> Array::move_many(std::map<std::uint16_t, ArmAngles> values,
                                                             bool relative) {
  std::vector<std::pair<std::uint16_t, ArmAngles>> list(values.begin(), values.end());
  std::vector<std::uint16_t> ids;
  for (const auto& [id, t] : list) {
    if (!find(id)) co_return Error(HostErrc::unknown_positioner, fmt::format("positioner {}", id));
    ids.push_back(id);
  }
  const auto move = relative ? CommandId::go_to_relative_position : CommandId::go_to_absolute_position;
  if (auto a = admit_all(move, ids); !a) co_return a.error();
  std::vector<Result<MoveResult>> results(list.size(), Result<MoveResult>(Error(HostErrc::cancelled)));
  const MovingMark mark(moving_, std::move(ids));
  co_await for_each_concurrently(list.size(), [&](std::size_t i) -> asio::awaitable<void> {
    Positioner* p = find(list[i].first);
    // (no co_await inside ?: : gcc 12 miscompiles it)
    if (relative) {
      results[i] = co_await p->goto_relative(list[i].second);
    } else {
      results[i] = co_await p->goto_absolute(list[i].second);
    }
  });
  MoveResults out;
  for (std::size_t i = 0; i < list.size(); ++i) out.emplace(list[i].first, std::move(results[i]));
  co_return out;
}

// --- counters and shutdown -----------------------------------------------------------------------

ClientCounters Array::client_totals() const {
  ClientCounters t;
  for (const auto& b : buses_) {
    const auto& c = b.client->counters();
    t.sent += c.sent;
    t.send_errors += c.send_errors;
    t.replies += c.replies;
    t.timeouts += c.timeouts;
    t.retries += c.retries;
    t.late += c.late;
    t.unmatched += c.unmatched;
    t.broadcasts += c.broadcasts;
    t.broadcast_duplicates += c.broadcast_duplicates;
    t.unsolicited += c.unsolicited;
    t.collisions += c.collisions;
    t.foreign += c.foreign;
    t.bad_replies += c.bad_replies;
    t.uid_waits += c.uid_waits;
    t.slot_waits += c.slot_waits;
    t.refused += c.refused;
    for (std::size_t i = 0; i < t.by_code.size(); ++i) t.by_code[i] += c.by_code[i];
  }
  return t;
}

asio::awaitable<void> Array::close() {
  while (background_ > 0) {
    core::Wakeup w(executor_);
    background_waiters_.push_back(&w);
    co_await w.wait_until(core::TimePoint::max());
    std::erase(background_waiters_, &w);
  }
  for (auto& b : buses_) {
    b.client->unsubscribe(b.subscription);
    co_await b.client->stop();
  }
}

}  // namespace axon::fps::host
