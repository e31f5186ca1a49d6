#include "axon/c4g/sim/scenario.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/packet.hpp"

#include <fmt/format.h>

namespace axon::c4g::sim {
namespace {

constexpr std::string_view kDefaultYaml = R"(# Default scenario: drive on, mode 0, a move out and back, then keep running.
steps:
  - drive_on
  - go_open: {type: A, mode: 0, arms: [1]}
  - move: {arm: 1, deg: [10, -5, 5, 20, 10, 30], duration: 1.5}
  - move: {arm: 1, deg: [0, 0, 0, 0, 0, 0], duration: 1.5}
  - run
)";

std::string where(const core::ConfigNode& n) { return fmt::format("{}:{}:{}", n.file(), n.line(), n.column()); }

Result<std::vector<int>> arms_of(const core::ConfigNode& n) {
  std::vector<int> arms;
  if (!n.has("arms")) return arms;
  AXON_TRY(list, n.child("arms"));
  AXON_TRY(items, list.items());
  for (const auto& it : items) {
    AXON_TRY(a, it.as<int>());
    if (a < 1 || a > static_cast<int>(protocol::kMaxArms)) return it.error(CoreErrc::config_bad_value, "an arm is 1..4");
    arms.push_back(a);
  }
  return arms;
}

Result<double> positive_seconds(const core::ConfigNode& n) {
  AXON_TRY(s, n.as<double>());
  if (!(s >= 0) || s > 1e6) return n.error(CoreErrc::config_bad_value, "expected seconds >= 0");
  return s;
}

// Modes a program may open: the ones the simulator applies.
bool openable(std::int32_t m) {
  switch (m) {
    case 0: case 10: case 1: case 2: case 4: case 5: case 7: case 8: case 9: return true;
    case 12: return true;  // 2': the program ends mode 2 itself
    default: return m > 100 && m < 200;
  }
}

Result<Step> parse_step(const core::ConfigNode& item) {
  Step s;
  s.where = where(item);
  std::string key;
  std::optional<core::ConfigNode> args;
  if (item.is_map()) {
    const auto keys = item.keys();
    if (keys.size() != 1) return item.error(CoreErrc::config_bad_value, "a step is one key (e.g. 'delay: 1')");
    key = keys[0];
    AXON_TRY(c, item.child(key));
    args = c;
  } else {
    AXON_TRY(k, item.as<std::string>());
    key = k;
  }
  auto need_map = [&](std::initializer_list<std::string_view> known) -> Result<void> {
    if (!args) return item.error(CoreErrc::config_bad_value, fmt::format("'{}' needs its arguments", key));
    if (!args->is_map()) return args->error(CoreErrc::config_bad_value, "expected a map of arguments");
    return args->reject_unknown(known);
  };
  auto optional_map = [&](std::initializer_list<std::string_view> known) -> Result<void> {
    if (!args) return ok();
    return need_map(known);
  };
  if (key == "drive_on" || key == "drive_off") {
    s.kind = key == "drive_on" ? StepKind::drive_on : StepKind::drive_off;
    if (auto r = optional_map({"arms"}); !r) return r.error();
    if (args) { AXON_TRY(a, arms_of(*args)); s.arms = a; }
  } else if (key == "wait_for_pc") {
    s.kind = StepKind::wait_for_pc;
    if (auto r = optional_map({"arms", "timeout"}); !r) return r.error();
    if (args) {
      AXON_TRY(a, arms_of(*args));
      s.arms = a;
      if (args->has("timeout")) { AXON_TRY(t, args->child("timeout")); AXON_TRY(v, positive_seconds(t)); s.seconds = v; }
    }
  } else if (key == "go_open") {
    s.kind = StepKind::go_open;
    if (auto r = need_map({"type", "mode", "arms"}); !r) return r.error();
    AXON_TRY(type, args->get_or<std::string>("type", "A"));
    if (type == "A" || type == "a") s.type = OpenType::a;
    else if (type == "B" || type == "b") s.type = OpenType::b;
    else { AXON_TRY(t, args->child("type")); return t.error(CoreErrc::config_bad_value, "type is A or B"); }
    AXON_TRY(mnode, args->child("mode"));
    AXON_TRY(mtext, mnode.as<std::string>());
    const auto m = protocol::parse_mode(mtext);
    if (!m) return mnode.error(CoreErrc::config_bad_value, fmt::format("unknown mode '{}'", mtext));
    if (!openable(*m))
      return mnode.error(CoreErrc::config_bad_value,
                         fmt::format("mode {} ({}) cannot be opened by a program in the simulator (modes: 0, 0', 1, 2, 4, 5, "
                                     "7, 8, 9, 1xx, and 2' to leave mode 2; the special modes have their own steps or come from the PC)",
                                     mtext, protocol::mode_name(*m)));
    s.mode = *m;
    AXON_TRY(a, arms_of(*args));
    s.arms = a;
  } else if (key == "move") {
    s.kind = StepKind::move;
    if (auto r = need_map({"arm", "deg", "duration"}); !r) return r.error();
    AXON_TRY(arm, args->get_or<int>("arm", 1));
    if (arm < 1 || arm > 4) { AXON_TRY(n, args->child("arm")); return n.error(CoreErrc::config_bad_value, "an arm is 1..4"); }
    s.arm = arm;
    AXON_TRY(dnode, args->child("deg"));
    AXON_TRY(items, dnode.items());
    if (items.empty() || items.size() > protocol::kAxesPerArm)
      return dnode.error(CoreErrc::config_bad_value, "expected 1..10 joint targets [deg] (null keeps an axis)");
    for (const auto& it : items) {
      if (it.is_map() || it.is_sequence()) return it.error(CoreErrc::config_bad_value, "expected a joint target [deg] or null");
      auto v = it.as<double>();
      if (!v) {
        auto text = it.as<std::string>();  // a YAML null is not a scalar: it fails here too
        if (text && text.value() != "~" && text.value() != "null") return v.error();
        s.deg.emplace_back();
        continue;
      }
      if (!(v.value() > -1e5 && v.value() < 1e5)) return it.error(CoreErrc::config_bad_value, "a joint target must be finite");
      s.deg.emplace_back(v.value());
    }
    AXON_TRY(dur, args->child("duration"));
    AXON_TRY(d, positive_seconds(dur));
    if (d <= 0) return dur.error(CoreErrc::config_bad_value, "a move needs a duration > 0");
    s.seconds = d;
  } else if (key == "delay" || key == "freeze_passive") {
    s.kind = key == "delay" ? StepKind::delay : StepKind::freeze_passive;
    if (!args) return item.error(CoreErrc::config_bad_value, fmt::format("'{}' needs seconds", key));
    AXON_TRY(v, positive_seconds(*args));
    s.seconds = v;
  } else if (key == "cmd") {
    s.kind = StepKind::cmd;
    if (auto r = need_map({"arm", "value"}); !r) return r.error();
    AXON_TRY(arm, args->get_in<int>("arm", 1, 4));
    AXON_TRY(value, args->get_in<int>("value", 0, 255));
    s.arm = arm;
    s.value = value;
  } else if (key == "selector") {
    s.kind = StepKind::selector;
    if (!args) return item.error(CoreErrc::config_bad_value, "'selector' needs auto or prog");
    AXON_TRY(v, args->as<std::string>());
    if (v != "auto" && v != "prog") return args->error(CoreErrc::config_bad_value, "the state selector is auto or prog");
    s.value = v == "prog" ? 1 : 0;
  } else if (key == "override") {
    s.kind = StepKind::general_override;
    if (!args) return item.error(CoreErrc::config_bad_value, "'override' needs a percentage");
    AXON_TRY(v, args->as<int>());
    if (v < 1 || v > 100) return args->error(CoreErrc::config_bad_value, "the general override is 1..100 %");
    s.value = v;
  } else if (key == "restart" || key == "exit_open" || key == "run") {
    s.kind = key == "restart" ? StepKind::restart : key == "exit_open" ? StepKind::exit_open : StepKind::run;
    if (args) return args->error(CoreErrc::config_bad_value, fmt::format("'{}' takes no arguments", key));
  } else {
    return item.error(CoreErrc::config_unknown_key,
                      fmt::format("unknown step '{}' (drive_on, drive_off, go_open, wait_for_pc, move, delay, cmd, "
                                  "freeze_passive, restart, exit_open, selector, override, run)",
                                  key));
  }
  return s;
}

}  // namespace

std::string_view to_string(StepKind k) noexcept {
  switch (k) {
    case StepKind::drive_on: return "drive_on";
    case StepKind::drive_off: return "drive_off";
    case StepKind::go_open: return "go_open";
    case StepKind::wait_for_pc: return "wait_for_pc";
    case StepKind::move: return "move";
    case StepKind::delay: return "delay";
    case StepKind::cmd: return "cmd";
    case StepKind::freeze_passive: return "freeze_passive";
    case StepKind::restart: return "restart";
    case StepKind::exit_open: return "exit_open";
    case StepKind::run: return "run";
    case StepKind::selector: return "selector";
    case StepKind::general_override: return "override";
  }
  return "?";
}

Result<Scenario> Scenario::from_config(const core::ConfigNode& root) {
  if (!root.is_map()) return root.error(CoreErrc::config_bad_value, "expected a map with 'steps'");
  AXON_TRY(root.reject_unknown({"name", "steps"}));
  Scenario sc;
  AXON_TRY(name, root.get_or<std::string>("name", root.file()));
  sc.name = name;
  AXON_TRY(steps, root.child("steps"));
  AXON_TRY(items, steps.items());
  for (std::size_t i = 0; i < items.size(); ++i) {
    AXON_TRY(s, parse_step(items[i]));
    if ((s.kind == StepKind::exit_open || s.kind == StepKind::run) && i + 1 != items.size())
      return items[i].error(CoreErrc::config_bad_value, fmt::format("'{}' must be the last step", to_string(s.kind)));
    sc.steps.push_back(std::move(s));
  }
  return sc;
}

Result<Scenario> Scenario::load_file(const std::string& path) {
  AXON_TRY(root, core::ConfigNode::load_file(path));
  return from_config(root);
}

Result<Scenario> Scenario::parse(std::string_view yaml, std::string name) {
  AXON_TRY(root, core::ConfigNode::load_string(yaml, std::move(name)));
  return from_config(root);
}

std::string_view Scenario::default_yaml() noexcept { return kDefaultYaml; }

Scenario Scenario::default_scenario() {
  auto s = parse(kDefaultYaml, "<default scenario>");
  return std::move(s).value();
}

}  // namespace axon::c4g::sim
