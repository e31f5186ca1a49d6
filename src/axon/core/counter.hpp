// Statistics counters that one thread increments and others read: relaxed atomics are enough,
// because readers only want a recent value, never an ordering with other memory.
#pragma once

#include <atomic>
#include <cstdint>

namespace axon::core {

inline void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

}  // namespace axon::core
