#include "axon/can/fault_plan.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>

namespace axon::can {

namespace {

using core::ConfigNode;
using axon::CoreErrc;

constexpr double kMaxDelayMs = 3'600'000.0;  // an hour: anything longer is a typo

Result<FaultRule::Action> parse_action(const ConfigNode& node) {
  AXON_TRY(c, node.child("action"));
  AXON_TRY(text, c.as<std::string>());
  if (text == "drop") return FaultRule::Action::drop;
  if (text == "delay") return FaultRule::Action::delay;
  if (text == "duplicate") return FaultRule::Action::duplicate;
  if (text == "corrupt") return FaultRule::Action::corrupt;
  return c.error(CoreErrc::config_bad_value,
                 fmt::format("unknown action '{}'; expected drop, delay, duplicate or corrupt", text));
}

Result<Filter::Format> parse_format(const ConfigNode& node) {
  if (!node.has("format")) return Filter::Format::any;
  AXON_TRY(c, node.child("format"));
  AXON_TRY(text, c.as<std::string>());
  if (text == "any") return Filter::Format::any;
  if (text == "standard") return Filter::Format::standard;
  if (text == "extended") return Filter::Format::extended;
  return c.error(CoreErrc::config_bad_value, fmt::format("unknown format '{}'; expected any, standard or extended", text));
}

// An optional count or seed (0 or more). Read as a signed number so that a negative value gets a
// clear message.
Result<std::uint64_t> non_negative(const ConfigNode& node, std::string_view key, std::uint64_t fallback) {
  if (!node.has(key)) return fallback;
  AXON_TRY(c, node.child(key));
  AXON_TRY(v, c.as<std::int64_t>());
  if (v < 0) return c.error(CoreErrc::config_bad_value, fmt::format("expected 0 or more, got {}", v));
  return static_cast<std::uint64_t>(v);
}

// A key that only makes sense with one action.
Result<void> only_with(const ConfigNode& node, std::string_view key, FaultRule::Action have, FaultRule::Action need,
                       std::string_view need_name) {
  if (!node.has(key) || have == need) return ok();
  AXON_TRY(c, node.child(key));
  return c.error(CoreErrc::config_bad_value, fmt::format("only allowed with action: {}", need_name));
}

Result<FaultRule> parse_rule(const ConfigNode& node) {
  if (!node.is_map()) return node.error(CoreErrc::config_bad_value, "expected a rule (a map with at least 'action')");
  AXON_TRY(node.reject_unknown({"action", "id", "mask", "format", "skip", "count", "probability", "delay_ms", "xor"}));
  FaultRule r;
  AXON_TRY(action, parse_action(node));
  r.action = action;

  if (node.has("id")) {
    AXON_TRY(id, node.get_in<std::uint32_t>("id", 0, Frame::kMaxExtendedId));
    r.match.id = id;
    r.match.mask = Frame::kMaxExtendedId;  // an id alone matches exactly that id
  }
  if (node.has("mask")) {
    AXON_TRY(mask, node.get_in<std::uint32_t>("mask", 0, Frame::kMaxExtendedId));
    r.match.mask = mask;
  }
  AXON_TRY(format, parse_format(node));
  r.match.format = format;

  AXON_TRY(skip, non_negative(node, "skip", 0));
  r.skip = skip;
  if (node.has("count")) {
    AXON_TRY(count, non_negative(node, "count", 0));
    if (count == 0) {
      AXON_TRY(c, node.child("count"));
      return c.error(CoreErrc::config_bad_value, "expected 1 or more (a rule with count 0 never fires)");
    }
    r.count = count;
  }
  if (node.has("probability")) {
    AXON_TRY(p, node.get_in<double>("probability", 0.0, 1.0));
    r.probability = p;
  }

  AXON_TRY(only_with(node, "delay_ms", r.action, FaultRule::Action::delay, "delay"));
  AXON_TRY(only_with(node, "xor", r.action, FaultRule::Action::corrupt, "corrupt"));
  if (r.action == FaultRule::Action::delay) {
    AXON_TRY(c, node.child("delay_ms"));
    AXON_TRY(ms, c.as<double>());
    if (!(ms > 0.0) || ms > kMaxDelayMs)
      return c.error(CoreErrc::config_bad_value, fmt::format("expected a delay above 0 and at most {} ms, got {}", kMaxDelayMs, ms));
    r.delay = core::Duration(std::llround(ms * 1e6));
  }
  if (r.action == FaultRule::Action::corrupt && node.has("xor")) {
    AXON_TRY(x, node.get_in<std::uint32_t>("xor", 1, 0xFF));  // 0 would flip nothing
    r.corrupt_xor = static_cast<std::uint8_t>(x);
  }
  return r;
}

}  // namespace

Result<FaultPlan> FaultPlan::from_config(const ConfigNode& node) {
  if (!node.is_map()) return node.error(CoreErrc::config_bad_value, "expected a fault plan (a map with 'seed' and 'rules')");
  AXON_TRY(node.reject_unknown({"seed", "rules"}));
  FaultPlan plan;
  AXON_TRY(seed, non_negative(node, "seed", 1));
  plan.seed = seed;
  if (!node.has("rules")) return plan;
  AXON_TRY(rules, node.child("rules"));
  AXON_TRY(items, rules.items());
  plan.rules.reserve(items.size());
  for (const auto& item : items) {
    AXON_TRY(rule, parse_rule(item));
    plan.rules.push_back(rule);
  }
  return plan;
}

FaultInjector::FaultInjector(FaultPlan plan)
    : plan_(std::move(plan)), seen_(plan_.rules.size(), 0), rng_(plan_.seed) {}

FaultInjector::Decision FaultInjector::apply(const Frame& frame) {
  Decision d;
  d.frame = frame;
  for (std::size_t i = 0; i < plan_.rules.size(); ++i) {
    const FaultRule& r = plan_.rules[i];
    if (!r.match.matches(frame)) continue;
    // Nothing to corrupt in a remote or empty frame: such frames are not this rule's business.
    if (r.action == FaultRule::Action::corrupt && frame.payload().empty()) continue;
    const std::uint64_t n = seen_[i]++;
    if (n < r.skip || n - r.skip >= r.count) continue;
    if (r.probability < 1.0) {
      // 53 random bits make a uniform double in [0, 1); done by hand so that the sequence is
      // the same with every standard library.
      const double u = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
      if (!(u < r.probability)) continue;
    }
    switch (r.action) {
      case FaultRule::Action::drop: d.drop = true; break;
      case FaultRule::Action::delay: d.delay = r.delay; break;
      case FaultRule::Action::duplicate: d.duplicate = true; break;
      case FaultRule::Action::corrupt: {
        const auto in = frame.payload();
        std::array<std::uint8_t, Frame::kMaxData> bytes{};
        for (std::size_t k = 0; k < in.size(); ++k) bytes[k] = static_cast<std::uint8_t>(in[k] ^ r.corrupt_xor);
        d.frame = Frame::data(frame.id(), frame.format(), std::span(bytes.data(), in.size())).value();
        d.frame.set_timestamp(frame.timestamp());
        d.corrupted = true;
        break;
      }
    }
    return d;
  }
  return d;
}

}  // namespace axon::can
