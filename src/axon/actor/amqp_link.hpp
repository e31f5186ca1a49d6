// AmqpLink: one connection to an AMQP 0-9-1 broker (RabbitMQ), on a thread of its own (an ordinary
// thread, never a real-time one), over Debian's librabbitmq. It declares the topic exchange and,
// when asked, a queue with its bindings and consumes it; it publishes what any thread hands it.
//
// When the broker goes away the link tears the connection down and reconnects with back-off
// (LinkConfig::backoff_min_s doubling up to backoff_max_s), declaring everything again: a restarted
// broker is rejoined without restarting the program. Messages published meanwhile wait in a bounded
// outbox and go out on reconnection (the oldest are dropped, and counted, when it is full).
//
// Callbacks run on the link's thread: they must return quickly and must not wait for the link.
// The constructor throws axon::Exception (CoreErrc::io) when it cannot start; the destructor stops
// the thread and closes the connection, and never throws. librabbitmq's
// headers stay inside amqp_link.cpp.
#pragma once

#include "axon/actor/message.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace axon::actor {

struct LinkConfig {
  std::string host = "127.0.0.1";
  std::uint16_t port = 5672;
  std::string user = "guest";
  std::string password = "guest";
  std::string vhost = "/";
  std::string exchange{kDefaultExchange};
  std::string queue;                  // empty: publish only
  std::vector<std::string> bindings;  // routing keys the queue is bound to
  int heartbeat_s = 5;
  double connect_timeout_s = 2.0;    // TCP connect, login, each declaration
  double backoff_min_s = 0.1;
  double backoff_max_s = 2.0;
  std::size_t outbox_limit = 10000;
  bool mandatory = false;             // ask the broker to return messages no queue takes
};

struct LinkCounters {
  std::uint64_t connects = 0;       // connections made (1 + reconnections)
  std::uint64_t connect_failures = 0;
  std::uint64_t received = 0;
  std::uint64_t published = 0;
  std::uint64_t dropped = 0;        // outbox overflow (the oldest message goes)
  std::uint64_t returned = 0;       // unroutable (mandatory) messages the broker gave back
};

class AmqpLink {
 public:
  struct Callbacks {
    std::function<void(Message)> on_message;        // a delivery on the queue
    std::function<void(Message)> on_returned;       // a mandatory message no queue took
    std::function<void(bool connected, const std::string& why)> on_state;
  };

  AmqpLink(LinkConfig config, Callbacks callbacks);  // starts the thread; connects in the background
  ~AmqpLink();
  AmqpLink(const AmqpLink&) = delete;
  AmqpLink& operator=(const AmqpLink&) = delete;

  // From any thread: queued, sent by the link's thread (after reconnection when disconnected).
  void publish(Message message);
  [[nodiscard]] bool connected() const noexcept;
  [[nodiscard]] LinkCounters counters() const;
  // Ends the thread and closes the connection (what is still in the outbox is sent first when
  // connected). Idempotent.
  void stop() noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::actor
