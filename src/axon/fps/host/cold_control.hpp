// Operation at cold temperatures, applied: reads the focal plane's temperatures from the PLC,
// decides with the pure policy (fps/plc/cold_policy.hpp) and sends the result to every robot of the
// array: SET_SPEED (both arms) and SET_HOLDING_CURRENT (alpha, beta).
//
// Settings go out only when the decision changes (or `force`), and again to robots that failed to
// take them last time. Speed and holding current are volatile in the robots: after a power cycle
// call step(true). watch() runs step() now and then every `period` until told to stop.
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/plc/cold_policy.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace axon::fps::host {

class FocalPlaneArray;

struct ColdApplyReport {
  plc::ColdDecision decision;
  bool changed = false;                         // differs from what was applied before (or first run)
  bool sent = false;                            // settings went out this time
  std::vector<std::uint16_t> applied;           // robots that took both settings
  std::map<std::uint16_t, std::string> failed; // robots that refused or did not answer (retried next step)

  // The decision, then "applied to N robots" / "unchanged", then each failure.
  [[nodiscard]] std::string to_text() const;
};

class ColdControl {
 public:
  explicit ColdControl(FocalPlaneArray& plane, plc::ColdPolicyConfig config = {});

  // One round. Errors: no PLC (HostErrc::invalid_argument), the PLC's read failing (PlcErrc).
  boost::asio::awaitable<Result<ColdApplyReport>> step(bool force = false);
  // step(true), then step() every `period` until *stop becomes true (set on the array's executor) or
  // `limit` has passed since the start (zero: no limit); both are checked every 50 ms between
  // steps, so a stop takes effect within that. Each report (or error) goes to `on_report`.
  boost::asio::awaitable<void> watch(core::Duration period, const bool* stop,
                                     std::function<void(const Result<ColdApplyReport>&)> on_report,
                                     core::Duration limit = core::Duration::zero());

  // What the robots were last told (nullopt before the first step that sent anything).
  [[nodiscard]] const std::optional<plc::ColdSettings>& applied() const noexcept { return applied_; }

 private:
  FocalPlaneArray* plane_;
  plc::ColdPolicyConfig config_;
  std::optional<plc::ColdSettings> applied_;
  std::set<std::uint16_t> pending_;  // robots that missed the last settings
};

}  // namespace axon::fps::host
