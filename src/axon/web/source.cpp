#include "axon/web/source.hpp"

#include "axon/core/error.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace axon::web {

Source::Source(std::string name, std::string title, std::string page)
    : name_(std::move(name)), title_(std::move(title)), page_(std::move(page)) {
  const bool ok = !name_.empty() && std::all_of(name_.begin(), name_.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
  if (!ok) throw Exception(Error(CoreErrc::invalid_argument, fmt::format("web source name '{}': use a-z, 0-9, '_' and '-'", name_)));
}

void Source::set_info(std::string json) {
  std::lock_guard lock(mutex_);
  info_ = std::move(json);
}

std::string Source::info() const {
  std::lock_guard lock(mutex_);
  return info_;
}

void Source::publish(std::string state_json) {
  // Built outside the lock; the lock only swaps the pointer (the old snapshot lives on while a
  // reader still sends it).
  auto next = std::make_shared<Snapshot>();
  next->state = std::move(state_json);
  std::lock_guard lock(mutex_);
  next->sequence = ++sequence_;
  latest_ = std::move(next);
}

void Source::publish_metrics(std::string metrics) {
  auto next = std::make_shared<const std::string>(std::move(metrics));
  std::lock_guard lock(mutex_);
  metrics_ = std::move(next);
}

std::shared_ptr<const std::string> Source::metrics() const {
  std::lock_guard lock(mutex_);
  return metrics_;
}

std::shared_ptr<const Snapshot> Source::latest() const {
  std::lock_guard lock(mutex_);
  return latest_;
}

}  // namespace axon::web
