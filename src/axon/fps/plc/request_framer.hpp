// Modbus TCP requests cut out of a server's byte stream, without blocking and with a bound.
//
// A request is the MBAP header (transaction id, protocol id 0, length, unit id) and the PDU the
// length announces. For the functions whose layout is fixed (read/write coils and registers, the
// multiple writes with their byte count, mask write, write-and-read, the two status reads) the
// announced length must be exactly what the function needs; other functions pass with any length
// up to the protocol's limit, for the server to answer "illegal function". Anything else (another
// protocol id, a length of 0 or 1 or beyond 254, a length that disagrees with the function) is not
// Modbus TCP: the framer reports it once and stops, and the server ends that connection (there is
// no resynchronising a TCP stream once its framing is lost).
//
// Bounded: the framer never holds more than one partial request (< kMaxRequestSize bytes) between
// calls to next(), however the bytes arrive.
#pragma once

#include "axon/core/error.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::plc {

inline constexpr std::size_t kMbapHeaderSize = 7;    // transaction 2, protocol 2, length 2, unit 1
inline constexpr std::size_t kMaxRequestSize = 260;  // MBAP + the longest PDU (Modbus TCP's ADU limit)

// Why `adu` (a complete request as its MBAP length says) is not a well-formed Modbus TCP request,
// or an empty string when it is.
std::string request_problem(std::span<const std::uint8_t> adu);

class RequestFramer {
 public:
  // Takes bytes as they came from the socket.
  void feed(std::span<const std::uint8_t> bytes);
  // The next complete request (header included; valid until the next feed() or next()), nothing
  // until more bytes arrive, or PlcErrc::io once the stream is found not to be Modbus TCP (then
  // always that error).
  std::optional<Result<std::span<const std::uint8_t>>> next();
  // Bytes held that do not yet form a request.
  [[nodiscard]] std::size_t buffered() const noexcept { return buf_.size() - head_; }

 private:
  std::vector<std::uint8_t> buf_;
  std::size_t head_ = 0;
  std::string broken_;  // the problem, once found
};

}  // namespace axon::fps::plc
