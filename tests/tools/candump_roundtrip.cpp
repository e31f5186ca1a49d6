// Test-only tool for the python-can interoperability test (tests/integration/python_can_log.py):
//
//   axon_candump_tool write FILE   writes a fixed set of frames as a candump log
//   axon_candump_tool read FILE    prints every entry as `TIMESTAMP_NS IFACE ID#DATA [error|rx|tx]`
//
// The python test holds its own copy of the fixed set, so a mistake here cannot hide one in the
// library. Exit status: 0 on success, 2 when the file cannot be written or read (the error on stderr).
#include "axon/can/candump_log.hpp"

#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <string_view>
#include <vector>

namespace {

using axon::can::Frame;
using axon::can::IdFormat;
using axon::can::LogEntry;

LogEntry entry(Frame f, std::int64_t us, const char* iface, bool error = false) {
  f.set_timestamp(axon::core::WallTime(us * 1000));
  return LogEntry{f, iface, error, {}};
}

std::vector<LogEntry> fixed_set() {
  using B = std::vector<std::uint8_t>;
  auto data = [](std::uint32_t id, IdFormat fmt, B bytes) { return Frame::data(id, fmt, bytes).value(); };
  return {
      entry(data(0x12345678, IdFormat::extended, {0x01, 0x02, 0x03, 0x04}), 1436509052249713, "vcan0"),
      entry(data(0x123, IdFormat::standard, {0xDE, 0xAD, 0xBE, 0xEF}), 1436509052249714, "vcan0"),
      entry(Frame::remote(0x7FF, IdFormat::standard, 0).value(), 1436509052250000, "vcan0"),
      entry(Frame::remote(0x42, IdFormat::extended, 4).value(), 1436509052300001, "can1"),
      entry(data(0x000, IdFormat::standard, {}), 1436509053000000, "can1"),
      entry(data(0x1FFFFFFF, IdFormat::extended, {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77}), 1436509053999999,
            "vcan0"),
      entry(data(0x555, IdFormat::standard, {0xFF}), 1700000000123456, "vcan0"),
      entry(data(0x080, IdFormat::extended, {0, 0, 0, 0, 0, 0, 0, 0}), 1700000001000000, "can0", true),
  };
}

int fail(const axon::Error& e) {
  std::fprintf(stderr, "error: %s\n", e.message().c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 || (std::string_view(argv[1]) != "write" && std::string_view(argv[1]) != "read")) {
    std::fprintf(stderr, "usage: %s write|read FILE\n", argv[0]);
    return 1;
  }
  const std::string_view mode = argv[1];
  if (mode == "write") {
    auto writer = axon::can::CandumpWriter::create(argv[2]);
    if (!writer) return fail(writer.error());
    for (const auto& e : fixed_set())
      if (auto r = writer.value().write(e); !r) return fail(r.error());
    return 0;
  }
  auto reader = axon::can::CandumpReader::open(argv[2]);
  if (!reader) return fail(reader.error());
  for (;;) {
    auto next = reader.value().next();
    if (!next) return fail(next.error());
    if (!next.value()) break;
    const LogEntry& e = *next.value();
    std::string text = e.frame.to_string();
    std::string flag;
    if (e.error_frame) {
      const auto line = axon::can::format_candump_line(e);
      text = line.substr(line.rfind(' ') + 1);  // the id with the error flag, as in the log
      flag = " error";
    } else if (e.direction == axon::can::LogDirection::rx) {
      flag = " rx";
    } else if (e.direction == axon::can::LogDirection::tx) {
      flag = " tx";
    }
    fmt::print("{} {} {}{}\n", e.frame.timestamp().count(), e.iface, text, flag);
  }
  return 0;
}
