// The fps page of a host that drives a focal plane (web::FpsHostView on a web::Server):
//
//   - FpsHostPage: over a host::FocalPlaneArray on its executor (`axon fps plane --http`). The
//     server runs on a thread of its own; the view reads the robots and publishes on the array's
//     executor, 10 updates a second and a read round at most 4 times a second.
//   - FpsClientPage: over the plane a blocking fps::Client opened (the fps actor's --http). The
//     view lives on the client's loop thread (Client::with_loop). bus_use() tells it what the
//     client's next call does with the buses, so that its reads never meet an upload, a discovery,
//     a firmware upgrade or a measurement: shared -> it reads everything, moving -> positions only
//     (the move polls the status words itself), exclusive -> nothing, after waiting for a round
//     under way to end.
//
// Lifetimes: the view reads the array, so a page ends before the array closes: FpsHostPage through
// finish() on the array's executor, FpsClientPage in its destructor (it waits for the view).
// Errors: the constructors throw axon::Exception as web::Server does (a port in use); an
// FpsClientPage over a client opened from bus names alone (no layout to draw) is refused with
// CoreErrc::invalid_argument.
#pragma once

#include "axon/web/fps_host_view.hpp"
#include "axon/web/server.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <utility>  // before asio's awaitable.hpp, which uses std::exchange

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>

namespace axon::fps {
class Client;
enum class BusUse;
}  // namespace axon::fps

namespace axon::web {

struct FpsHostPageOptions {
  ServerOptions server;                          // server_address() reads --http's HOST:PORT
  std::string title;                             // "" : "fps: host view of '<plane>'"
  std::chrono::milliseconds publish_period{100};  // the page: 10 updates a second
  std::chrono::milliseconds read_period{250};     // a read round at most 4 times a second
};

class FpsHostPage {
 public:
  // On the array's executor `ex`, from its thread: the view starts reading there at once.
  FpsHostPage(FpsHostPageOptions options, fps::host::FocalPlaneArray& array, boost::asio::any_io_executor ex);
  ~FpsHostPage();
  FpsHostPage(const FpsHostPage&) = delete;
  FpsHostPage& operator=(const FpsHostPage&) = delete;

  // The view, on the array's executor only (set_reading around operations).
  [[nodiscard]] FpsHostView& view() noexcept;
  [[nodiscard]] std::string where() const;  // HOST:PORT as listening
  // The view ends after its current round (on the executor; returns at once).
  void stop() noexcept;
  [[nodiscard]] bool done() const noexcept;  // the view's run is over (on the executor)
  // stop(), then until the view's run is over: before the array closes.
  boost::asio::awaitable<void> finish();

  struct State;

 private:
  std::unique_ptr<Server> server_;
  std::shared_ptr<State> state_;  // shared with the view's run, which may outlast the page
};

class FpsClientPage {
 public:
  // From any thread but the client's loop; the client stays open until the page is gone.
  FpsClientPage(FpsHostPageOptions options, fps::Client& client);
  ~FpsClientPage();  // ends the view on the client's loop and waits for it
  FpsClientPage(const FpsClientPage&) = delete;
  FpsClientPage& operator=(const FpsClientPage&) = delete;

  // What the client's next calls do with the buses (see above); from any thread but the loop's.
  void bus_use(fps::BusUse use);
  [[nodiscard]] std::string where() const;

 private:
  fps::Client& client_;
  std::unique_ptr<FpsHostPage> page_;
};

}  // namespace axon::web
