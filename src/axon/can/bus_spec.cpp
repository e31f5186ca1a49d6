#include "axon/can/bus_spec.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>

namespace axon::can {

namespace {
bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }
bool valid_name(std::string_view s) {
  if (s.empty() || s.size() > 64) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}
}  // namespace

Result<BusSpec> parse_bus_spec(std::string_view text) {
  auto bad = [&](std::string_view why) { return Error(CanErrc::bad_spec, fmt::format("bus '{}': {}", text, why)); };
  BusSpec s;
  s.text = std::string(text);
  if (starts_with(text, "virtual:")) {
    s.kind = BusSpec::Kind::virtual_bus;
    s.channel = std::string(text.substr(8));
    if (!valid_name(s.channel)) return bad("virtual bus name must be letters, digits, '_', '-' or '.'");
    return s;
  }
  if (starts_with(text, "socketcan:")) {
    s.kind = BusSpec::Kind::socketcan;
    s.channel = std::string(text.substr(10));
    if (!valid_name(s.channel) || s.channel.size() > 15) return bad("interface name must be 1..15 characters");
    return s;
  }
  const bool is_scd = starts_with(text, "socketcand://"), is_cannet = starts_with(text, "cannet://");
  if (!is_scd && !is_cannet) return bad("unknown kind");
  std::string_view rest = text.substr(is_scd ? 13 : 9);
  const auto slash = rest.rfind('/');
  if (slash == std::string_view::npos) return bad(is_scd ? "missing /CHANNEL" : "missing /N (channel 1..4)");
  auto ep = net::parse_endpoint(rest.substr(0, slash), is_scd ? kSocketcandPort : kCanNetPort);
  if (!ep) return bad(ep.error().detail);
  s.endpoint = ep.value();
  const std::string_view ch = rest.substr(slash + 1);
  if (is_scd) {
    s.kind = BusSpec::Kind::socketcand;
    if (!valid_name(ch)) return bad("channel name must be letters, digits, '_', '-' or '.'");
    s.channel = std::string(ch);
    return s;
  }
  s.kind = BusSpec::Kind::cannet;
  int n = 0;
  auto [p, ec] = std::from_chars(ch.data(), ch.data() + ch.size(), n);
  if (ec != std::errc() || p != ch.data() + ch.size() || n < 1 || n > 4) return bad("CAN@net channel must be 1..4");
  s.cannet_channel = n;
  s.channel = fmt::format("can{}", n - 1);
  return s;
}

std::string BusSpec::to_string() const {
  switch (kind) {
    case Kind::virtual_bus: return "virtual:" + channel;
    case Kind::socketcan: return "socketcan:" + channel;
    case Kind::socketcand: return fmt::format("socketcand://{}/{}", endpoint.to_string(), channel);
    case Kind::cannet: return fmt::format("cannet://{}/{}", endpoint.to_string(), cannet_channel);
  }
  return text;
}

std::string BusSpec::short_name() const {
  if (kind == Kind::cannet) return fmt::format("cannet{}", cannet_channel);
  return channel;
}

}  // namespace axon::can
