#include "axon/fps/protocol/payload.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>

namespace axon::fps::protocol {

Result<Payload> Payload::from(std::span<const std::uint8_t> bytes) {
  if (bytes.size() > kMaxSize) {
    return Error(ProtocolErrc::wrong_length, fmt::format("{} bytes do not fit one frame (max 8)", bytes.size()));
  }
  Payload p;
  for (auto b : bytes) p.put_u8(b);
  return p;
}

std::string Payload::to_hex() const {
  std::string s;
  for (std::size_t i = 0; i < size_; ++i) {
    if (i) s += ' ';
    s += fmt::format("{:02X}", bytes_[i]);
  }
  return s;
}

Result<void> expect_size(std::span<const std::uint8_t> bytes, std::size_t expected, std::string_view what) {
  if (bytes.size() != expected) {
    return Error(ProtocolErrc::wrong_length,
                 fmt::format("{}: {} data bytes, expected {}", what, bytes.size(), expected));
  }
  return ok();
}

}  // namespace axon::fps::protocol
