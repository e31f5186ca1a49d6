#include "axon/blmc/sim/fault_plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace axon::blmc::sim {
namespace {

Result<core::Duration> seconds_at(const core::ConfigNode& node, std::string_view key) {
  AXON_TRY(c, node.child(key));
  AXON_TRY(v, c.as<double>());
  if (!std::isfinite(v) || v < 0 || v > 1e6) return c.error(CoreErrc::config_bad_value, "expected seconds within 0..1e6");
  return std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(v));
}

Result<LinkDirection> direction(const core::ConfigNode& node) {
  AXON_TRY(d, node.get_or<std::string>("direction", "both"));
  if (d == "rx") return LinkDirection::rx;
  if (d == "tx") return LinkDirection::tx;
  if (d == "both") return LinkDirection::both;
  AXON_TRY(c, node.child("direction"));
  return c.error(CoreErrc::config_bad_value, "expected rx, tx or both, got '" + d + "'");
}

}  // namespace

std::string_view name(FaultKind k) noexcept {
  switch (k) {
    case FaultKind::encoder: return "encoder";
    case FaultKind::pos_converter: return "pos_converter";
    case FaultKind::transmit: return "transmit";
    case FaultKind::over_current: return "over_current";
    case FaultKind::undocumented: return "undocumented";
  }
  return "?";
}

Result<void> BoardFaultPlan::validate() const {
  const auto bad = [](std::string what) { return make_error(CoreErrc::invalid_argument, "fault plan: " + what); };
  for (const auto& e : events) {
    if (e.at < core::Duration::zero() || e.duration < core::Duration::zero()) return bad("event times must not be negative");
  }
  for (const auto& s : stalls) {
    if (s.from < core::Duration::zero() || s.until <= s.from) return bad("a stall needs 0 <= from < until");
  }
  for (const auto& d : drops) {
    if (!std::isfinite(d.probability) || d.probability < 0 || d.probability > 1) return bad("drop probability must be within 0..1");
    if (d.from < core::Duration::zero() || d.until <= d.from) return bad("a drop window needs 0 <= from < until");
  }
  return ok();
}

Result<BoardFaultPlan> BoardFaultPlan::from_config(const core::ConfigNode& node,
                                                   std::initializer_list<std::string_view> extra_keys) {
  for (const auto& k : node.keys()) {
    const bool known = k == "seed" || k == "events" || k == "stalls" || k == "drops" ||
                       std::find(extra_keys.begin(), extra_keys.end(), k) != extra_keys.end();
    if (!known) {
      AXON_TRY(c, node.child(k));
      return c.error(CoreErrc::config_unknown_key, "unknown key (expected seed, events, stalls, drops)");
    }
  }
  BoardFaultPlan plan;
  AXON_TRY(seed, node.get_or<std::uint64_t>("seed", plan.seed));
  plan.seed = seed;
  if (node.has("events")) {
    AXON_TRY(list, node.child("events"));
    AXON_TRY(items, list.items());
    for (const auto& it : items) {
      AXON_TRY(it.reject_unknown({"at_s", "kind", "duration_s", "persistent"}));
      FaultEvent e;
      AXON_TRY(at, seconds_at(it, "at_s"));
      e.at = at;
      AXON_TRY(kind, it.get<std::string>("kind"));
      if (kind == "encoder") e.kind = FaultKind::encoder;
      else if (kind == "pos_converter") e.kind = FaultKind::pos_converter;
      else if (kind == "transmit") e.kind = FaultKind::transmit;
      else if (kind == "over_current") e.kind = FaultKind::over_current;
      else if (kind == "undocumented") e.kind = FaultKind::undocumented;
      else {
        AXON_TRY(c, it.child("kind"));
        return c.error(CoreErrc::config_bad_value,
                       "expected encoder, pos_converter, transmit, over_current or undocumented, got '" + kind + "'");
      }
      if (it.has("duration_s")) {
        AXON_TRY(d, seconds_at(it, "duration_s"));
        e.duration = d;
      }
      AXON_TRY(p, it.get_or<bool>("persistent", false));
      e.persistent = p;
      plan.events.push_back(e);
    }
  }
  if (node.has("stalls")) {
    AXON_TRY(list, node.child("stalls"));
    AXON_TRY(items, list.items());
    for (const auto& it : items) {
      AXON_TRY(it.reject_unknown({"from_s", "until_s", "direction"}));
      StallWindow s;
      AXON_TRY(from, seconds_at(it, "from_s"));
      AXON_TRY(until, seconds_at(it, "until_s"));
      AXON_TRY(dir, direction(it));
      if (until <= from) return it.error(CoreErrc::config_bad_value, "until_s must be after from_s");
      s.from = from;
      s.until = until;
      s.direction = dir;
      plan.stalls.push_back(s);
    }
  }
  if (node.has("drops")) {
    AXON_TRY(list, node.child("drops"));
    AXON_TRY(items, list.items());
    for (const auto& it : items) {
      AXON_TRY(it.reject_unknown({"probability", "from_s", "until_s", "direction"}));
      DropRule d;
      AXON_TRY(p, it.get_in<double>("probability", 0.0, 1.0));
      d.probability = p;
      AXON_TRY(dir, direction(it));
      d.direction = dir;
      if (it.has("from_s")) {
        AXON_TRY(from, seconds_at(it, "from_s"));
        d.from = from;
      }
      if (it.has("until_s")) {
        AXON_TRY(until, seconds_at(it, "until_s"));
        d.until = until;
      }
      if (d.until <= d.from) return it.error(CoreErrc::config_bad_value, "until_s must be after from_s");
      plan.drops.push_back(d);
    }
  }
  return plan;
}

namespace {

void add_to(BoardFaultPlan& p, const BoardFaultPlan& plan, bool seed_given) {
  p.events.insert(p.events.end(), plan.events.begin(), plan.events.end());
  p.stalls.insert(p.stalls.end(), plan.stalls.begin(), plan.stalls.end());
  p.drops.insert(p.drops.end(), plan.drops.begin(), plan.drops.end());
  if (seed_given) p.seed = plan.seed;
}

}  // namespace

Result<std::vector<BoardFaultPlan>> load_fault_plans(const std::string& path, unsigned boards) {
  std::vector<BoardFaultPlan> plans(boards);
  if (path.empty() || boards == 0) return plans;
  AXON_TRY(root, core::ConfigNode::load_file(path));
  std::vector<core::ConfigNode> items;
  if (root.is_sequence()) {
    AXON_TRY(list, root.items());
    items = std::move(list);
  } else {
    items.push_back(root);
  }
  for (const auto& item : items) {
    AXON_TRY(plan, BoardFaultPlan::from_config(item, {"board"}));
    const bool one = item.has("board");
    unsigned which = 0;
    if (one) {
      AXON_TRY(n, item.get_in<unsigned>("board", 0u, boards - 1));
      which = n;
    }
    for (unsigned b = 0; b < boards; ++b)
      if (!one || b == which) add_to(plans[b], plan, item.has("seed"));
  }
  return plans;
}

}  // namespace axon::blmc::sim
