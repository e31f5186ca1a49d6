// Fuzzes the web server's request path: arbitrary bytes parsed as one HTTP request with the
// server's limits (Beast's parser), then routed (router.hpp) over a source with a published state
// and metrics. Nothing may crash; every answer must be a complete HTTP response (in the request's
// version, 1.0 or 1.1), and a request the parser rejects must be answered 400 and counted.
#include "axon/web/router.hpp"
#include "axon/web/server.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

axon::web::Router& router() {
  // Pages from a folder that need not exist: file routes answer 404, never read elsewhere.
  static auto* r = [] {
    auto* made = new axon::web::Router("/nonexistent/axon-web-fuzz");
    auto source = std::make_shared<axon::web::Source>("fps", "fuzz", "fps");
    source->set_info("{\"robots\":[]}");
    source->publish("{\"robots\":[]}");
    source->publish_metrics("# HELP axon_fuzz_total F\n# TYPE axon_fuzz_total counter\naxon_fuzz_total 1\n");
    made->add(source);
    return made;
  }();
  return *r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  axon::web::ServerStats stats;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto answer = axon::web::answer_raw_request(router(), bytes, stats);
  require(answer.starts_with("HTTP/1.1 ") || answer.starts_with("HTTP/1.0 "));
  require(answer.find("\r\n\r\n") != std::string::npos);
  require(stats.requests == 1);
  require(stats.bad_requests == 0 || answer.starts_with("HTTP/1.1 400 "));
  return 0;
}
