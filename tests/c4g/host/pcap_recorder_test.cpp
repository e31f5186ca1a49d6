#include "axon/c4g/host/pcap_recorder.hpp"

#include "axon/net/udp_frame.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <pcap/pcap.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <unistd.h>
#include <filesystem>
#include <string>
#include <vector>

using namespace axon;
using namespace axon::c4g::host;
using net::SocketAddress;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / fmt::format("axon_{}_{}.pcap", name, ::getpid())).string();
}

std::uint16_t get16(const u_char* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
std::uint32_t get32(const u_char* p) { return (std::uint32_t{get16(p)} << 16) | get16(p + 2); }

struct CapturedPacket {
  std::int64_t ns;
  std::uint32_t caplen, len;
  std::vector<u_char> bytes;
};

std::vector<CapturedPacket> read_back(const std::string& path, int* linktype) {
  char err[PCAP_ERRBUF_SIZE];
  pcap_t* p = pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, err);
  EXPECT_NE(p, nullptr) << err;
  std::vector<CapturedPacket> out;
  if (!p) return out;
  *linktype = pcap_datalink(p);
  pcap_pkthdr* h;
  const u_char* data;
  while (pcap_next_ex(p, &h, &data) == 1) {
    out.push_back({static_cast<std::int64_t>(h->ts.tv_sec) * 1'000'000'000 + h->ts.tv_usec, h->caplen, h->len,
                   std::vector<u_char>(data, data + h->caplen)});
  }
  pcap_close(p);
  return out;
}

std::vector<std::byte> pattern(std::size_t n, int seed) {
  std::vector<std::byte> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = std::byte(static_cast<unsigned char>((i * 7 + static_cast<std::size_t>(seed)) & 0xff));
  return v;
}

const SocketAddress kController{0x0a020c96, 1000};  // 10.2.12.150
const SocketAddress kPc{0x0a020c95, 1000};          // 10.2.12.149

}  // namespace

TEST(PcapRecorder, WritesDatagramsWithAddressesPortsPayloadsAndTimes) {
  const auto path = temp_path("rec");
  auto rec = PcapRecorder::open(path).value();
  const auto a = pattern(12 + 36 * 6, 1);  // a six-axis cyclic packet
  const auto b = pattern(1200, 2);          // the initialization packet
  const std::int64_t t0 = 1'700'000'000'123'456'789;
  ASSERT_TRUE(rec->record(kController, kPc, a, t0));
  ASSERT_TRUE(rec->record(kPc, SocketAddress{0x0a020c96, 5001}, b, t0 + 87'654));
  rec->flush();
  EXPECT_EQ(rec->written(), 2u);
  rec->close();
  EXPECT_EQ(rec->dropped(), 0u);

  int linktype = -1;
  const auto pk = read_back(path, &linktype);
  EXPECT_EQ(linktype, DLT_EN10MB);
  ASSERT_EQ(pk.size(), 2u);

  EXPECT_EQ(pk[0].ns, t0);
  EXPECT_EQ(pk[1].ns, t0 + 87'654);
  for (int i = 0; i < 2; ++i) {
    const auto& p = pk[static_cast<std::size_t>(i)];
    const auto& payload = i == 0 ? a : b;
    ASSERT_EQ(p.caplen, 42 + payload.size());
    EXPECT_EQ(p.len, p.caplen);
    const u_char* eth = p.bytes.data();
    EXPECT_EQ(get16(eth + 12), 0x0800);
    const u_char* ip = eth + 14;
    EXPECT_EQ(ip[0], 0x45);
    EXPECT_EQ(get16(ip + 2), 28 + payload.size());
    EXPECT_EQ(ip[9], 17);
    EXPECT_EQ(net::fold_checksum(net::ones_complement_sum({reinterpret_cast<const std::byte*>(ip), 20})), 0)
        << "IPv4 header checksum";
    const u_char* udp = ip + 20;
    EXPECT_EQ(get16(udp + 4), 8 + payload.size());
    EXPECT_NE(get16(udp + 6), 0) << "UDP checksum present";
    EXPECT_EQ(std::memcmp(udp + 8, payload.data(), payload.size()), 0);
    if (i == 0) {
      EXPECT_EQ(get32(ip + 12), kController.ip);
      EXPECT_EQ(get32(ip + 16), kPc.ip);
      EXPECT_EQ(get16(udp), 1000);
      EXPECT_EQ(get16(udp + 2), 1000);
    } else {
      EXPECT_EQ(get32(ip + 12), kPc.ip);
      EXPECT_EQ(get32(ip + 16), 0x0a020c96u);
      EXPECT_EQ(get16(udp + 2), 5001);
    }
  }
  std::filesystem::remove(path);
}

TEST(PcapRecorder, LongDatagramsAreCutButKeepTheirLength) {
  const auto path = temp_path("cut");
  auto rec = PcapRecorder::open(path).value();
  const auto big = pattern(3000, 3);
  ASSERT_TRUE(rec->record(kController, kPc, big, 1'000'000'000));
  rec->close();
  EXPECT_EQ(rec->cut(), 1u);
  int linktype = -1;
  const auto pk = read_back(path, &linktype);
  ASSERT_EQ(pk.size(), 1u);
  EXPECT_EQ(pk[0].caplen, 42 + PcapRecorder::kSnapPayload);
  EXPECT_EQ(pk[0].len, 42 + 3000u);
  EXPECT_EQ(get16(pk[0].bytes.data() + 14 + 2), 28 + 3000);
  EXPECT_EQ(get16(pk[0].bytes.data() + 34 + 6), 0) << "no UDP checksum over bytes not kept";
  std::filesystem::remove(path);
}

TEST(PcapRecorder, FullQueueDropsAndCountsWithoutBlocking) {
  const auto path = temp_path("drop");
  PcapOptions o;
  o.queue_capacity = 2;
  o.drain_interval = std::chrono::hours(1);  // the writer will not drain on its own
  auto rec = PcapRecorder::open(path, o).value();
  const auto a = pattern(20, 4);
  int accepted = 0;
  for (int i = 0; i < 5; ++i) accepted += rec->record(kController, kPc, a, 1'000 + i) ? 1 : 0;
  EXPECT_EQ(accepted, 2);
  EXPECT_EQ(rec->dropped(), 3u);
  rec->close();  // drains what was queued, promptly
  EXPECT_EQ(rec->written(), 2u);
  EXPECT_FALSE(rec->record(kController, kPc, a, 9));
  EXPECT_EQ(rec->dropped(), 4u);
  int linktype = -1;
  EXPECT_EQ(read_back(path, &linktype).size(), 2u);
  std::filesystem::remove(path);
}

TEST(PcapRecorder, UnwritablePathIsAnError) {
  auto r = PcapRecorder::open("/nonexistent-dir/x.pcap");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CoreErrc::io);
}

TEST(PcapRecorder, TcpdumpDecodesTheCaptureWhenInstalled) {
  const char* candidates[] = {"/usr/bin/tcpdump", "/usr/sbin/tcpdump"};
  std::string tcpdump;
  for (const char* c : candidates)
    if (std::filesystem::exists(c)) tcpdump = c;
  if (tcpdump.empty()) GTEST_SKIP() << "tcpdump not installed";
  const auto path = temp_path("tcpdump");
  auto rec = PcapRecorder::open(path).value();
  ASSERT_TRUE(rec->record(kController, kPc, pattern(48, 5), 1'000'000'000));
  rec->close();
  const auto out = path + ".txt";
  const std::string cmd = fmt::format("{} -nn -vv -r {} > {} 2>&1", tcpdump, path, out);
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream f(out);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("10.2.12.150.1000 > 10.2.12.149.1000"), std::string::npos) << text;
  EXPECT_NE(text.find("UDP, length 48"), std::string::npos) << text;
  EXPECT_EQ(text.find("bad"), std::string::npos) << text;  // "bad cksum", "bad udp cksum"
  std::filesystem::remove(path);
  std::filesystem::remove(out);
}

// A long session's capture with a size limit: the full file moves to PATH.1 (older ones PATH.2 ...)
// and recording goes on in PATH; every file is a complete capture that libpcap reads, and no
// datagram is lost or split across files.
TEST(PcapRecorder, SizeLimitRotatesIntoCompleteCaptures) {
  const std::string path = temp_path("rotate");
  for (int k = 0; k <= 3; ++k) std::filesystem::remove(k == 0 ? path : fmt::format("{}.{}", path, k));
  PcapOptions o;
  o.rotation.max_bytes = 4096;  // about 10 six-axis datagrams a file
  o.rotation.keep = 50;
  auto rec = PcapRecorder::open(path, o).value();
  const auto payload = pattern(228, 1);
  const int n = 100;
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(rec->record(kController, kPc, payload, 1'700'000'000'000'000'000LL + i));
    if (i % 10 == 9) rec->flush();  // the queue never fills
  }
  rec->close();
  EXPECT_GT(rec->rotations(), 5u);
  EXPECT_EQ(rec->write_failures(), 0u);
  std::size_t total = 0;
  for (unsigned k = 0; k <= rec->rotations(); ++k) {
    const std::string name = k == 0 ? path : fmt::format("{}.{}", path, k);
    EXPECT_LE(std::filesystem::file_size(name), 4096u) << name;
    int linktype = 0;
    const auto got = read_back(name, &linktype);
    EXPECT_EQ(linktype, DLT_EN10MB) << name;
    EXPECT_FALSE(got.empty()) << name;
    total += got.size();
    std::filesystem::remove(name);
  }
  EXPECT_EQ(total, static_cast<std::size_t>(n));
}
