#include "axon/core/deadline_queue.hpp"

#include <boost/asio/execution/context.hpp>
#include <boost/asio/query.hpp>

#include <algorithm>

namespace axon::core {

namespace asio = boost::asio;

DeadlineClient::~DeadlineClient() {
  if (queue_ != nullptr) queue_->forget(*this);
}

DeadlineQueue::DeadlineQueue(asio::execution_context& context) : asio::execution_context::service(context) {}

DeadlineQueue::~DeadlineQueue() { shutdown(); }

void DeadlineQueue::shutdown() {
  // Clients that outlive the context must not call back into it.
  for (auto& e : heap_) {
    e.client->queue_ = nullptr;
    e.client->entries_ = 0;
  }
  heap_.clear();
  timer_.reset();
}

DeadlineQueue& DeadlineQueue::of(const asio::any_io_executor& executor) {
  auto& context = asio::query(executor, asio::execution::context);
  auto& q = asio::use_service<DeadlineQueue>(context);
  if (!q.timer_) q.timer_.emplace(executor);
  return q;
}

void DeadlineQueue::arm(DeadlineClient& c, TimePoint at) {
  if (c.queue_ != nullptr && c.queue_ != this) c.queue_->forget(c);
  c.queue_ = this;
  ++c.entries_;
  ++c.generation_;
  c.armed_ = at;
  heap_.push_back(Entry{at, next_seq_++, c.generation_, &c});
  std::push_heap(heap_.begin(), heap_.end(), later);
  // While firing, the loop itself looks at the new deadline (and arms the timer at the end).
  if (!firing_ && at < waiting_for_ - slack_) wait_for(at);
}

void DeadlineQueue::disarm(DeadlineClient& c) noexcept {
  if (c.queue_ != this) return;
  ++c.generation_;  // its entry becomes stale; the timer may fire for nothing once
  c.armed_ = TimePoint::max();
}

void DeadlineQueue::forget(DeadlineClient& c) noexcept {
  const auto n = heap_.size();
  heap_.erase(std::remove_if(heap_.begin(), heap_.end(), [&c](const Entry& e) { return e.client == &c; }), heap_.end());
  if (heap_.size() != n) std::make_heap(heap_.begin(), heap_.end(), later);
  c.queue_ = nullptr;
  c.entries_ = 0;
  c.armed_ = TimePoint::max();
}

void DeadlineQueue::wait_for(TimePoint at) {
  if (!timer_) return;
  const TimePoint until = at < TimePoint::max() - slack_ ? at + slack_ : TimePoint::max();
  waiting_for_ = until;
  ++waits_;
  timer_->expires_at(until);  // cancels an earlier wait, whose handler then does nothing
  timer_->async_wait([this](const boost::system::error_code& ec) {
    if (ec == asio::error::operation_aborted) return;
    fire();
  });
}

void DeadlineQueue::fire() {
  waiting_for_ = TimePoint::max();
  firing_ = true;
  TimePoint now = std::chrono::steady_clock::now();
  while (!heap_.empty()) {
    if (heap_.front().at > now) {
      now = std::chrono::steady_clock::now();  // handlers take time: look again before sleeping
      if (heap_.front().at > now) break;
    }
    std::pop_heap(heap_.begin(), heap_.end(), later);
    const Entry e = heap_.back();
    heap_.pop_back();
    if (--e.client->entries_ == 0) e.client->queue_ = nullptr;
    if (e.generation != e.client->generation_) continue;  // re-armed or disarmed since
    e.client->armed_ = TimePoint::max();
    e.client->on_deadline();  // may arm again or destroy the client: e.client is not touched after
  }
  firing_ = false;
  if (!heap_.empty()) wait_for(heap_.front().at);
}

}  // namespace axon::core
