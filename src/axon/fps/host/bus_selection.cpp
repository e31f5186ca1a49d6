#include "axon/fps/host/bus_selection.hpp"

#include "axon/can/cannet_client.hpp"
#include "axon/can/open.hpp"
#include "axon/core/config.hpp"
#include "axon/net/endpoint.hpp"

#include <fmt/format.h>

#include <functional>
#include <map>
#include <string_view>

namespace axon::fps::host {
namespace {

// A list in the file where each entry may appear once.
template <class T>
Result<std::vector<T>> distinct_items(const core::ConfigNode& root, const char* key,
                                      const std::function<Result<void>(const core::ConfigNode&, const T&)>& check) {
  AXON_TRY(node, root.child(key));
  AXON_TRY(items, node.items());
  std::vector<T> out;
  std::map<T, int> line_of;
  for (const auto& item : items) {
    AXON_TRY(v, item.template as<T>());
    AXON_TRY(check(item, v));
    if (auto [it, fresh] = line_of.emplace(v, item.line()); !fresh) {
      const auto what = [&] {
        if constexpr (std::is_same_v<T, int>) return fmt::format("channel {}", v);
        else return fmt::format("'{}'", v);
      }();
      return item.error(CoreErrc::config_bad_value, fmt::format("{} listed twice (first at line {})", what, it->second));
    }
    out.push_back(v);
  }
  return out;
}

}  // namespace

Result<void> BusSelection::apply_file(const std::string& path) {
  AXON_TRY(root, core::ConfigNode::load_file(path));
  if (!root.is_map()) return root.error(CoreErrc::config_bad_value, "expected a map of bus options");
  AXON_TRY(root.reject_unknown({"gateway", "channels", "socketcand", "channel", "buses", "timeout_ms"}));
  if (root.has("gateway")) {
    AXON_TRY(v, root.get<std::string>("gateway"));
    if (gateway.empty()) gateway = v;
  }
  if (root.has("socketcand")) {
    AXON_TRY(v, root.get<std::string>("socketcand"));
    if (socketcand.empty()) socketcand = v;
  }
  if (root.has("channels")) {
    AXON_TRY(v, distinct_items<int>(root, "channels", [](const core::ConfigNode& item, const int& c) -> Result<void> {
      if (c < 1 || c > 4) return item.error(CoreErrc::config_bad_value, "a gateway channel is 1..4");
      return ok();
    }));
    if (channels.empty()) channels = v;
  }
  const auto any = [](const core::ConfigNode&, const std::string&) -> Result<void> { return ok(); };
  if (root.has("channel")) {
    AXON_TRY(v, distinct_items<std::string>(root, "channel", any));
    if (scd_channels.empty()) scd_channels = v;
  }
  if (root.has("buses")) {
    AXON_TRY(v, distinct_items<std::string>(root, "buses", any));
    if (buses.empty()) buses = v;
  }
  if (root.has("timeout_ms")) {
    AXON_TRY(ms, root.get_in<int>("timeout_ms", 1, 600000));
    if (timeout_s < 0) timeout_s = ms / 1000.0;
  }
  return ok();
}

void BusSelection::apply_defaults() {
  if (channels.empty()) channels = {1};
  if (scd_channels.empty()) scd_channels = {"can0"};
  if (timeout_s < 0) timeout_s = 1.0;
}

Result<std::vector<can::BusSpec>> BusSelection::specs() const {
  if (empty())
    return Error(CoreErrc::invalid_argument, "select the buses: --gateway HOST:PORT, --socketcand HOST:PORT or --bus SPEC");
  std::vector<std::string> texts;
  if (!gateway.empty()) {
    AXON_TRY(ep, net::parse_endpoint(gateway, can::kCanNetPort));
    for (int c : channels) texts.push_back(fmt::format("cannet://{}/{}", ep.to_string(), c));
  }
  if (!socketcand.empty())
    for (const auto& c : scd_channels) texts.push_back(fmt::format("socketcand://{}/{}", socketcand, c));
  texts.insert(texts.end(), buses.begin(), buses.end());
  std::vector<can::BusSpec> out;
  for (const auto& t : texts) {
    auto spec = can::parse_bus_spec(t);
    if (!spec) return Error(CoreErrc::invalid_argument, spec.error().message());
    out.push_back(std::move(spec).value());
  }
  if (auto distinct = can::check_distinct(out); !distinct) return Error(CoreErrc::invalid_argument, distinct.error().detail);
  return out;
}

}  // namespace axon::fps::host
