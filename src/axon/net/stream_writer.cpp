#include "axon/net/stream_writer.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/write.hpp>

namespace axon::net {

StreamWriter::StreamWriter(Socket& socket)
    : socket_(socket), progress_(socket.get_executor(), asio::steady_timer::time_point::max()) {}

void StreamWriter::write(std::string_view text, std::size_t units, std::shared_ptr<void> keep_alive) {
  if (error_) return;
  queued_.append(text);
  queued_units_ += units;
  if (!running_) {
    running_ = true;
    asio::co_spawn(socket_.get_executor(), run(std::move(keep_alive)), asio::detached);
  }
}

asio::awaitable<void> StreamWriter::run(std::shared_ptr<void> keep_alive) {
  while (!queued_.empty() && !error_) {
    in_flight_.swap(queued_);
    in_flight_units_ = queued_units_;
    queued_.clear();
    queued_units_ = 0;
    boost::system::error_code ec;
    co_await asio::async_write(socket_, asio::buffer(in_flight_), asio::redirect_error(asio::use_awaitable, ec));
    in_flight_.clear();
    in_flight_units_ = 0;
    if (ec && !error_) error_ = ec;
    progress_.cancel();
  }
  if (error_) {
    queued_.clear();
    queued_units_ = 0;
  }
  running_ = false;
  progress_.cancel();
  (void)keep_alive;
}

asio::awaitable<void> StreamWriter::wait_until_at_most(std::size_t bytes) {
  while (pending_bytes() > bytes && !error_) {
    boost::system::error_code ec;
    co_await progress_.async_wait(asio::redirect_error(asio::use_awaitable, ec));
  }
}

void StreamWriter::stop() {
  if (!error_) error_ = asio::error::operation_aborted;
  queued_.clear();
  queued_units_ = 0;
  progress_.cancel();
}

}  // namespace axon::net
