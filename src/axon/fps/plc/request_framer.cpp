#include "axon/fps/plc/request_framer.hpp"

#include "axon/fps/plc/error.hpp"

#include <fmt/format.h>

namespace axon::fps::plc {

namespace {

unsigned be16(std::span<const std::uint8_t> b, std::size_t at) { return (unsigned{b[at]} << 8) | b[at + 1]; }

// The PDU size (function code included) a function with a fixed layout needs; 0 for the others.
std::size_t fixed_pdu_size(std::span<const std::uint8_t> pdu) {
  switch (pdu[0]) {
    case 0x01: case 0x02: case 0x03: case 0x04: case 0x05: case 0x06: return 5;  // address, quantity or value
    case 0x07: case 0x11: return 1;                                              // exception status, server id
    case 0x0F: case 0x10: return pdu.size() < 6 ? 6 : 6 + std::size_t{pdu[5]};   // + byte count and data
    case 0x16: return 7;                                                         // address, AND mask, OR mask
    case 0x17: return pdu.size() < 10 ? 10 : 10 + std::size_t{pdu[9]};           // read and write ranges, data
    default: return 0;
  }
}

// The header's own problem, as soon as the 6 bytes up to the length are there.
std::string header_problem(std::span<const std::uint8_t> head) {
  if (const unsigned protocol = be16(head, 2); protocol != 0) return fmt::format("protocol id {} (Modbus is 0)", protocol);
  const std::size_t length = be16(head, 4);
  if (length < 2) return fmt::format("length {} (a unit id and a function code at least)", length);
  if (length + 6 > kMaxRequestSize) return fmt::format("length {} (at most {})", length, kMaxRequestSize - 6);
  return {};
}

}  // namespace

std::string request_problem(std::span<const std::uint8_t> adu) {
  if (adu.size() < kMbapHeaderSize + 1) return fmt::format("{} bytes: no MBAP header and function code", adu.size());
  if (auto p = header_problem(adu); !p.empty()) return p;
  if (be16(adu, 4) + 6 != adu.size())
    return fmt::format("length {} but {} bytes follow it", be16(adu, 4), adu.size() - 6);
  const auto pdu = adu.subspan(kMbapHeaderSize);
  if (const std::size_t need = fixed_pdu_size(pdu); need != 0 && need != pdu.size())
    return fmt::format("function {:#04x} takes {} bytes, the header announces {}", pdu[0], need, pdu.size());
  return {};
}

void RequestFramer::feed(std::span<const std::uint8_t> bytes) {
  if (head_ > 0) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
  if (broken_.empty()) buf_.insert(buf_.end(), bytes.begin(), bytes.end());
}

std::optional<Result<std::span<const std::uint8_t>>> RequestFramer::next() {
  auto fail = [this](std::string why) {
    broken_ = std::move(why);
    buf_.clear();
    head_ = 0;
    return Result<std::span<const std::uint8_t>>(Error(PlcErrc::io, fmt::format("not Modbus TCP: {}", broken_)));
  };
  if (!broken_.empty()) return fail(broken_);
  const auto rest = std::span<const std::uint8_t>(buf_).subspan(head_);
  if (rest.size() >= 6) {
    if (auto p = header_problem(rest); !p.empty()) return fail(std::move(p));
    const std::size_t total = 6 + be16(rest, 4);
    if (rest.size() >= total) {
      const auto adu = rest.first(total);
      if (auto p = request_problem(adu); !p.empty()) return fail(std::move(p));
      head_ += total;
      return Result<std::span<const std::uint8_t>>(adu);
    }
  }
  if (head_ > 0) {  // keep only the partial request
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
  return std::nullopt;
}

}  // namespace axon::fps::plc
