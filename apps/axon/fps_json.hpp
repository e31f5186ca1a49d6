// JSON of fps results shared by several `axon fps` subcommands (fps_layout.cpp, fps_plane.cpp).
#pragma once

#include "axon/fps/layout/layout_check.hpp"

#include <nlohmann/json.hpp>

#include <string_view>
#include <vector>

namespace axon::app {

// {ok, matched, missing, offline_answered, offline_silent, not_checked, wrong_bus, unexpected,
// duplicated, failed_buses}
inline nlohmann::json layout_check_json(const fps::LayoutCheck& c) {
  using json = nlohmann::json;
  auto buses = [](const std::vector<fps::BusRef>& v) {
    json a = json::array();
    for (const auto& b : v) a.push_back(b.to_string());
    return a;
  };
  json j{{"ok", c.ok()},           {"matched", c.matched},   {"missing", c.missing},
         {"offline_answered", c.offline_answered}, {"offline_silent", c.offline_silent},
         {"not_checked", c.not_checked}};
  j["wrong_bus"] = json::array();
  for (const auto& w : c.wrong_bus)
    j["wrong_bus"].push_back(json{{"id", w.id}, {"expected", w.expected.to_string()}, {"found", buses(w.found)}});
  for (const char* key : {"unexpected", "duplicated"}) {
    j[key] = json::array();
    for (const auto& u : std::string_view(key) == "unexpected" ? c.unexpected : c.duplicated)
      j[key].push_back(json{{"id", u.id}, {"found", buses(u.found)}});
  }
  j["failed_buses"] = json::object();
  for (const auto& [b, why] : c.failed_buses) j["failed_buses"][b.to_string()] = why;
  return j;
}

}  // namespace axon::app
