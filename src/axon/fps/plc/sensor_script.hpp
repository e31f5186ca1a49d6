// Scripted sensor values for the PLC emulator: each sensor follows its own list of (time, value)
// points, linearly interpolated between them and held after the last one (e.g. a night cooling
// the focal plane from +5 to -15 degC). Before a sensor's first point its value is left alone.
//
// YAML (a list, in any order):
//   - {t: 0, sensor: fps_plate_centre, value: 5}
//   - {t: 600, sensor: fps_plate_centre, value: -15}
//   - {t: 0, sensor: humidity, value: 40}
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"

#include <map>
#include <string>
#include <vector>

namespace axon::fps::plc {

struct ScriptPoint {
  double t_s = 0;  // seconds since the emulator started
  std::string sensor;
  double value = 0;
};

class SensorScript {
 public:
  SensorScript() = default;
  explicit SensorScript(std::vector<ScriptPoint> points);
  static Result<SensorScript> from_config(const core::ConfigNode& node);

  [[nodiscard]] bool empty() const noexcept { return by_sensor_.empty(); }
  [[nodiscard]] std::vector<std::string> sensors() const;
  // The scripted value of every sensor that has one at time t.
  [[nodiscard]] std::map<std::string, double> values_at(double t_s) const;

 private:
  std::map<std::string, std::vector<std::pair<double, double>>> by_sensor_;  // sorted by time
};

}  // namespace axon::fps::plc
