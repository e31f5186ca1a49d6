// Synthetic Ethernet + IPv4 + UDP headers around a payload, as a capture file shows a datagram.
//
// Used to record datagrams sent and received through a UDP socket (which only sees payloads)
// into a capture that network analysers decode with the real addresses and ports. Pure functions,
// no I/O, no allocation.
#pragma once

#include "axon/net/udp_socket.hpp"

#include <cstddef>
#include <cstdint>
#include <span>

namespace axon::net {

inline constexpr std::size_t kEthernetHeaderSize = 14;
inline constexpr std::size_t kIpv4HeaderSize = 20;
inline constexpr std::size_t kUdpHeaderSize = 8;
inline constexpr std::size_t kUdpFrameOverhead = kEthernetHeaderSize + kIpv4HeaderSize + kUdpHeaderSize;  // 42
inline constexpr std::size_t kMaxUdpPayload = 65'507;  // 65535 - IPv4 header - UDP header

// The ones'-complement sum of 16-bit big-endian words (RFC 1071), not yet complemented; an odd
// trailing byte is padded with zero. Chain calls through `start`.
std::uint32_t ones_complement_sum(std::span<const std::byte> data, std::uint32_t start = 0) noexcept;
// Folds a sum to 16 bits and complements it: the checksum to put in a header.
std::uint16_t fold_checksum(std::uint32_t sum) noexcept;

// Writes Ethernet (locally administered MACs 02:00:<IPv4>), IPv4 (no options, DF, TTL 64) and UDP
// headers for a datagram of `payload_size` bytes from `src` to `dst`, followed by `payload`
// (which may be shorter than payload_size when the capture was truncated; the UDP checksum is
// then 0, "not computed"). `out` must hold kUdpFrameOverhead + payload.size() bytes; returns the
// number of bytes written. payload_size must not exceed kMaxUdpPayload.
std::size_t write_udp_frame(std::span<std::byte> out, const SocketAddress& src, const SocketAddress& dst,
                            std::span<const std::byte> payload, std::size_t payload_size,
                            std::uint16_t ip_id) noexcept;

}  // namespace axon::net
