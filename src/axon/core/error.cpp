#include "axon/core/error.hpp"

namespace axon {

std::string Error::message() const {
  std::string m = code ? code.message() : std::string("no error");
  if (detail.empty()) return m;
  std::string out;
  out.reserve(detail.size() + 2 + m.size());
  out.append(detail).append(": ").append(m);
  return out;
}

namespace {
class CoreCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.core"; }
  std::string message(int c) const override {
    switch (static_cast<CoreErrc>(c)) {
      case CoreErrc::invalid_argument: return "invalid argument; check the value against the command's help";
      case CoreErrc::config_syntax: return "configuration file is not valid YAML; fix the syntax at the position shown";
      case CoreErrc::config_missing_key: return "required configuration key is missing; add it";
      case CoreErrc::config_bad_value: return "configuration value has the wrong type or is out of range";
      case CoreErrc::config_unknown_key: return "unknown configuration key; check its spelling against the docs";
      case CoreErrc::io: return "input/output error; check the file or device path and permissions";
      case CoreErrc::timeout: return "timed out; check that the peer is powered, connected and addressed correctly";
      case CoreErrc::cancelled: return "operation cancelled";
      case CoreErrc::closed: return "closed; reopen the connection or device";
      case CoreErrc::not_supported: return "not supported on this system";
      case CoreErrc::permission: return "permission denied; run with the needed privileges or capabilities";
    }
    return "unknown core error";
  }
  // Bad input from the user (values, configuration files) compares equal to
  // std::errc::invalid_argument, so a surface (the CLI's exit code 2) tells it from a failed device.
  std::error_condition default_error_condition(int c) const noexcept override {
    switch (static_cast<CoreErrc>(c)) {
      case CoreErrc::invalid_argument:
      case CoreErrc::config_syntax:
      case CoreErrc::config_missing_key:
      case CoreErrc::config_bad_value:
      case CoreErrc::config_unknown_key: return std::errc::invalid_argument;
      default: return {c, *this};
    }
  }
};
}  // namespace

const std::error_category& core_category() noexcept {
  static const CoreCategory c;
  return c;
}

}  // namespace axon
