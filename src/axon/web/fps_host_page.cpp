#include "axon/web/fps_host_page.hpp"

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/core/wakeup.hpp"
#include "axon/fps/host/client.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <boost/asio/co_spawn.hpp>

#include <thread>

namespace axon::web {
namespace fps_host_page {

// A read round waits for silent robots at most the reply timeout; a view still reading after this
// long is said in the log (and still waited for: it reads the array the client is about to close).
constexpr auto kSlowRound = std::chrono::seconds(5);
constexpr auto kPoll = std::chrono::milliseconds(5);

HostReading reading_for(fps::BusUse use) {
  switch (use) {
    case fps::BusUse::shared: return HostReading::all;
    case fps::BusUse::moving: return HostReading::positions;
    case fps::BusUse::exclusive: return HostReading::none;
  }
  return HostReading::none;
}

// Polls `ask` (run on the client's loop) until it says true; warns once after kSlowRound.
void wait_on_loop(fps::Client& client, const std::function<bool()>& ask, std::string_view what) {
  const auto start = std::chrono::steady_clock::now();
  bool warned = false;
  for (;;) {
    bool yes = false;
    client.with_loop([&](fps::host::FocalPlaneArray*, boost::asio::io_context&) { yes = ask(); });
    if (yes) return;
    if (!warned && std::chrono::steady_clock::now() - start > kSlowRound) {
      spdlog::warn("fps page: still waiting for {} after {} s", what, kSlowRound.count());
      warned = true;
    }
    std::this_thread::sleep_for(kPoll);
  }
}

}  // namespace fps_host_page

struct FpsHostPage::State {
  std::shared_ptr<Source> source;
  std::unique_ptr<FpsHostView> view;
  std::shared_ptr<bool> alive = std::make_shared<bool>(true);
  bool done = false;
};

namespace fps_host_page {

// No try block and no temporaries around the co_await: gcc 12 has destroyed such locals twice in
// coroutines (a shared_ptr's count then runs out early). The end and any exception come to
// co_spawn's completion handler instead.
boost::asio::awaitable<void> serve(std::shared_ptr<FpsHostPage::State> s, FpsHostPageOptions o) {
  co_await s->view->run(*s->source, o.publish_period, o.read_period, s->alive);
}

}  // namespace fps_host_page

FpsHostPage::FpsHostPage(FpsHostPageOptions o, fps::host::FocalPlaneArray& array, boost::asio::any_io_executor ex)
    : state_(std::make_shared<State>()) {
  o.server.push_period = o.publish_period;
  const auto title = o.title.empty() ? fmt::format("fps: host view of '{}'", array.plane().name()) : o.title;
  state_->view = std::make_unique<FpsHostView>(array);
  state_->source = std::make_shared<Source>("fps", title, "fps");
  state_->source->set_info(state_->view->info_json());
  server_ = std::make_unique<Server>(o.server);
  server_->add(state_->source);
  boost::asio::co_spawn(ex, fps_host_page::serve(state_, o), [s = state_](std::exception_ptr e) {
    if (e) {
      try {
        std::rethrow_exception(e);
      } catch (const std::exception& x) {
        spdlog::error("fps page: the view stopped: {}", x.what());
      }
    }
    s->done = true;
  });
}

FpsHostPage::~FpsHostPage() { stop(); }

FpsHostView& FpsHostPage::view() noexcept { return *state_->view; }
std::string FpsHostPage::where() const { return fmt::format("{}:{}", server_->address(), server_->port()); }
void FpsHostPage::stop() noexcept { *state_->alive = false; }
bool FpsHostPage::done() const noexcept { return state_->done; }

boost::asio::awaitable<void> FpsHostPage::finish() {
  stop();
  while (!state_->done) co_await core::sleep_for(std::chrono::milliseconds(10));
}

FpsClientPage::FpsClientPage(FpsHostPageOptions options, fps::Client& client) : client_(client) {
  client_.with_loop([&](fps::host::FocalPlaneArray* array, boost::asio::io_context& io) {
    if (!array)
      throw Exception(Error(CoreErrc::invalid_argument,
                            "the fps page needs the plane's layout to draw it: open the client from a layout, not "
                            "from bus names alone"));
    page_ = std::make_unique<FpsHostPage>(std::move(options), *array, io.get_executor());
  });
}

FpsClientPage::~FpsClientPage() {
  try {
    client_.with_loop([this](fps::host::FocalPlaneArray*, boost::asio::io_context&) { page_->stop(); });
    fps_host_page::wait_on_loop(client_, [this] { return page_->done(); }, "the view's last read round");
    client_.with_loop([this](fps::host::FocalPlaneArray*, boost::asio::io_context&) { page_.reset(); });
  } catch (const std::exception& e) {
    spdlog::error("fps page: ending the view: {}", e.what());
  }
}

void FpsClientPage::bus_use(fps::BusUse use) {
  const auto mode = fps_host_page::reading_for(use);
  client_.with_loop([&](fps::host::FocalPlaneArray*, boost::asio::io_context&) { page_->view().set_reading(mode); });
  if (mode == HostReading::none)
    fps_host_page::wait_on_loop(client_, [this] { return !page_->view().reading_now(); }, "a read round to end");
}

std::string FpsClientPage::where() const { return page_->where(); }

}  // namespace axon::web
