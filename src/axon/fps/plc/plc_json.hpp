// The PLC's state as JSON: what `axon fps plc status --json` prints and what the fps actor's `plc`
// keyword carries (docs/schema/fps.json).
#pragma once

#include "axon/fps/plc/client.hpp"

#include <nlohmann/json.hpp>

namespace axon::fps::plc {

// {name, value (null: a sensor fault), unit}
nlohmann::json to_json(const SensorReading& reading);
// {positioner_power: [6 bools, sextant 1 first], gateway_power: [...], sync_line, temperatures: [...],
//  humidity, pressure, coolant_flow}
nlohmann::json to_json(const PlcStatus& status);

}  // namespace axon::fps::plc
