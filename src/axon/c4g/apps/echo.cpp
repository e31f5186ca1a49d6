#include "axon/c4g/apps/echo.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

namespace axon::c4g::apps {

void EchoApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  bool any = false;
  for (std::size_t i = 0; i < ctx.request.count; ++i) {
    const auto& q = ctx.request.axes[i];
    if (q.mode != protocol::code(protocol::Mode::mode0_prime)) continue;
    auto& r = reply.axis(i);
    r.mode = q.mode;
    r.d1 = q.d1;
    r.d2 = q.d2;
    any = true;
  }
  if (any) echoed_.fetch_add(1, std::memory_order_relaxed);
}

std::string EchoApp::status() const { return App::status() + fmt::format(" echoed {}", echoed()); }

std::string EchoApp::summary() const { return App::summary() + fmt::format("echo: {} cycles echoed in mode 0'\n", echoed()); }

}  // namespace axon::c4g::apps
