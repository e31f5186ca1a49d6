#include "axon/can/blocking_bus.hpp"

#include "axon/can/open.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/loop_thread.hpp"

#include <mutex>

namespace axon::can {

namespace {

using Seconds = std::chrono::duration<double>;
core::Duration duration_of(double s) { return std::chrono::duration_cast<core::Duration>(Seconds(s)); }

// The in-process virtual media that blocking buses reach (virtual:NAME): one medium per name, all
// on one loop, alive while a blocking bus holds them.
struct LocalMedia {
  core::LoopThread loop;
  std::unique_ptr<VirtualBusRegistry> registry;

  LocalMedia() {
    registry = loop.call([this] { return std::make_unique<VirtualBusRegistry>(loop.executor()); });
  }
  ~LocalMedia() {
    try {
      loop.call([this] { registry.reset(); });
    } catch (...) {
    }
  }

  static std::shared_ptr<LocalMedia> get() {
    static std::mutex mutex;
    static std::weak_ptr<LocalMedia> current;
    std::lock_guard lock(mutex);
    auto media = current.lock();
    if (!media) current = media = std::make_shared<LocalMedia>();
    return media;
  }
};

}  // namespace

struct BlockingBus::Impl {
  std::shared_ptr<LocalMedia> media;      // virtual buses: the process's media and their loop
  std::unique_ptr<core::LoopThread> own;  // every other bus: a loop of its own
  core::LoopThread* loop = nullptr;
  std::unique_ptr<Bus> bus;               // made, used and destroyed on *loop

  Bus& open_bus() const {
    if (!bus) throw Exception(Error(CanErrc::closed, "the bus was closed"));
    return *bus;
  }
};

BlockingBus::BlockingBus(const std::string& spec_text, BlockingBusOptions options) : impl_(std::make_unique<Impl>()) {
  const BusSpec spec = value_or_throw(parse_bus_spec(spec_text));
  auto& impl = *impl_;
  if (spec.kind == BusSpec::Kind::virtual_bus) {
    impl.media = LocalMedia::get();
    impl.loop = &impl.media->loop;
    auto* registry = impl.media->registry.get();
    impl.bus = impl.loop->call([registry, &spec, &options] {
      if (!registry->find(spec.channel)) value_or_throw(registry->add(spec.channel));
      return value_or_throw(registry->open(spec.channel, options.bus));
    });
    return;
  }
  impl.own = std::make_unique<core::LoopThread>();
  impl.loop = impl.own.get();
  OpenOptions o;
  o.bus = options.bus;
  o.connect_timeout = duration_of(options.connect_timeout_s);
  auto* loop = impl.loop;
  // LoopThread::run wants a coroutine whose value has a default: the error is thrown on the loop.
  impl.bus = loop->run(
      [loop, spec, o]() -> asio::awaitable<std::unique_ptr<Bus>> {
        auto opened = co_await can::open_bus(loop->executor(), spec, o);
        co_return value_or_throw(std::move(opened));
      },
      o.connect_timeout + std::chrono::seconds(5));
}

BlockingBus::~BlockingBus() { close(); }

void BlockingBus::close() noexcept {
  auto& impl = *impl_;
  if (!impl.bus) return;
  try {
    impl.loop->call([&impl] {
      impl.bus->close();
      impl.bus.reset();
    });
  } catch (...) {
  }
}

void BlockingBus::send(const Frame& frame) {
  auto& bus = impl_->open_bus();
  impl_->loop->run(
      [&bus, frame]() -> asio::awaitable<void> {
        auto sent = co_await bus.send(frame);
        value_or_throw(std::move(sent));
      },
      std::chrono::seconds(10));
}

std::optional<Frame> BlockingBus::receive(double timeout_s) {
  auto& bus = impl_->open_bus();
  if (!(timeout_s > 0)) {
    return impl_->loop->call([&bus]() -> std::optional<Frame> {
      if (auto f = bus.try_receive()) return f;
      if (!bus.is_open()) throw Exception(Error(CanErrc::closed, bus.name()));
      return std::nullopt;
    });
  }
  const auto timeout = duration_of(timeout_s);
  return impl_->loop->run(
      [&bus, timeout]() -> asio::awaitable<std::optional<Frame>> {
        auto r = co_await bus.receive(timeout);
        if (!r && r.error() == CanErrc::timeout) co_return std::nullopt;
        co_return value_or_throw(std::move(r));
      },
      timeout + std::chrono::seconds(5));
}

void BlockingBus::set_filters(std::vector<Filter> filters) {
  auto& bus = impl_->open_bus();
  impl_->loop->call([&bus, &filters] { bus.set_filters(std::move(filters)); });
}

std::string BlockingBus::name() const {
  auto& bus = impl_->open_bus();
  return bus.name();
}

BusStats BlockingBus::stats() const {
  auto& bus = impl_->open_bus();
  return impl_->loop->call([&bus] { return bus.stats(); });
}

BusState BlockingBus::state() const {
  if (!impl_->bus) return BusState::closed;
  auto& bus = *impl_->bus;
  return impl_->loop->call([&bus] { return bus.state(); });
}

bool BlockingBus::is_open() const { return state() != BusState::closed; }

}  // namespace axon::can
