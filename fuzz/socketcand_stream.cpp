// Fuzzes the socketcand tokenizer and parser with arbitrary byte streams cut into arbitrary reads.
//
// Checks: no crash; the messages (and the number of framing errors) do not depend on how the
// stream is cut; every message is one '<' ... '>' within the length limit; the tokenizer keeps no
// more than one message's worth of bytes; every message that parses formats to text that parses
// back to the same message, and formatting that again gives the same text.
#include "axon/can/socketcand_codec.hpp"

#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

namespace sc = axon::can::socketcand;

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

struct Outcome {
  std::vector<std::string> messages;
  std::size_t errors = 0;
};

void drain(sc::Tokenizer& t, Outcome& out) {
  while (auto r = t.next()) {
    if (*r)
      out.messages.push_back(r->value());
    else
      ++out.errors;
  }
  require(t.buffered() <= t.max_length());
}

void check_message(const std::string& text, std::size_t max_length) {
  require(text.size() >= 2 && text.size() <= max_length);
  require(text.front() == '<' && text.back() == '>');
  require(text.find_first_of("<>", 1) == text.size() - 1);

  auto m = sc::parse(text);
  require(static_cast<bool>(m) == static_cast<bool>(sc::parse_terse(text)));
  if (!m) {
    require(m.error() == axon::can::CanErrc::parse_error);
    return;
  }
  const std::string again = sc::format(m.value());
  auto back = sc::parse(again);
  require(static_cast<bool>(back));
  require(back.value() == m.value());
  require(sc::format(back.value()) == again);
  // What we write, the tokenizer cuts out whole.
  sc::Tokenizer t;
  t.feed(again);
  auto one = t.next();
  require(one && *one && one->value() == again && !t.next());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // The first byte picks the length limit, the second how the rest is cut into reads.
  const std::size_t max_length = data[0] < 128 ? sc::kMaxMessageLength : 2 + data[0] % 64;
  const unsigned cut = data[1];
  const std::string_view stream(reinterpret_cast<const char*>(data + 2), size - 2);

  Outcome whole;
  {
    sc::Tokenizer t(max_length);
    t.feed(stream);
    drain(t, whole);
  }
  Outcome pieces;
  {
    sc::Tokenizer t(max_length);
    std::size_t pos = 0, step = 0;
    while (pos < stream.size()) {
      const std::size_t n = 1 + (cut * 31 + step++ * 7) % 23;
      t.feed(stream.substr(pos, n));
      pos += n;
      drain(t, pieces);
    }
  }
  require(whole.messages == pieces.messages);
  require(whole.errors == pieces.errors);
  for (const auto& m : whole.messages) check_message(m, max_length);
  return 0;
}
