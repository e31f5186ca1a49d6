#include "axon/actor/bus_actor.hpp"

namespace axon::actor {

BusActor::BusActor(BusActorConfig config)
    : config_(std::move(config)), core_(config_.name, [this](Message m) {
        if (auto* link = live_.load()) link->publish(std::move(m));
      }) {
  config_.link.queue = config_.name + "_commands";
  config_.link.bindings = {command_binding(config_.name)};
}

BusActor::~BusActor() {
  core_.wait_idle();
  if (link_) link_->stop();
  live_ = nullptr;
}

void BusActor::on_state(std::function<void(bool)> f) { on_state_ = std::move(f); }

void BusActor::start() {
  if (link_) return;
  AmqpLink::Callbacks callbacks;
  callbacks.on_message = [this](Message m) { core_.handle(m); };
  callbacks.on_state = [this](bool up, const std::string&) {
    if (on_state_) on_state_(up);
  };
  link_ = std::make_unique<AmqpLink>(config_.link, std::move(callbacks));
  live_ = link_.get();
}

bool BusActor::connected() const noexcept { return link_ && link_->connected(); }

LinkCounters BusActor::link_counters() const { return link_ ? link_->counters() : LinkCounters{}; }

}  // namespace axon::actor
