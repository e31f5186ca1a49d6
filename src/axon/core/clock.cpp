#include "axon/core/clock.hpp"

namespace axon::core {

SteadyClock& SteadyClock::instance() noexcept {
  static SteadyClock c;
  return c;
}

}  // namespace axon::core
