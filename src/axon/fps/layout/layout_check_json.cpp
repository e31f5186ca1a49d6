#include "axon/fps/layout/layout_check_json.hpp"

#include <string_view>

namespace axon::fps {

nlohmann::json to_json(const LayoutCheck& c) {
  using json = nlohmann::json;
  auto buses = [](const std::vector<BusRef>& v) {
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

}  // namespace axon::fps
