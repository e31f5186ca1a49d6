// Network addresses as users write them: "HOST:PORT", "[v6addr]:PORT".
#pragma once

#include "axon/core/error.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace axon::net {

struct Endpoint {
  std::string host;
  std::uint16_t port = 0;
  [[nodiscard]] std::string to_string() const;
};

// Parses "HOST:PORT" (or "[IPv6]:PORT"); when the text has no port, default_port is used if non-zero.
Result<Endpoint> parse_endpoint(std::string_view text, std::uint16_t default_port = 0);

}  // namespace axon::net
