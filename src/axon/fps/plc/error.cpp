#include "axon/fps/plc/error.hpp"

#include <string>

namespace axon::fps::plc {
namespace {
class PlcCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.fps.plc"; }
  std::string message(int c) const override {
    switch (static_cast<PlcErrc>(c)) {
      case PlcErrc::connect_failed: return "cannot connect to the PLC; check its address, port and the network";
      case PlcErrc::timeout: return "the PLC did not answer in time";
      case PlcErrc::io: return "the Modbus connection to the PLC failed";
      case PlcErrc::bad_address:
        return "the PLC refused the register address; check the register map (docs/fps-plc.md) against the PLC program";
      case PlcErrc::device_exception: return "the PLC answered with a Modbus exception";
      case PlcErrc::invalid_argument: return "invalid argument";
      case PlcErrc::bad_map: return "inconsistent PLC register map";
      case PlcErrc::server_failed: return "the PLC emulator could not start";
    }
    return "unknown PLC error";
  }
  // A bad option or input from the caller compares equal to std::errc::invalid_argument (the CLI's
  // exit code 2; core/error.cpp).
  std::error_condition default_error_condition(int c) const noexcept override {
    if (static_cast<PlcErrc>(c) == PlcErrc::invalid_argument) return std::errc::invalid_argument;
    return {c, *this};
  }
};
}  // namespace

const std::error_category& plc_category() noexcept {
  static const PlcCategory c;
  return c;
}

}  // namespace axon::fps::plc
