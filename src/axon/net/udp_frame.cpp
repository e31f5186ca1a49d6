#include "axon/net/udp_frame.hpp"

#include <cstring>

namespace axon::net {

namespace {

void put16(std::byte* p, std::uint16_t v) noexcept {
  p[0] = std::byte(v >> 8);
  p[1] = std::byte(v & 0xff);
}
void put32(std::byte* p, std::uint32_t v) noexcept {
  put16(p, static_cast<std::uint16_t>(v >> 16));
  put16(p + 2, static_cast<std::uint16_t>(v & 0xffff));
}
void put_mac(std::byte* p, std::uint32_t ip) noexcept {
  p[0] = std::byte{0x02};  // locally administered, unicast
  p[1] = std::byte{0x00};
  put32(p + 2, ip);
}

}  // namespace

std::uint32_t ones_complement_sum(std::span<const std::byte> data, std::uint32_t sum) noexcept {
  std::size_t i = 0;
  for (; i + 1 < data.size(); i += 2)
    sum += (static_cast<std::uint32_t>(data[i]) << 8) | static_cast<std::uint32_t>(data[i + 1]);
  if (i < data.size()) sum += static_cast<std::uint32_t>(data[i]) << 8;
  // Keep the carry from growing without bound on long inputs.
  while (sum >> 16) sum = (sum & 0xffff) + (sum >> 16);
  return sum;
}

std::uint16_t fold_checksum(std::uint32_t sum) noexcept {
  while (sum >> 16) sum = (sum & 0xffff) + (sum >> 16);
  return static_cast<std::uint16_t>(~sum & 0xffff);
}

std::size_t write_udp_frame(std::span<std::byte> out, const SocketAddress& src, const SocketAddress& dst,
                            std::span<const std::byte> payload, std::size_t payload_size,
                            std::uint16_t ip_id) noexcept {
  std::byte* eth = out.data();
  put_mac(eth, dst.ip);
  put_mac(eth + 6, src.ip);
  put16(eth + 12, 0x0800);

  std::byte* ip = eth + kEthernetHeaderSize;
  const auto udp_length = static_cast<std::uint16_t>(kUdpHeaderSize + payload_size);
  ip[0] = std::byte{0x45};  // version 4, 5 words
  ip[1] = std::byte{0};
  put16(ip + 2, static_cast<std::uint16_t>(kIpv4HeaderSize + udp_length));
  put16(ip + 4, ip_id);
  put16(ip + 6, 0x4000);  // don't fragment
  ip[8] = std::byte{64};
  ip[9] = std::byte{17};  // UDP
  put16(ip + 10, 0);
  put32(ip + 12, src.ip);
  put32(ip + 16, dst.ip);
  put16(ip + 10, fold_checksum(ones_complement_sum({ip, kIpv4HeaderSize})));

  std::byte* udp = ip + kIpv4HeaderSize;
  put16(udp, src.port);
  put16(udp + 2, dst.port);
  put16(udp + 4, udp_length);
  put16(udp + 6, 0);
  if (!payload.empty()) std::memcpy(udp + kUdpHeaderSize, payload.data(), payload.size());
  if (payload.size() == payload_size) {
    // Pseudo-header (addresses, protocol, UDP length), then the UDP header and payload.
    std::byte pseudo[12];
    put32(pseudo, src.ip);
    put32(pseudo + 4, dst.ip);
    pseudo[8] = std::byte{0};
    pseudo[9] = std::byte{17};
    put16(pseudo + 10, udp_length);
    std::uint32_t sum = ones_complement_sum({pseudo, sizeof pseudo});
    sum = ones_complement_sum({udp, kUdpHeaderSize + payload.size()}, sum);
    std::uint16_t c = fold_checksum(sum);
    if (c == 0) c = 0xffff;  // 0 would mean "no checksum"
    put16(udp + 6, c);
  }
  return kUdpFrameOverhead + payload.size();
}

}  // namespace axon::net
