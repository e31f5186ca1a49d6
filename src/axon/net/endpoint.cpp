#include "axon/net/endpoint.hpp"

#include <fmt/format.h>

#include <charconv>

namespace axon::net {

std::string Endpoint::to_string() const {
  if (host.find(':') != std::string::npos) return fmt::format("[{}]:{}", host, port);
  return fmt::format("{}:{}", host, port);
}

Result<Endpoint> parse_endpoint(std::string_view text, std::uint16_t default_port) {
  auto bad = [&](std::string_view why) {
    return Error(CoreErrc::invalid_argument, fmt::format("address '{}': {} (expected HOST:PORT)", text, why));
  };
  Endpoint ep;
  std::string_view port_text;
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string_view::npos) return bad("missing ']'");
    ep.host = std::string(text.substr(1, close - 1));
    if (close + 1 < text.size()) {
      if (text[close + 1] != ':') return bad("expected ':' after ']'");
      port_text = text.substr(close + 2);
    }
  } else {
    const auto colon = text.rfind(':');
    if (colon == std::string_view::npos) {
      ep.host = std::string(text);
    } else {
      ep.host = std::string(text.substr(0, colon));
      port_text = text.substr(colon + 1);
    }
  }
  if (ep.host.empty()) return bad("empty host");
  if (port_text.empty()) {
    if (default_port == 0) return bad("no port");
    ep.port = default_port;
    return ep;
  }
  unsigned v = 0;
  auto [p, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), v);
  if (ec != std::errc() || p != port_text.data() + port_text.size() || v > 65535) return bad("port must be 0..65535");
  ep.port = static_cast<std::uint16_t>(v);
  return ep;
}

}  // namespace axon::net
