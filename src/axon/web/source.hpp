// web::Source: one thing a process shows on its web server (a simulated focal plane, a motor board,
// a c4g server), as a name, a page and the latest state the owner published.
//
// The owner publishes from its own thread (an event loop's timer; a real-time loop hands its data
// to such a thread first, never publishes from the cycle): the state as a JSON object, often (the
// pages want 5-10 updates a second), and its metrics as Prometheus text (metrics_text.hpp), as
// often as a scraper needs them (about once a second), both built by the owner. The server reads the
// latest snapshot from its thread and sends it to /api/state, /metrics and the WebSocket clients;
// nothing of the owner runs on the server's thread. publish() takes a mutex only to swap a pointer.
//
// What does not change while the process runs (a layout, the meaning of status bits) is set once
// with set_info() and served at /api/<name>/info, so the pushed state stays small.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

namespace axon::web {

struct Snapshot {
  std::uint64_t sequence = 0;  // 1 for the first publish(), then counting up
  std::string state;           // a JSON object
};

class Source {
 public:
  // `name`: lowercase letters, digits, '_' and '-' (it appears in URLs and messages); the page is
  // <page>.html in the assets folder (empty: no page). Throws axon::Exception
  // (CoreErrc::invalid_argument) for a bad name.
  Source(std::string name, std::string title, std::string page = {});

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] const std::string& title() const noexcept { return title_; }
  [[nodiscard]] const std::string& page() const noexcept { return page_; }

  // Any thread.
  void set_info(std::string json);
  [[nodiscard]] std::string info() const;  // "{}" until set
  void publish(std::string state_json);
  // Whole metric families (HELP, TYPE, samples), replacing the previous ones.
  void publish_metrics(std::string metrics);
  // nullptr until the first publish() / publish_metrics().
  [[nodiscard]] std::shared_ptr<const Snapshot> latest() const;
  [[nodiscard]] std::shared_ptr<const std::string> metrics() const;

 private:
  std::string name_;
  std::string title_;
  std::string page_;
  mutable std::mutex mutex_;
  std::string info_ = "{}";
  std::shared_ptr<const Snapshot> latest_;
  std::shared_ptr<const std::string> metrics_;
  std::uint64_t sequence_ = 0;
};

}  // namespace axon::web
