#include "axon/fps/plc/sensor_script.hpp"

#include <algorithm>

namespace axon::fps::plc {

SensorScript::SensorScript(std::vector<ScriptPoint> points) {
  for (auto& p : points) by_sensor_[p.sensor].emplace_back(p.t_s, p.value);
  for (auto& [name, pts] : by_sensor_)
    std::stable_sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
}

Result<SensorScript> SensorScript::from_config(const core::ConfigNode& node) {
  AXON_TRY(items, node.items());
  std::vector<ScriptPoint> points;
  for (const auto& item : items) {
    AXON_TRY(item.reject_unknown({"t", "sensor", "value"}));
    AXON_TRY(t, item.get<double>("t"));
    if (t < 0) return item.error(CoreErrc::config_bad_value, "t must not be negative");
    AXON_TRY(sensor, item.get<std::string>("sensor"));
    AXON_TRY(value, item.get<double>("value"));
    points.push_back(ScriptPoint{t, sensor, value});
  }
  return SensorScript(std::move(points));
}

std::vector<std::string> SensorScript::sensors() const {
  std::vector<std::string> out;
  for (const auto& [name, pts] : by_sensor_) out.push_back(name);
  return out;
}

std::map<std::string, double> SensorScript::values_at(double t) const {
  std::map<std::string, double> out;
  for (const auto& [name, pts] : by_sensor_) {
    if (pts.empty() || t < pts.front().first) continue;
    auto next = std::upper_bound(pts.begin(), pts.end(), t, [](double v, const auto& p) { return v < p.first; });
    if (next == pts.end()) {
      out[name] = pts.back().second;
      continue;
    }
    const auto& b = *next;
    const auto& a = *(next - 1);
    const double f = b.first > a.first ? (t - a.first) / (b.first - a.first) : 1.0;
    out[name] = a.second + f * (b.second - a.second);
  }
  return out;
}

}  // namespace axon::fps::plc
