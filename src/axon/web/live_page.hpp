// The --http page of a long-running process that is not itself an event loop the view could live
// on (the actors, `axon sim blmc`): a web::Server of its own thread, one Source and a view,
// published from a thread of the page's own, never from a real-time one.
//
//   - LivePage: the server, the source, a lock and the publishing thread. Every `period` it runs
//     the owner's tick under the lock (sample, publish); feed() runs the owner's code under the same
//     lock from any other thread (an actor's watcher handing over what it read).
//   - BlmcPage: a web::BlmcView on a LivePage, fed measurements (BlmcActorOptions::on_board_read,
//     or a sampler such as the simulator's truth).
//   - C4gPage: a web::C4gView on a LivePage, fed the app switch's events (C4gActorOptions::on_event).
//
// Errors: the constructors throw axon::Exception as web::Server does (an address that does not
// parse, a port in use). The destructors stop and never throw.
#pragma once

#include "axon/web/blmc_view.hpp"
#include "axon/web/c4g_view.hpp"
#include "axon/web/server.hpp"

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace axon::web {

class LivePage {
 public:
  LivePage(const ServerOptions& server, std::shared_ptr<Source> source);
  ~LivePage();
  LivePage(const LivePage&) = delete;
  LivePage& operator=(const LivePage&) = delete;

  // Starts the publishing thread: tick(n) every `period` under the lock, n = 1, 2, ...
  void start(std::chrono::milliseconds period, std::function<void(unsigned)> tick);
  // f() under the lock, from any thread but the page's.
  void feed(const std::function<void()>& f);
  // Ends the thread (a last tick first) and the server. Idempotent.
  void stop() noexcept;

  [[nodiscard]] Server& server() noexcept { return *server_; }
  [[nodiscard]] Source& source() noexcept { return *source_; }
  [[nodiscard]] std::string where() const;  // HOST:PORT as listening

 private:
  void loop(std::chrono::milliseconds period);

  std::unique_ptr<Server> server_;
  std::shared_ptr<Source> source_;
  std::mutex mutex_;  // the view's, between the tick and feed()
  std::function<void(unsigned)> tick_;
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

struct BlmcPageOptions {
  ServerOptions server;
  BlmcViewOptions view;
  std::string title;
  std::chrono::milliseconds period{100};     // the tick
  unsigned publish_every = 1;                // ticks per publish (the metrics every 10th publish)
  std::function<void(BlmcView&, double t_s)> sample{};  // each tick, seconds since the start (empty: none)
};

class BlmcPage {
 public:
  explicit BlmcPage(BlmcPageOptions options);
  ~BlmcPage();
  // Board `board`'s measurements as read now (any thread but the page's).
  void add_measurements(std::size_t board, const blmc::host::Measurements& m);
  void stop() noexcept { page_.stop(); }
  [[nodiscard]] std::string where() const { return page_.where(); }

 private:
  BlmcView view_;
  LivePage page_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

class C4gPage {
 public:
  C4gPage(const ServerOptions& server, const c4g::apps::App& app, const c4g::host::Server& c4g_server,
          C4gViewOptions view, std::string title);
  ~C4gPage();
  // Each event of the app, in order (any thread but the page's).
  void add_event(const c4g::apps::Event& event, const std::string& text);
  void stop() noexcept { page_.stop(); }
  [[nodiscard]] std::string where() const { return page_.where(); }

 private:
  C4gView view_;
  LivePage page_;
};


}  // namespace axon::web
