// Configuration files: YAML read into typed values with validation.
//
// A ConfigNode wraps one node of a parsed file and remembers where it came from, so every error
// names the file, the line and column, the key path (e.g. "buses[2].bitrate") and what was
// expected. Family code maps nodes to its own structs with get<T>() / get_or<T>() and checks
// ranges with get_in(); reject_unknown() catches misspelt keys.
#pragma once

#include "axon/core/error.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace axon::core {

class ConfigNode {
 public:
  static Result<ConfigNode> load_file(const std::string& path);
  static Result<ConfigNode> load_string(std::string_view text, std::string name = "<config>");

  [[nodiscard]] bool has(std::string_view key) const;
  [[nodiscard]] bool is_map() const { return node_.IsMap(); }
  [[nodiscard]] bool is_sequence() const { return node_.IsSequence(); }
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] const std::string& file() const { return *file_; }
  [[nodiscard]] int line() const { return node_.Mark().line + 1; }
  [[nodiscard]] int column() const { return node_.Mark().column + 1; }

  // A required sub-node (map or sequence).
  [[nodiscard]] Result<ConfigNode> child(std::string_view key) const;
  // The elements of a sequence node; an error if this node is not a sequence.
  [[nodiscard]] Result<std::vector<ConfigNode>> items() const;
  // The keys of a map node, in file order.
  [[nodiscard]] std::vector<std::string> keys() const;

  // This node's own scalar value. T: bool, integral types, double, std::string.
  template <class T>
  [[nodiscard]] Result<T> as() const;
  // A required key's value.
  template <class T>
  [[nodiscard]] Result<T> get(std::string_view key) const {
    AXON_TRY(c, child(key));
    return c.template as<T>();
  }
  // An optional key's value, or the fallback when the key is absent (present but wrong: error).
  template <class T>
  [[nodiscard]] Result<T> get_or(std::string_view key, T fallback) const {
    if (!has(key)) return fallback;
    return get<T>(key);
  }
  // A required numeric key within [lo, hi].
  template <class T>
  [[nodiscard]] Result<T> get_in(std::string_view key, T lo, T hi) const {
    AXON_TRY(c, child(key));
    AXON_TRY(v, c.template as<T>());
    if (v < lo || v > hi) return c.error(CoreErrc::config_bad_value, range_text(lo, hi, c.scalar()));
    return v;
  }
  // An error if the map has keys outside `known` (typos must not be ignored silently).
  [[nodiscard]] Result<void> reject_unknown(std::initializer_list<std::string_view> known) const;

  // An error located at this node: "FILE:LINE:COL: key 'PATH': WHAT".
  [[nodiscard]] Error error(CoreErrc code, std::string_view what) const;

 private:
  ConfigNode(YAML::Node node, std::shared_ptr<const std::string> file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}
  [[nodiscard]] std::string scalar() const;
  [[nodiscard]] Result<std::int64_t> as_int64() const;
  [[nodiscard]] Result<double> as_double() const;
  template <class T>
  static std::string range_text(T lo, T hi, const std::string& got) {
    return fmt::format("expected a value within {}..{}, got '{}'", lo, hi, got);
  }

  YAML::Node node_;
  std::shared_ptr<const std::string> file_;
  std::string path_;
};

template <class T>
Result<T> ConfigNode::as() const {
  if constexpr (std::is_same_v<T, std::string>) {
    if (!node_.IsScalar()) return error(CoreErrc::config_bad_value, "expected a string");
    return node_.Scalar();
  } else if constexpr (std::is_same_v<T, bool>) {
    const std::string s = scalar();
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
    return error(CoreErrc::config_bad_value, "expected true or false, got '" + s + "'");
  } else if constexpr (std::is_integral_v<T>) {
    AXON_TRY(v, as_int64());
    if (v < static_cast<std::int64_t>(std::numeric_limits<T>::min()) ||
        (v > 0 && static_cast<std::uint64_t>(v) > static_cast<std::uint64_t>(std::numeric_limits<T>::max())))
      return error(CoreErrc::config_bad_value, range_text(std::numeric_limits<T>::min(), std::numeric_limits<T>::max(), scalar()));
    return static_cast<T>(v);
  } else if constexpr (std::is_floating_point_v<T>) {
    AXON_TRY(v, as_double());
    return static_cast<T>(v);
  } else {
    static_assert(sizeof(T) == 0, "ConfigNode::as<T>: unsupported type");
  }
}

// `text` as a YAML double-quoted scalar (quotes, backslashes, control and non-ASCII characters
// escaped), for writers of configuration files: whatever a string holds, the file reads back the
// same string.
[[nodiscard]] std::string yaml_quoted(std::string_view text);

}  // namespace axon::core
