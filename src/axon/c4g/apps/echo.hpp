// `echo` (mode 0', the maker's communication test): the PC returns the controller's target position
// and velocity (D1, D2) unchanged, without processing them. In any other mode the server's safe reply
// goes out. Counts the cycles echoed.
#pragma once

#include "axon/c4g/apps/app.hpp"

namespace axon::c4g::apps {

class EchoApp final : public App {
 public:
  [[nodiscard]] std::string_view name() const noexcept override { return "echo"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  [[nodiscard]] std::uint64_t echoed() const noexcept { return echoed_.load(std::memory_order_relaxed); }

 protected:
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;

 private:
  std::atomic<std::uint64_t> echoed_{0};
};

}  // namespace axon::c4g::apps
