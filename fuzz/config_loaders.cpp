// Fuzzes the YAML configuration loaders of the simulators, the PLC and the CAN fault injector:
// the first byte picks the loader, the rest is the file's text. A loader must give a value or an
// error with a message; nothing may crash or throw.
#include "axon/blmc/sim/adc_signal.hpp"
#include "axon/blmc/sim/board_config.hpp"
#include "axon/blmc/sim/fault_plan.hpp"
#include "axon/blmc/sim/motor_config.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/can/fault_plan.hpp"
#include "axon/core/config.hpp"
#include "axon/fps/plc/cold_policy.hpp"
#include "axon/fps/plc/register_map.hpp"
#include "axon/fps/plc/sensor_script.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"
#include "axon/fps/sim/positioner_config.hpp"
#include "axon/fps/sim/simulator_config.hpp"

#include <cstddef>
#include <cstdint>
#include <string_view>

using namespace axon;

namespace {

template <class R>
void check(const R& r) {
  if (!r && r.error().detail.empty()) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  auto root = core::ConfigNode::load_string(text, "<fuzz>");
  check(root);
  if (!root) return 0;
  const core::ConfigNode& n = root.value();
  switch (data[0] % 12) {
    case 0: check(fps::sim::SimulatorConfig::from_config(n)); break;
    case 1: check(fps::sim::PositionerConfig::from_config(n)); break;
    case 2: check(fps::sim::Scenario::from_config(n)); break;
    case 3: check(fps::plc::RegisterMap::from_config(n)); break;
    case 4: check(fps::plc::SensorScript::from_config(n)); break;
    case 5: check(fps::plc::ColdPolicyConfig::from_config(n)); break;
    case 6: check(can::FaultPlan::from_config(n)); break;
    case 7: check(blmc::sim::BoardConfig::from_config(n)); break;
    case 8: check(blmc::sim::MotorConfig::from_config(n)); break;
    case 9: check(blmc::sim::BoardFaultPlan::from_config(n)); break;
    case 10: check(blmc::sim::AdcSignal::from_config(n)); break;
    default: check(c4g::sim::Scenario::from_config(n)); break;
  }
  return 0;
}
