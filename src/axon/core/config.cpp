#include "axon/core/config.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace axon::core {

namespace {
// yaml-cpp keeps both entries of a key given twice in one map and answers lookups with the first:
// a second value the user meant would be ignored without a word. Refused with both lines instead.
Result<void> reject_duplicate_keys(const YAML::Node& node, const std::string& file) {
  if (node.IsSequence()) {
    for (const auto& item : node) {
      AXON_TRY(reject_duplicate_keys(item, file));
    }
  } else if (node.IsMap()) {
    for (auto a = node.begin(); a != node.end(); ++a) {
      if (a->first.IsScalar()) {
        auto b = a;
        for (++b; b != node.end(); ++b) {
          if (!b->first.IsScalar() || b->first.Scalar() != a->first.Scalar()) continue;
          const auto first = a->first.Mark(), again = b->first.Mark();
          return Error(CoreErrc::config_syntax,
                       fmt::format("{}:{}:{}: key '{}' given twice (first at line {}); remove one", file,
                                   again.line + 1, again.column + 1, a->first.Scalar(), first.line + 1));
        }
      }
      AXON_TRY(reject_duplicate_keys(a->second, file));
    }
  }
  return ok();
}
}  // namespace

Result<ConfigNode> ConfigNode::load_string(std::string_view text, std::string name) {
  auto file = std::make_shared<const std::string>(std::move(name));
  try {
    YAML::Node root = YAML::Load(std::string(text));
    if (!root.IsDefined() || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    AXON_TRY(reject_duplicate_keys(root, *file));
    return ConfigNode(root, file, "");
  } catch (const YAML::Exception& e) {
    return Error(CoreErrc::config_syntax,
                 fmt::format("{}:{}:{}: {}", *file, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
}

Result<ConfigNode> ConfigNode::load_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error(CoreErrc::io, fmt::format("cannot open configuration file '{}'", path));
  std::ostringstream ss;
  ss << in.rdbuf();
  return load_string(ss.str(), path);
}

bool ConfigNode::has(std::string_view key) const {
  return node_.IsMap() && node_[std::string(key)].IsDefined() && !node_[std::string(key)].IsNull();
}

Result<ConfigNode> ConfigNode::child(std::string_view key) const {
  std::string sub = path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  if (!node_.IsMap()) return error(CoreErrc::config_bad_value, fmt::format("expected a map containing '{}'", key));
  YAML::Node c = node_[std::string(key)];
  if (!c.IsDefined() || c.IsNull()) {
    return Error(CoreErrc::config_missing_key,
                 fmt::format("{}:{}:{}: key '{}': required but missing", *file_, line(), column(), sub));
  }
  return ConfigNode(c, file_, std::move(sub));
}

Result<std::vector<ConfigNode>> ConfigNode::items() const {
  if (!node_.IsSequence()) return error(CoreErrc::config_bad_value, "expected a list");
  std::vector<ConfigNode> out;
  out.reserve(node_.size());
  for (std::size_t i = 0; i < node_.size(); ++i) out.push_back(ConfigNode(node_[i], file_, fmt::format("{}[{}]", path_, i)));
  return out;
}

namespace {

// The text of a map key: a plain key as written, any other (a map or a list used as a key, a null)
// in YAML flow form, so that it is reported as an unknown key rather than thrown at the reader.
std::string key_text(const YAML::Node& key) {
  if (key.IsScalar()) return key.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << key;
  return out.c_str();
}

}  // namespace

std::vector<std::string> ConfigNode::keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) out.push_back(key_text(kv.first));
  return out;
}

Result<void> ConfigNode::reject_unknown(std::initializer_list<std::string_view> known) const {
  if (!node_.IsMap()) return ok();
  for (const auto& kv : node_) {
    const std::string k = key_text(kv.first);
    bool found = false;
    for (auto kn : known) found = found || kn == k;
    if (!found) {
      std::string list;
      for (auto kn : known) list += (list.empty() ? "" : ", ") + std::string(kn);
      const auto m = kv.first.Mark();
      return Error(CoreErrc::config_unknown_key,
                   fmt::format("{}:{}:{}: key '{}{}': unknown; expected one of: {}", *file_, m.line + 1, m.column + 1,
                               path_.empty() ? "" : path_ + ".", k, list));
    }
  }
  return ok();
}

Error ConfigNode::error(CoreErrc code, std::string_view what) const {
  return Error(code, fmt::format("{}:{}:{}: key '{}': {}", *file_, line(), column(), path_.empty() ? "<root>" : path_, what));
}

std::string ConfigNode::scalar() const { return node_.IsScalar() ? node_.Scalar() : std::string("<not a scalar>"); }

Result<std::int64_t> ConfigNode::as_int64() const {
  const std::string s = scalar();
  std::string_view v = s;
  bool neg = false;
  if (!v.empty() && (v[0] == '-' || v[0] == '+')) {
    neg = v[0] == '-';
    v.remove_prefix(1);
  }
  int base = 10;
  if (v.size() > 2 && v[0] == '0' && (v[1] == 'x' || v[1] == 'X')) {
    base = 16;
    v.remove_prefix(2);
  }
  std::uint64_t u = 0;
  auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), u, base);
  if (v.empty() || ec != std::errc() || p != v.data() + v.size() ||
      u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
    return error(CoreErrc::config_bad_value, fmt::format("expected an integer (decimal or 0x hex), got '{}'", s));
  const auto i = static_cast<std::int64_t>(u);
  return neg ? -i : i;
}

Result<double> ConfigNode::as_double() const {
  const std::string s = scalar();
  double d = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || !std::isfinite(d))
    return error(CoreErrc::config_bad_value, fmt::format("expected a finite number, got '{}'", s));
  return d;
}

std::string yaml_quoted(std::string_view text) {
  YAML::Emitter out;
  out.SetOutputCharset(YAML::EscapeNonAscii);
  out << YAML::DoubleQuoted << std::string(text);
  return out.c_str();
}

}  // namespace axon::core
