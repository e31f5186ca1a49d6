#include "axon/c4g/host/pcap_recorder.hpp"

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/net/udp_frame.hpp"

#include <boost/lockfree/spsc_queue.hpp>
#include <fmt/format.h>
#include <pcap/pcap.h>

#include <array>
#include <condition_variable>
#include <mutex>
#include <cstring>
#include <filesystem>
#include <thread>

namespace axon::c4g::host {

namespace {
struct Slot {
  std::int64_t wall_ns;
  net::SocketAddress src;
  net::SocketAddress dst;
  std::uint32_t size;      // datagram length on the wire
  std::uint32_t captured;  // bytes kept in payload
  std::array<std::byte, PcapRecorder::kSnapPayload> payload;
};
}  // namespace

struct PcapRecorder::Impl {
  explicit Impl(std::size_t capacity) : queue(capacity) {}
  ~Impl() {
    if (dumper) pcap_dump_close(dumper);
    if (handle) pcap_close(handle);
  }
  boost::lockfree::spsc_queue<Slot> queue;
  pcap_t* handle = nullptr;
  pcap_dumper_t* dumper = nullptr;
  std::thread writer;
  std::mutex mutex;  // writer thread and close()/flush() only, never the cycle thread
  std::condition_variable wake_cv;
  bool wake = false;  // under mutex
  std::uint16_t ip_id = 0;
  std::chrono::steady_clock::time_point opened{};  // of the current file, for the age limit
  bool records = false;                            // the current file holds a datagram
  std::array<std::byte, net::kUdpFrameOverhead + kSnapPayload> frame{};
};

Result<std::unique_ptr<PcapRecorder>> PcapRecorder::open(const std::string& path, const PcapOptions& options) {
  if (options.queue_capacity == 0) return Error(CoreErrc::invalid_argument, "pcap recorder: queue capacity must be positive");
  std::unique_ptr<PcapRecorder> r(new PcapRecorder());
  r->path_ = path;
  r->options_ = options;
  r->impl_ = std::make_unique<Impl>(options.queue_capacity);
  r->impl_->handle = pcap_open_dead_with_tstamp_precision(DLT_EN10MB, static_cast<int>(net::kUdpFrameOverhead + kSnapPayload),
                                                          PCAP_TSTAMP_PRECISION_NANO);
  if (r->impl_->handle == nullptr) return Error(CoreErrc::io, "pcap_open_dead failed");
  AXON_TRY(options.rotation.validate());
  r->impl_->dumper = pcap_dump_open(r->impl_->handle, path.c_str());
  if (r->impl_->dumper == nullptr)
    return Error(CoreErrc::io, fmt::format("pcap file '{}': {}", path, pcap_geterr(r->impl_->handle)));
  r->impl_->opened = std::chrono::steady_clock::now();
  r->impl_->writer = std::thread([p = r.get()] { p->run(); });
  return r;
}

PcapRecorder::~PcapRecorder() { close(); }

bool PcapRecorder::record(const net::SocketAddress& src, const net::SocketAddress& dst, std::span<const std::byte> payload,
                          std::int64_t wall_ns) noexcept {
  if (closed_.load(std::memory_order_relaxed) || !impl_) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  Slot s;
  s.wall_ns = wall_ns;
  s.src = src;
  s.dst = dst;
  s.size = static_cast<std::uint32_t>(payload.size());
  s.captured = static_cast<std::uint32_t>(std::min(payload.size(), kSnapPayload));
  if (s.captured) std::memcpy(s.payload.data(), payload.data(), s.captured);
  if (!impl_->queue.push(s)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  if (s.captured < s.size) cut_.fetch_add(1, std::memory_order_relaxed);
  queued_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

bool PcapRecorder::rotate_if_due(std::size_t bytes) {
  auto& im = *impl_;
  const auto& lim = options_.rotation;
  if (im.dumper == nullptr) return reopen();  // an earlier rotation failed: try again
  if (!lim.any() || !im.records) return true;
  const auto size = static_cast<std::uint64_t>(pcap_dump_ftell64(im.dumper)) + 16 + bytes;  // 16: record header
  const bool too_big = lim.max_bytes > 0 && size > lim.max_bytes;
  const bool too_old = lim.max_age > core::Duration::zero() && std::chrono::steady_clock::now() - im.opened >= lim.max_age;
  if (!too_big && !too_old) return true;
  pcap_dump_close(im.dumper);
  im.dumper = nullptr;
  return reopen();
}

bool PcapRecorder::reopen() {
  auto& im = *impl_;
  std::error_code ec;
  if (std::filesystem::exists(path_, ec) && !core::RotatingFile::shift(path_, options_.rotation.keep)) return false;
  im.dumper = pcap_dump_open(im.handle, path_.c_str());
  if (im.dumper == nullptr) return false;
  im.opened = std::chrono::steady_clock::now();
  im.records = false;
  rotations_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void PcapRecorder::run() {
  auto write_one = [this](const Slot& s) {
    const std::size_t wire = std::min<std::size_t>(s.size, net::kMaxUdpPayload);
    const std::size_t n = net::write_udp_frame(impl_->frame, s.src, s.dst, {s.payload.data(), s.captured}, wire, impl_->ip_id++);
    if (!rotate_if_due(n)) {
      write_failures_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    impl_->records = true;
    pcap_pkthdr h{};
    // With nanosecond precision the header's microsecond field carries nanoseconds.
    h.ts.tv_sec = static_cast<time_t>(s.wall_ns / 1'000'000'000);
    h.ts.tv_usec = static_cast<suseconds_t>(s.wall_ns % 1'000'000'000);
    h.caplen = static_cast<bpf_u_int32>(n);
    h.len = static_cast<bpf_u_int32>(net::kUdpFrameOverhead + wire);
    pcap_dump(reinterpret_cast<u_char*>(impl_->dumper), &h, reinterpret_cast<const u_char*>(impl_->frame.data()));
  };
  for (;;) {
    {
      // Sleep first: the cycle thread never signals (that could block it); the writer polls.
      std::unique_lock lock(impl_->mutex);
      impl_->wake_cv.wait_for(lock, options_.drain_interval,
                              [this] { return impl_->wake || stop_.load(std::memory_order_acquire); });
      impl_->wake = false;
    }
    const bool stopping = stop_.load(std::memory_order_acquire);
    std::size_t n = 0;
    Slot s;
    while (impl_->queue.pop(s)) {
      write_one(s);
      ++n;
    }
    if (n) {
      if (impl_->dumper != nullptr) pcap_dump_flush(impl_->dumper);
      handled_.fetch_add(n, std::memory_order_release);  // written, or counted as a write failure
    }
    if (stopping) return;  // the queue was drained after the stop request was seen
  }
}

void PcapRecorder::flush() {
  if (!impl_ || !impl_->writer.joinable()) return;
  const std::uint64_t target = queued();
  while (handled_.load(std::memory_order_acquire) < target) {
    {
      std::lock_guard lock(impl_->mutex);
      impl_->wake = true;
    }
    impl_->wake_cv.notify_one();
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void PcapRecorder::close() {
  if (closed_.exchange(true)) return;
  if (!impl_) return;
  {
    std::lock_guard lock(impl_->mutex);
    stop_.store(true, std::memory_order_release);
  }
  impl_->wake_cv.notify_one();
  if (impl_->writer.joinable()) impl_->writer.join();
  impl_.reset();
}

Result<std::vector<std::byte>> read_init_packet(const std::string& path) {
  char err[PCAP_ERRBUF_SIZE] = {};
  pcap_t* p = pcap_open_offline(path.c_str(), err);
  if (!p) return Error(CoreErrc::invalid_argument, fmt::format("cannot read capture {}: {}", path, err));
  constexpr std::size_t kInitSize = protocol::kInitPacketSize;
  std::vector<std::byte> out;
  const int link = pcap_datalink(p);
  pcap_pkthdr* hdr = nullptr;
  const u_char* data = nullptr;
  while (out.empty() && pcap_next_ex(p, &hdr, &data) == 1) {
    std::size_t off = link == DLT_EN10MB ? 14 : (link == DLT_RAW ? 0 : SIZE_MAX);
    if (off == SIZE_MAX || hdr->caplen < off + 28) continue;
    if (link == DLT_EN10MB && (data[12] != 0x08 || data[13] != 0x00)) continue;
    const std::size_t ihl = (data[off] & 0x0F) * 4u;
    if ((data[off] >> 4) != 4 || data[off + 9] != 17) continue;
    const std::size_t udp = off + ihl;
    const std::size_t len = (static_cast<std::size_t>(data[udp + 4]) << 8 | data[udp + 5]);
    if (len != 8 + kInitSize || hdr->caplen < udp + len) continue;
    const auto* payload = reinterpret_cast<const std::byte*>(data + udp + 8);
    out.assign(payload, payload + kInitSize);
  }
  pcap_close(p);
  if (out.empty()) return Error(CoreErrc::invalid_argument, fmt::format("{}: no 1200-byte initialization packet in the capture", path));
  return out;
}

}  // namespace axon::c4g::host
