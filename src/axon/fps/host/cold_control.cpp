#include "axon/fps/host/cold_control.hpp"

#include "axon/core/wakeup.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/focal_plane_array.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>

namespace axon::fps::host {

std::string ColdApplyReport::to_text() const {
  std::string out = decision.report();
  if (!sent) {
    out += "  settings unchanged: nothing sent\n";
  } else {
    out += fmt::format("  {}: applied to {} robots, {} failed\n", changed ? "changed" : "resent", applied.size(),
                       failed.size());
  }
  for (const auto& [id, why] : failed) out += fmt::format("  positioner {}: {}\n", id, why);
  return out;
}

ColdControl::ColdControl(FocalPlaneArray& plane, plc::ColdPolicyConfig config)
    : plane_(&plane), config_(std::move(config)) {}

asio::awaitable<Result<ColdApplyReport>> ColdControl::step(bool force) {
  auto* plc = plane_->plc();
  if (plc == nullptr) co_return Error(HostErrc::invalid_argument, "the cold policy needs the PLC (no PLC endpoint given)");
  auto temps = co_await plc->call([](plc::PlcClient& c) { return c.temperatures(); });
  if (!temps) co_return temps.error();
  ColdApplyReport rep;
  rep.decision = plc::cold_policy(temps.value(), config_);
  const auto& s = rep.decision.settings;
  rep.changed = !applied_ || *applied_ != s;
  Array& array = plane_->array();
  std::vector<std::uint16_t> targets;
  if (rep.changed || force) {
    targets = array.ids();
  } else {
    targets.assign(pending_.begin(), pending_.end());
  }
  if (targets.empty()) co_return rep;
  rep.sent = true;
  const auto rpm = static_cast<std::int64_t>(s.motor_rpm);
  const auto alpha = static_cast<std::int64_t>(std::lround(s.alpha_holding_pct));
  const auto beta = static_cast<std::int64_t>(std::lround(s.beta_holding_pct));
  std::vector<std::string> errors(targets.size());
  co_await for_each_concurrently(targets.size(), [&](std::size_t i) -> asio::awaitable<void> {
    Positioner* p = array.find(targets[i]);
    if (p == nullptr) {
      errors[i] = "unknown positioner";
      co_return;
    }
    auto sp = co_await p->set_speed(rpm, rpm);
    if (!sp) {
      errors[i] = fmt::format("SET_SPEED: {}", sp.error().message());
      co_return;
    }
    auto hc = co_await p->set_holding_current(alpha, beta);
    if (!hc) errors[i] = fmt::format("SET_HOLDING_CURRENT: {}", hc.error().message());
  });
  if (rep.changed || force) pending_.clear();
  for (std::size_t i = 0; i < targets.size(); ++i) {
    if (errors[i].empty()) {
      rep.applied.push_back(targets[i]);
      pending_.erase(targets[i]);
    } else {
      rep.failed.emplace(targets[i], errors[i]);
      pending_.insert(targets[i]);
    }
  }
  applied_ = s;
  spdlog::info("fps cold policy: {} rpm, holding alpha {} % beta {} %: {} robots, {} failed", rpm, alpha, beta,
               rep.applied.size(), rep.failed.size());
  co_return rep;
}

asio::awaitable<void> ColdControl::watch(core::Duration period, const bool* stop,
                                         std::function<void(const Result<ColdApplyReport>&)> on_report,
                                         core::Duration limit) {
  using Clock = std::chrono::steady_clock;
  constexpr auto kStopCheck = std::chrono::milliseconds(50);
  const auto t0 = Clock::now();
  auto stopped = [&] {
    return (stop != nullptr && *stop) || (limit > core::Duration::zero() && Clock::now() - t0 >= limit);
  };
  bool first = true;
  while (!stopped()) {
    auto r = co_await step(first);
    first = false;
    if (on_report) on_report(r);
    const auto next = Clock::now() + period;
    while (!stopped() && Clock::now() < next) co_await core::sleep_for(kStopCheck);
  }
}

}  // namespace axon::fps::host
