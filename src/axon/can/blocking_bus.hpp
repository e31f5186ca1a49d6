// axon::can::BlockingBus: one CAN bus from a plain program (or Python), without Asio. It opens any
// bus spec (can/bus_spec.hpp) on an event loop of its own thread (core::LoopThread); send() and
// receive() block until done. `virtual:NAME` opens a node of the in-process medium NAME, shared by
// every BlockingBus of the process that names it (those run on one loop, the media's), which
// exists while one of them is open: two buses on "virtual:vcan0" see each other's frames.
//
//   axon::can::BlockingBus bus("socketcand://127.0.0.1:29536/vcan0");
//   bus.send(axon::can::Frame::parse("123#DEADBEEF").value());
//   if (auto f = bus.receive(1.0)) std::puts(f->to_string().c_str());
//
// Errors: throws axon::Exception with a CanErrc code (bad_spec, connect_failed, closed, ...) or
// a net code; a receive that times out is not an error (nullopt). Threading: one thread at a time.
// The destructor closes the bus and never throws.
#pragma once

#include "axon/can/bus.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::can {

struct BlockingBusOptions {
  BusOptions bus{};
  double connect_timeout_s = 5.0;
};

class BlockingBus {
 public:
  explicit BlockingBus(const std::string& spec, BlockingBusOptions options = {});
  ~BlockingBus();
  BlockingBus(const BlockingBus&) = delete;
  BlockingBus& operator=(const BlockingBus&) = delete;

  // Waits until the transport took the frame (queued for the wire or written to the socket).
  void send(const Frame& frame);
  // The next frame that passes the filters, waiting at most timeout_s (0: only a frame already
  // queued); nullopt when none came. Errors: closed.
  std::optional<Frame> receive(double timeout_s);
  void set_filters(std::vector<Filter> filters);

  [[nodiscard]] std::string name() const;
  [[nodiscard]] BusStats stats() const;
  [[nodiscard]] BusState state() const;
  [[nodiscard]] bool is_open() const;
  // Closes the transport; frames already queued can still be received. Idempotent.
  void close() noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::can
