// The simulated controller's events as the against-the-simulator tests read them.
#pragma once

#include "axon/c4g/sim/controller.hpp"

#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

namespace axon::c4g::test {

// Whether an event named `name` has `text` in its text.
[[nodiscard]] inline bool has_event(const std::vector<sim::Event>& events, std::string_view name, std::string_view text = {}) {
  return std::any_of(events.begin(), events.end(),
                     [&](const sim::Event& e) { return e.name == name && e.text.find(text) != std::string::npos; });
}

// One line per event, for a failing test's message.
[[nodiscard]] inline std::string event_log(const std::vector<sim::Event>& events) {
  std::string out;
  for (const auto& e : events) out += e.name + ": " + e.text + "\n";
  return out;
}

}  // namespace axon::c4g::test
