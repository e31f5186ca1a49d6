#include "axon/fps/host/client.hpp"

#include "axon/can/open.hpp"
#include "axon/core/loop_thread.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/host/back_off.hpp"
#include "axon/fps/host/cold_control.hpp"
#include "axon/fps/host/troubleshoot.hpp"
#include "axon/fps/host/datum_check.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/host/plan_and_move.hpp"
#include "axon/fps/host/plane_upgrade.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/targets.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/this_coro.hpp>
#include <fmt/format.h>

namespace axon::fps {

namespace asio = boost::asio;

namespace {

using Seconds = std::chrono::duration<double>;
core::Duration duration_of(double s) { return std::chrono::duration_cast<core::Duration>(Seconds(s)); }

template <class T>
T need(Result<T>&& r) {
  if (!r) throw Exception(r.error());
  if constexpr (!std::is_void_v<T>) return std::move(r).value();
}

Angles angles(const host::ArmAngles& a) { return {a.alpha, a.beta}; }
std::optional<Angles> angles(const std::optional<host::ArmAngles>& a) {
  return a ? std::optional<Angles>(angles(*a)) : std::nullopt;
}

std::vector<RobotStatus> rows_of(const host::StatusTable& table) {
  std::vector<RobotStatus> out;
  for (const auto& r : table.rows) {
    RobotStatus s{r.id, r.bus_name, r.state(), r.ready(), r.firmware ? r.firmware->to_string() : std::string(), {},
                  angles(r.position), r.error};
    if (r.status) s.flags = r.status->names();
    out.push_back(std::move(s));
  }
  return out;
}

MoveOutcome outcome_of(const host::TrajectoryReport& report) {
  MoveOutcome out{report.completed, report.summary(), {}};
  for (const auto& r : report.robots)
    out.robots.push_back({r.id, r.state == host::RobotState::completed, host::to_string(r.state), angles(r.target),
                          angles(r.reached), r.detail});
  return out;
}

MoveOutcome outcome_of(const std::map<std::uint16_t, host::ArmAngles>& targets, const host::Array::MoveResults& results) {
  MoveOutcome out{true, {}, {}};
  for (const auto& [id, r] : results) {
    RobotMove m{id, r.has_value(), r ? "completed" : "failed", angles(targets.at(id)), std::nullopt, {}};
    if (r) m.reached = angles(r.value().reached);
    else m.detail = r.error().message();
    if (!m.ok) out.summary += fmt::format("robot {}: {}\n", id, m.detail);
    out.completed = out.completed && m.ok;
    out.robots.push_back(std::move(m));
  }
  return out;
}

PlanOutcome plan_outcome(const plan::CollisionModel& model, const plan::Plan& p, std::string notes) {
  PlanOutcome out{p.verified, model.size(), p.not_reached, p.stats.duration_s, p.stats.plan_s, p.check.min_clearance_mm,
                  {}, std::move(notes), {}, {}};
  for (std::size_t i = 0; i < model.size() && i < p.robots.size(); ++i)
    out.ends[static_cast<std::uint16_t>(model.robot(i).id())] = {p.robots[i].end.alpha_deg, p.robots[i].end.beta_deg};
  out.notes += p.summary(model);
  for (const auto id : p.safe_zone.robots()) out.outside_safe_zone.push_back(static_cast<std::uint16_t>(id));
  out.safe_zone = p.safe_zone.summary();
  return out;
}

}  // namespace

const RobotMove* MoveOutcome::find(std::uint16_t id) const noexcept {
  for (const auto& r : robots)
    if (r.id == id) return &r;
  return nullptr;
}

struct Client::Impl {
  ClientConfig config;
  core::LoopThread loop;  // first: it outlives what runs on it
  std::vector<std::unique_ptr<can::Bus>> buses;
  std::unique_ptr<host::Array> own_array;
  std::unique_ptr<host::FocalPlaneArray> plane_array;
  host::Array* array = nullptr;
  std::optional<FocalPlane> layout;

  // A blocking call: the coroutine on the loop, bounded by the call timeout (overrun: stop everyone).
  template <class F>
  auto run(F make) {
    return loop.run(std::move(make), duration_of(config.call_timeout_s), [this] {
      if (array) array->request_stop("a blocking call overran its timeout");
    });
  }

  host::Array& open_array() const {
    if (!array) throw Exception(Error(host::HostErrc::invalid_argument, "the client is not open: call open() first"));
    return *array;
  }

  // The array that can start by the PLC's sync line: opened on a plane, with a PLC.
  host::FocalPlaneArray& sync_array() const {
    if (!plane_array || !plane_array->plc())
      throw Exception(Error(host::HostErrc::invalid_argument,
                            "a start by the sync line needs the PLC: open(plane) with ClientConfig::plc_address"));
    return *plane_array;
  }

  [[nodiscard]] host::ArrayOptions array_options() const {
    host::ArrayOptions o;
    o.client.timeout = duration_of(config.reply_timeout_s);
    o.positioner.poll_interval = duration_of(config.poll_interval_s);
    o.positioner.position_tolerance = config.position_tolerance_deg;
    if (config.field_firmware_history) o.positioner.firmware_history = protocol::FirmwareHistory::field;
    if (config.document_version_byte_order) o.positioner.version_byte_order = protocol::VersionByteOrder::document;
    o.discover_window = duration_of(config.discover_window_s);
    return o;
  }

  // On the loop: stop what moves, close the array and the buses.
  asio::awaitable<void> shut() {
    if (!array) co_return;
    if (!array->moving().empty()) co_await array->emergency_stop("the client closed while robots moved");
    if (plane_array) co_await plane_array->close();
    else co_await array->close();
    for (auto& b : buses) b->close();
  }
};

Client::Client(ClientConfig config) : impl_(std::make_unique<Impl>()) { impl_->config = config; }

Client::~Client() { close(); }

void Client::close() noexcept {
  if (!impl_ || !impl_->array) return;
  auto* impl = impl_.get();
  try {
    impl->loop.run([impl] { return impl->shut(); }, std::chrono::seconds(10));
  } catch (...) {  // a close that fails leaves nothing more to do than drop the handles
  }
  try {
    impl->loop.call([impl] {
      impl->plane_array.reset();
      impl->own_array.reset();
      impl->buses.clear();
    });
  } catch (...) {
  }
  impl->array = nullptr;
}

bool Client::is_open() const noexcept { return impl_->array != nullptr; }

void Client::set_call_timeout(double seconds) {
  if (!(seconds > 0)) throw Exception(Error(host::HostErrc::invalid_argument, fmt::format("call timeout {:g} s: must be > 0", seconds)));
  impl_->config.call_timeout_s = seconds;
}

void Client::open(const std::vector<std::string>& bus_specs) {
  close();
  std::vector<can::BusSpec> specs;
  for (const auto& text : bus_specs) specs.push_back(need(can::parse_bus_spec(text)));
  if (specs.empty()) throw Exception(Error(host::HostErrc::invalid_argument, "open: no bus given"));
  need(can::check_distinct(specs));
  auto* impl = impl_.get();
  impl->run([impl, specs]() -> asio::awaitable<void> {
    auto opened = co_await can::open_buses(co_await asio::this_coro::executor, specs);
    impl->buses = need(std::move(opened));
    std::vector<can::Bus*> raw;
    for (auto& b : impl->buses) raw.push_back(b.get());
    impl->own_array = std::make_unique<host::Array>(raw, impl->array_options());
    impl->array = impl->own_array.get();
  });
}

void Client::open(const FocalPlane& plane, const std::map<std::uint16_t, std::string>& gateway_addresses) {
  close();
  host::FocalPlaneArrayOptions o;
  o.array = impl_->array_options();
  for (const auto& [id, text] : gateway_addresses) o.addresses[id] = need(net::parse_endpoint(text, can::kCanNetPort));
  if (!impl_->config.plc_address.empty()) o.plc = need(net::parse_endpoint(impl_->config.plc_address, 502));
  o.sync_hold = duration_of(impl_->config.sync_hold_s);
  auto* impl = impl_.get();
  impl->run([impl, plane, o]() -> asio::awaitable<void> {
    auto connected = co_await host::FocalPlaneArray::connect(co_await asio::this_coro::executor, plane, o);
    impl->plane_array = need(std::move(connected));
    impl->array = &impl->plane_array->array();
  });
  impl->layout = plane;
}

void Client::set_layout(const FocalPlane& plane) { impl_->layout = plane; }

std::vector<RobotStatus> Client::discover() {
  auto* impl = impl_.get();
  impl->open_array();
  return impl->run([impl]() -> asio::awaitable<std::vector<RobotStatus>> {
    Result<host::DiscoveryReport> r = Error(host::HostErrc::cancelled);
    if (impl->plane_array) r = co_await impl->plane_array->discover();
    else r = co_await impl->array->discover();
    co_return rows_of(need(std::move(r)).table);
  });
}

std::vector<RobotStatus> Client::status() {
  auto& array = impl_->open_array();
  return impl_->run([&array]() -> asio::awaitable<std::vector<RobotStatus>> {
    const auto table = co_await array.status_table(true);
    co_return rows_of(table);
  });
}

void Client::with_loop(const std::function<void(host::FocalPlaneArray*, asio::io_context&)>& f) {
  impl_->loop.call([this, &f] { f(impl_->plane_array.get(), impl_->loop.executor().context()); });
}

std::vector<std::uint16_t> Client::robots() const {
  auto& array = impl_->open_array();
  return impl_->loop.call([&array] { return array.ids(); });
}

MoveOutcome Client::goto_absolute(const std::map<std::uint16_t, Angles>& targets) {
  auto& array = impl_->open_array();
  std::map<std::uint16_t, host::ArmAngles> t;
  for (const auto& [id, a] : targets) t[id] = {a.alpha, a.beta};
  return impl_->run([&array, t]() -> asio::awaitable<MoveOutcome> {
    auto r = co_await array.goto_absolute(t);
    co_return outcome_of(t, need(std::move(r)));
  });
}

MoveOutcome Client::run_trajectories(const std::map<std::uint16_t, ArmPath>& paths, bool by_sync_line) {
  auto& array = impl_->open_array();
  auto* sync = by_sync_line ? &impl_->sync_array() : nullptr;
  host::Trajectories uploads;
  for (const auto& [id, path] : paths) {
    std::vector<protocol::ArmPoint> alpha, beta;
    for (const auto& [deg, s] : path.alpha) alpha.push_back({deg, s});
    for (const auto& [deg, s] : path.beta) beta.push_back({deg, s});
    auto t = protocol::Trajectory::from_physical(alpha, beta);
    if (!t) throw Exception(Error(t.error().code, fmt::format("robot {}: {}", id, t.error().detail)));
    uploads.emplace(id, std::move(t).value());
  }
  return impl_->run([&array, sync, uploads]() -> asio::awaitable<MoveOutcome> {
    // Two statements, not one conditional expression: gcc 12 destroys a co_await's temporaries
    // twice inside ?: (a double free here).
    if (sync) co_return outcome_of(need(co_await sync->run_trajectories(uploads, {}, true)));
    co_return outcome_of(need(co_await array.run_trajectories(uploads)));
  });
}

namespace {

// The geometry the sweep to the hard stops is checked on: the layout's, when there is one.
std::shared_ptr<const plan::CollisionModel> datum_model(const Client::Impl& impl) {
  if (!impl.layout) return nullptr;
  return std::make_shared<const plan::CollisionModel>(need(plan::model_from_layout(*impl.layout)));
}

}  // namespace

Angles Client::go_to_datums(std::uint16_t id) {
  auto& array = impl_->open_array();
  auto model = datum_model(*impl_);
  return impl_->run([&array, id, model]() -> asio::awaitable<Angles> {
    auto* p = need(array.positioner(id));
    if (model) need(co_await host::check_datum_sweep(array, *model, id, host::Arm::both));
    auto done = co_await p->go_to_datums(host::Arm::both);
    need(std::move(done));
    auto at = co_await p->read_position();
    co_return angles(need(std::move(at)));
  });
}

namespace {

BackOffOutcome outcome_of(const host::BackOffReport& r) {
  BackOffOutcome out{r.contacts_before, {}, r.contacts_after, r.ok(), r.summary()};
  for (const auto& s : r.steps)
    out.moves.push_back({s.id, s.moved, s.plan.arm, s.plan.step_deg, {s.plan.from.alpha_deg, s.plan.from.beta_deg},
                         {s.plan.to.alpha_deg, s.plan.to.beta_deg}, s.plan.clearance_before_mm, s.plan.clearance_after_mm,
                         s.problem});
  return out;
}

}  // namespace

BackOffOutcome Client::back_off(const std::vector<std::uint16_t>& ids) {
  auto& array = impl_->open_array();
  auto model = datum_model(*impl_);
  if (!model) throw Exception(Error(host::HostErrc::invalid_argument, "back_off needs the layout: open(plane) or set_layout()"));
  return impl_->run([&array, ids, model]() -> asio::awaitable<BackOffOutcome> {
    host::BackOffRequest request;
    request.ids = ids;
    auto r = co_await host::back_off(array, *model, request);
    co_return outcome_of(need(std::move(r)));
  });
}

host::FrictionReport Client::friction_survey(const std::vector<std::uint16_t>& ids, host::FrictionOptions options,
                                            const std::string& history_file) {
  auto& array = impl_->open_array();
  auto model = datum_model(*impl_);
  if (!model) throw Exception(Error(host::HostErrc::invalid_argument, "friction_survey needs the layout: open(plane) or set_layout()"));
  if (!history_file.empty()) {
    auto earlier = need(host::load_friction_history(history_file));
    options.history.insert(options.history.end(), earlier.begin(), earlier.end());
  }
  auto report = impl_->run([&array, ids, model, options]() -> asio::awaitable<host::FrictionReport> {
    auto r = co_await host::friction_survey(array, *model, ids, options);
    co_return need(std::move(r));
  });
  if (!history_file.empty()) need(host::append_friction_history(history_file, report.records()));
  return report;
}

host::HallTestReport Client::hall_test(std::uint16_t id, const host::HallTestOptions& options) {
  auto& array = impl_->open_array();
  auto model = datum_model(*impl_);
  if (!model) throw Exception(Error(host::HostErrc::invalid_argument, "hall_test needs the layout: open(plane) or set_layout()"));
  return impl_->run([&array, id, model, options]() -> asio::awaitable<host::HallTestReport> {
    auto r = co_await host::hall_test(array, *model, id, options);
    co_return need(std::move(r));
  });
}

namespace {

std::string version_text(const std::optional<protocol::FirmwareVersion>& v) { return v ? v->to_string() : ""; }

FirmwareOutcome outcome_of(const host::PlaneUpgradeReport& r) {
  FirmwareOutcome out{r.ok(), {}, r.summary()};
  for (const auto& rr : r.robots)
    out.robots.push_back({rr.id, rr.sextant, host::to_string(rr.outcome), rr.attempts, rr.reason, rr.half_written,
                          version_text(rr.before), version_text(rr.after)});
  return out;
}

}  // namespace

LayoutCheck Client::check_layout() {
  impl_->open_array();
  auto* fpa = impl_->plane_array.get();
  if (!fpa) throw Exception(Error(host::HostErrc::invalid_argument, "check_layout needs a layout: open(plane)"));
  return impl_->run([fpa]() -> asio::awaitable<LayoutCheck> { co_return co_await fpa->check_layout(); });
}

ColdOutcome Client::apply_cold_policy() {
  impl_->open_array();
  auto* fpa = impl_->plane_array.get();
  if (!fpa) throw Exception(Error(host::HostErrc::invalid_argument, "apply_cold_policy needs a layout: open(plane)"));
  const auto r = impl_->run([fpa]() -> asio::awaitable<host::ColdApplyReport> {
    host::ColdControl cold(*fpa);
    auto step = co_await cold.step(true);
    co_return need(std::move(step));
  });
  const auto& d = r.decision;
  return {d.settings.motor_rpm, d.settings.alpha_holding_pct, d.settings.beta_holding_pct, d.coldest_c, d.coldest_sensor,
          r.applied, r.failed, r.to_text()};
}

FirmwareOutcome Client::upgrade_firmware(const std::vector<std::uint8_t>& image, const UpgradeSettings& settings,
                                        const std::function<void(const SextantUpgrade&)>& progress) {
  impl_->open_array();
  auto* fpa = impl_->plane_array.get();
  if (!fpa) throw Exception(Error(host::HostErrc::invalid_argument, "upgrade_firmware needs a layout: open(plane)"));
  if (!(settings.power_off_s >= 0 && settings.power_off_s <= 60))
    throw Exception(Error(host::HostErrc::invalid_argument, "power_off_s must be within 0..60"));
  host::PlaneUpgradeOptions o;
  if (!settings.expected_version.empty()) o.expected_version = need(protocol::FirmwareVersion::parse(settings.expected_version));
  o.sextants = settings.sextants;
  o.retries = settings.retries;
  o.power_off_time = duration_of(settings.power_off_s);
  if (progress)
    o.progress = [&progress](const host::SextantProgress& p) {
      progress({p.sextant, p.total, p.done, p.failed, p.bytes, p.seconds, p.finished, p.to_text()});
    };
  return impl_->run([fpa, &image, o]() -> asio::awaitable<FirmwareOutcome> {
    auto r = co_await host::upgrade_plane(*fpa, image, o);
    co_return outcome_of(need(std::move(r)));
  });
}

CalibrationOutcome Client::calibrate(std::uint16_t id, const CalibrationSteps& steps) {
  auto& array = impl_->open_array();
  host::CalibrationPlan plan;
  plan.motors = steps.motors;
  plan.datums = steps.datums;
  plan.cogging = steps.cogging;
  plan.save = steps.save;
  auto model = plan.datums ? datum_model(*impl_) : nullptr;
  return impl_->run([&array, id, plan, model]() -> asio::awaitable<CalibrationOutcome> {
    auto* p = need(array.positioner(id));
    if (model) need(co_await host::check_datum_sweep(array, *model, id, host::Arm::both));
    auto r = co_await p->calibrate(plan);
    const auto rep = need(std::move(r));
    const auto arms = [](const std::optional<protocol::ArmValues>& v) {
      return v ? std::optional<Angles>(Angles{static_cast<double>(v->alpha), static_cast<double>(v->beta)}) : std::nullopt;
    };
    co_return CalibrationOutcome{arms(rep.motor_error), arms(rep.datum_error), rep.saved, rep.final_status.names()};
  });
}

namespace {

PlanAndMoveOutcome plan_and_move_on(Client::Impl& impl, const std::vector<plan::Target>& targets, const PlanSettings& s);

}  // namespace

PlanAndMoveOutcome Client::plan_and_move(const std::map<std::uint16_t, Angles>& targets, const PlanSettings& settings) {
  std::vector<plan::Target> t;
  for (const auto& [id, a] : targets) {
    plan::Target target;
    target.robot = id;
    target.pose = plan::Pose{a.alpha, a.beta};
    t.push_back(std::move(target));
  }
  return plan_and_move_on(*impl_, t, settings);
}

PlanAndMoveOutcome Client::plan_and_move(const std::string& target_file, const PlanSettings& settings) {
  return plan_and_move_on(*impl_, need(plan::load_targets(target_file)), settings);
}

namespace {

PlanAndMoveOutcome plan_and_move_on(Client::Impl& impl, const std::vector<plan::Target>& targets, const PlanSettings& s) {
  auto& array = impl.open_array();
  if (!impl.layout)
    throw Exception(Error(host::HostErrc::invalid_argument, "plan_and_move needs the layout: open(plane) or set_layout()"));
  plan::LayoutModelOptions lo;
  lo.buffer_mm = s.buffer_mm;
  auto model = std::make_shared<plan::CollisionModel>(need(plan::model_from_layout(*impl.layout, lo)));
  std::string notes;
  auto poses = need(plan::target_poses(*model, targets, s.park_bad_targets ? plan::TargetPolicy::park : plan::TargetPolicy::reject,
                                       &notes));
  host::PlanAndMoveOptions o;
  o.planner.speed = {s.speed_deg_s, s.speed_deg_s};
  o.planner.seed = s.seed;
  o.allow_partial = s.allow_partial;
  o.refuse_outside_safe_zone = s.refuse_outside_safe_zone;
  o.point_fibre = plan::point_fibres(*model, targets, poses);
  if (s.start_by_sync_line) {
    auto* sync = &impl.sync_array();
    o.run = [sync](host::Trajectories t, host::TrajectoryOptions to) { return sync->run_trajectories(std::move(t), to, true); };
  }
  const FocalPlane& plane = *impl.layout;
  return impl.run([&array, &plane, model, poses, o, notes]() -> asio::awaitable<PlanAndMoveOutcome> {
    auto r = co_await host::plan_and_move(array, plane, *model, poses, o);
    const auto report = need(std::move(r));
    PlanAndMoveOutcome out{plan_outcome(*model, report.plan, notes), report.run.has_value(), {}};
    if (report.run) out.move = outcome_of(*report.run);
    else out.move.completed = true;
    co_return out;
  });
}

}  // namespace

StopOutcome Client::emergency_stop(const std::string& reason) {
  auto& array = impl_->open_array();
  return impl_->run([&array, reason]() -> asio::awaitable<StopOutcome> {
    const auto rep = co_await array.emergency_stop(reason);
    co_return StopOutcome{rep.reason, rep.robots_reached(), rep.buses_sent(), rep.buses.size(), rep.to_text()};
  });
}

void Client::stop(bool clear_flags) {
  auto& array = impl_->open_array();
  impl_->run([&array, clear_flags]() -> asio::awaitable<void> {
    auto r = co_await array.stop_all(clear_flags);
    need(std::move(r));
  });
}

UnlockOutcome Client::unlock() {
  auto& array = impl_->open_array();
  return impl_->run([&array]() -> asio::awaitable<UnlockOutcome> {
    auto r = co_await array.unlock();
    auto u = need(std::move(r));
    co_return UnlockOutcome{u.acknowledged, u.silent};
  });
}

bool Client::locked() const {
  auto& array = impl_->open_array();
  return impl_->loop.call([&array] { return array.locked(); });
}

std::string Client::lock_reason() const {
  auto& array = impl_->open_array();
  return impl_->loop.call([&array] { return array.locked() ? array.lock_state().reason : std::string(); });
}

void Client::interrupt(const std::string& reason) noexcept {
  auto* impl = impl_.get();
  try {
    // On the loop, between the steps of the call that waits (request_stop must run there).
    asio::post(impl->loop.executor(), [impl, reason] {
      if (impl->array) impl->array->request_stop(reason);
    });
  } catch (...) {  // only allocation can fail here; there is nothing to stop then but the caller
  }
}

}  // namespace axon::fps
