#include "axon/web/live_page.hpp"

#include "axon/core/error.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>


namespace axon::web {

LivePage::LivePage(const ServerOptions& server, std::shared_ptr<Source> source)
    : server_(std::make_unique<Server>(server)), source_(std::move(source)) {
  server_->add(source_);
}

LivePage::~LivePage() { stop(); }

std::string LivePage::where() const { return fmt::format("{}:{}", server_->address(), server_->port()); }

void LivePage::start(std::chrono::milliseconds period, std::function<void(unsigned)> tick) {
  tick_ = std::move(tick);
  thread_ = std::thread([this, period] { loop(period); });
}

void LivePage::feed(const std::function<void()>& f) {
  std::lock_guard lock(mutex_);
  f();
}

void LivePage::loop(std::chrono::milliseconds period) {
  unsigned n = 0;
  std::unique_lock wake_lock(wake_mutex_);
  for (bool last = false; !last;) {
    last = wake_.wait_for(wake_lock, period, [this] { return stopping_; });
    wake_lock.unlock();
    try {
      std::lock_guard lock(mutex_);
      tick_(++n);
    } catch (const std::exception& e) {
      spdlog::warn("web page: {}", e.what());
    }
    wake_lock.lock();
  }
}

void LivePage::stop() noexcept {
  {
    std::lock_guard lock(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (server_) server_->stop();
}

// ---- BlmcPage -----------------------------------------------------------------------------------

BlmcPage::BlmcPage(BlmcPageOptions options)
    : view_(options.view),
      page_(options.server, std::make_shared<Source>("blmc", options.title, "blmc")) {
  page_.source().set_info(view_.info_json());
  view_.publish(page_.source(), 1);
  const unsigned every = std::max(1u, options.publish_every);
  page_.start(options.period, [this, every, sample = std::move(options.sample)](unsigned n) {
    if (sample) sample(view_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    if (n % every == 0) view_.publish(page_.source());
  });
}

BlmcPage::~BlmcPage() { page_.stop(); }

void BlmcPage::add_measurements(std::size_t board, const blmc::host::Measurements& m) {
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  page_.feed([this, board, t, &m] { view_.add_measurements(board, t, m); });
}

// ---- C4gPage ------------------------------------------------------------------------------------

C4gPage::C4gPage(const ServerOptions& server, const c4g::apps::App& app, const c4g::host::Server& c4g_server,
                 C4gViewOptions view, std::string title)
    : view_(app, c4g_server, std::move(view)), page_(server, std::make_shared<Source>("c4g", std::move(title), "c4g")) {
  page_.source().set_info(view_.info_json());
  view_.publish(page_.source(), 1);
  page_.start(std::chrono::milliseconds(100), [this](unsigned) { view_.publish(page_.source(), 10); });
}

C4gPage::~C4gPage() { page_.stop(); }

void C4gPage::add_event(const c4g::apps::Event& event, const std::string& text) {
  page_.feed([this, &event, &text] { view_.add_event(event, text); });
}

}  // namespace axon::web
