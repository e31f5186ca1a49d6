// Fuzzes the CAN@net line layer. The input is cut into lines twice: at '\n' by hand, and by
// LineSplitter fed in two chunks (cut where the first byte says); both must agree. Every line is
// parsed; one that parses must format to text that parses back to the same value, and formatting
// that again must give the same text. Any disagreement traps.
#include "axon/can/cannet_codec.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace {

using namespace axon::can::cannet;

void check_line(std::string_view line) {
  auto parsed = parse_line(line);
  if (!parsed) {
    if (parsed.error().code != axon::can::CanErrc::parse_error || parsed.error().detail.empty()) __builtin_trap();
    return;
  }
  const std::string text = format_line(parsed.value());
  auto again = parse_line(text);
  if (!again || !(again.value() == parsed.value())) __builtin_trap();
  if (format_line(again.value()) != text) __builtin_trap();
}

// A splitter piece kept beyond the next call (Piece::text is a view valid only until then).
struct Owned {
  std::string text;
  bool overlong = false;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  constexpr std::size_t kMax = kMaxLineLength + 1;

  // What the splitter must produce: every '\n'-terminated line, too-long ones as overlong, and an
  // unterminated tail only when it is already too long.
  std::vector<Owned> expected;
  std::string_view rest = input;
  while (!rest.empty()) {
    const auto nl = rest.find('\n');
    const std::string_view line = rest.substr(0, nl);
    if (nl == std::string_view::npos) {
      if (line.size() > kMax) expected.push_back({{}, true});
      break;
    }
    expected.push_back(line.size() > kMax ? Owned{{}, true} : Owned{std::string(line), false});
    check_line(line);
    rest = rest.substr(nl + 1);
  }

  LineSplitter splitter;
  std::vector<Owned> got;
  const std::size_t cut = size == 0 ? 0 : data[0] % (size + 1);
  for (const std::string_view chunk : {input.substr(0, cut), input.substr(cut)}) {
    splitter.append(chunk);
    while (auto piece = splitter.next()) got.push_back({std::string(piece->text), piece->overlong});
  }
  if (got.size() != expected.size()) __builtin_trap();
  for (std::size_t i = 0; i < got.size(); ++i)
    if (got[i].overlong != expected[i].overlong || got[i].text != expected[i].text) __builtin_trap();
  return 0;
}
