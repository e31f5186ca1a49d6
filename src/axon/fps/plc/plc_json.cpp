#include "axon/fps/plc/plc_json.hpp"

namespace axon::fps::plc {

nlohmann::json to_json(const SensorReading& r) {
  return {{"name", r.name}, {"value", r.value ? nlohmann::json(*r.value) : nlohmann::json(nullptr)}, {"unit", r.unit}};
}

nlohmann::json to_json(const PlcStatus& s) {
  nlohmann::json j{{"positioner_power", s.positioner_power}, {"gateway_power", s.gateway_power}, {"sync_line", s.sync_line}};
  j["temperatures"] = nlohmann::json::array();
  for (const auto& t : s.temperatures) j["temperatures"].push_back(to_json(t));
  j["humidity"] = to_json(s.humidity);
  j["pressure"] = to_json(s.pressure);
  j["coolant_flow"] = to_json(s.coolant_flow);
  return j;
}

}  // namespace axon::fps::plc
