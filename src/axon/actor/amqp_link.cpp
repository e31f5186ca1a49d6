// AmqpLink over librabbitmq. The connection belongs to the link's thread alone (librabbitmq is not
// thread-safe): other threads hand messages over through the outbox and wake the thread with an
// eventfd, which it polls together with the broker's socket.
#include "axon/actor/amqp_link.hpp"
#include "axon/core/error.hpp"

#include <amqp.h>
#include <amqp_tcp_socket.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace axon::actor {
namespace {

constexpr amqp_channel_t kChannel = 1;
constexpr int kIdlePollMs = 250;  // heartbeats are sent from the consume call that follows a poll

amqp_bytes_t bytes_of(const std::string& s) { return amqp_bytes_t{s.size(), const_cast<char*>(s.data())}; }
std::string string_of(amqp_bytes_t b) { return {static_cast<const char*>(b.bytes), b.len}; }

timeval timeval_of(double s) {
  const double whole = std::floor(s);
  return timeval{static_cast<time_t>(whole), static_cast<suseconds_t>((s - whole) * 1e6)};
}

std::string rpc_error(const amqp_rpc_reply_t& r, const char* what) {
  switch (r.reply_type) {
    case AMQP_RESPONSE_NORMAL: return {};
    case AMQP_RESPONSE_NONE: return fmt::format("{}: no reply", what);
    case AMQP_RESPONSE_LIBRARY_EXCEPTION: return fmt::format("{}: {}", what, amqp_error_string2(r.library_error));
    case AMQP_RESPONSE_SERVER_EXCEPTION:
      if (r.reply.id == AMQP_CONNECTION_CLOSE_METHOD || r.reply.id == AMQP_CHANNEL_CLOSE_METHOD) {
        const auto* m = static_cast<const amqp_connection_close_t*>(r.reply.decoded);
        return fmt::format("{}: broker closed: {} {}", what, m->reply_code, string_of(m->reply_text));
      }
      return fmt::format("{}: broker error (method 0x{:08x})", what, r.reply.id);
  }
  return fmt::format("{}: unknown failure", what);
}

HeaderValue header_value(const amqp_field_value_t& v) {
  switch (v.kind) {
    case AMQP_FIELD_KIND_UTF8:
    case AMQP_FIELD_KIND_BYTES: return string_of(v.value.bytes);
    case AMQP_FIELD_KIND_BOOLEAN: return v.value.boolean != 0;
    case AMQP_FIELD_KIND_I8: return std::int64_t{v.value.i8};
    case AMQP_FIELD_KIND_U8: return std::int64_t{v.value.u8};
    case AMQP_FIELD_KIND_I16: return std::int64_t{v.value.i16};
    case AMQP_FIELD_KIND_U16: return std::int64_t{v.value.u16};
    case AMQP_FIELD_KIND_I32: return std::int64_t{v.value.i32};
    case AMQP_FIELD_KIND_U32: return std::int64_t{v.value.u32};
    case AMQP_FIELD_KIND_I64: return std::int64_t{v.value.i64};
    case AMQP_FIELD_KIND_U64: return static_cast<std::int64_t>(v.value.u64);
    default: return std::monostate{};
  }
}

Message message_of(const amqp_basic_properties_t& p, amqp_bytes_t body, std::string routing_key) {
  Message m;
  m.routing_key = std::move(routing_key);
  m.body = string_of(body);
  if (p._flags & AMQP_BASIC_HEADERS_FLAG)
    for (int i = 0; i < p.headers.num_entries; ++i)
      m.headers[string_of(p.headers.entries[i].key)] = header_value(p.headers.entries[i].value);
  if (p._flags & AMQP_BASIC_CORRELATION_ID_FLAG) m.correlation_id = string_of(p.correlation_id);
  if (p._flags & AMQP_BASIC_REPLY_TO_FLAG) m.reply_to = string_of(p.reply_to);
  if (p._flags & AMQP_BASIC_CONTENT_TYPE_FLAG) m.content_type = string_of(p.content_type);
  return m;
}

amqp_field_value_t field_of(const HeaderValue& v) {
  amqp_field_value_t f{};
  if (const auto* s = std::get_if<std::string>(&v)) {
    f.kind = AMQP_FIELD_KIND_UTF8;
    f.value.bytes = bytes_of(*s);
  } else if (const auto* i = std::get_if<std::int64_t>(&v)) {
    f.kind = AMQP_FIELD_KIND_I64;
    f.value.i64 = *i;
  } else if (const auto* b = std::get_if<bool>(&v)) {
    f.kind = AMQP_FIELD_KIND_BOOLEAN;
    f.value.boolean = *b ? 1 : 0;
  } else {
    f.kind = AMQP_FIELD_KIND_VOID;
  }
  return f;
}

}  // namespace

struct AmqpLink::Impl {
  LinkConfig config;
  Callbacks callbacks;
  int wake_fd = -1;
  std::atomic<bool> stopping{false};
  std::atomic<bool> is_connected{false};
  mutable std::mutex mutex;  // outbox and counters
  std::deque<Message> outbox;
  LinkCounters counts;
  amqp_connection_state_t conn = nullptr;
  std::thread thread;

  void wake() const noexcept {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(wake_fd, &one, sizeof one);
  }

  void run() noexcept {
    double backoff = config.backoff_min_s;
    while (!stopping) {
      std::string why;
      try {
        connect();
        backoff = config.backoff_min_s;
        set_state(true, "connected");
        serve();
        why = "stopped";
      } catch (const std::exception& e) {
        why = e.what();
      }
      const bool was_connected = is_connected.exchange(false);
      drop_connection();
      if (was_connected) set_state(false, why);
      else count_failure(why);
      if (stopping) break;
      wait_wake(backoff);
      backoff = std::min(backoff * 2, config.backoff_max_s);
    }
    drop_connection();
  }

  void count_failure(const std::string& why) {
    std::uint64_t n = 0;
    {
      std::lock_guard lock(mutex);
      n = ++counts.connect_failures;
    }
    if (n == 1 || n % 50 == 0) spdlog::warn("amqp: cannot reach {}:{} ({}); retrying", config.host, config.port, why);
  }

  void set_state(bool up, const std::string& why) {
    if (up) {
      std::lock_guard lock(mutex);
      ++counts.connects;
    }
    spdlog::info("amqp: {} {}:{} ({})", up ? "connected to" : "lost", config.host, config.port, why);
    if (callbacks.on_state) callbacks.on_state(up, why);
  }

  void wait_wake(double seconds) const {
    pollfd p{wake_fd, POLLIN, 0};
    ::poll(&p, 1, static_cast<int>(seconds * 1000));
    drain_wake();
  }

  void drain_wake() const {
    std::uint64_t n = 0;
    [[maybe_unused]] const auto r = ::read(wake_fd, &n, sizeof n);
  }

  void check(const amqp_rpc_reply_t& r, const char* what) const {
    if (r.reply_type != AMQP_RESPONSE_NORMAL) throw std::runtime_error(rpc_error(r, what));
  }

  void connect() {
    conn = amqp_new_connection();
    amqp_socket_t* socket = amqp_tcp_socket_new(conn);
    if (!socket) throw std::runtime_error("cannot create a socket");
    timeval tv = timeval_of(config.connect_timeout_s);
    // A peer that accepts the connection but never answers does not hold the thread: the login and
    // every declaration are bounded too.
    amqp_set_handshake_timeout(conn, &tv);
    amqp_set_rpc_timeout(conn, &tv);
    const int rc = amqp_socket_open_noblock(socket, config.host.c_str(), config.port, &tv);
    if (rc != AMQP_STATUS_OK) throw std::runtime_error(fmt::format("connect: {}", amqp_error_string2(rc)));
    check(amqp_login(conn, config.vhost.c_str(), 0, AMQP_DEFAULT_FRAME_SIZE, config.heartbeat_s, AMQP_SASL_METHOD_PLAIN,
                     config.user.c_str(), config.password.c_str()),
          "login");
    amqp_channel_open(conn, kChannel);
    check(amqp_get_rpc_reply(conn), "channel open");
    // As clu declares it: a topic exchange, not durable, deleted with its last binding.
    amqp_exchange_declare(conn, kChannel, bytes_of(config.exchange), amqp_cstring_bytes("topic"), 0, 0, 1, 0,
                          amqp_empty_table);
    check(amqp_get_rpc_reply(conn), "exchange declare");
    if (!config.queue.empty()) declare_queue();
    is_connected = true;
  }

  void declare_queue() {
    amqp_queue_declare(conn, kChannel, bytes_of(config.queue), 0, 0, 1, 1, amqp_empty_table);
    check(amqp_get_rpc_reply(conn), "queue declare");
    for (const auto& key : config.bindings) {
      amqp_queue_bind(conn, kChannel, bytes_of(config.queue), bytes_of(config.exchange), bytes_of(key), amqp_empty_table);
      check(amqp_get_rpc_reply(conn), "queue bind");
    }
    amqp_basic_consume(conn, kChannel, bytes_of(config.queue), amqp_empty_bytes, 0, 1, 1, amqp_empty_table);
    check(amqp_get_rpc_reply(conn), "consume");
  }

  void drop_connection() noexcept {
    if (!conn) return;
    amqp_destroy_connection(conn);  // no close handshake: the broker may be gone
    conn = nullptr;
  }

  // Until stop() or a connection failure (thrown).
  void serve() {
    while (!stopping) {
      flush();
      if (!amqp_data_in_buffer(conn) && !amqp_frames_enqueued(conn)) {
        pollfd p[2] = {{amqp_get_sockfd(conn), POLLIN, 0}, {wake_fd, POLLIN, 0}};
        ::poll(p, 2, kIdlePollMs);
        if (p[1].revents) drain_wake();
      }
      receive();
    }
    drain();
  }

  // What the outbox holds, in order. A message that cannot be written stays first in the outbox.
  void flush() {
    for (;;) {
      Message m;
      {
        std::lock_guard lock(mutex);
        if (outbox.empty()) return;
        m = std::move(outbox.front());
        outbox.pop_front();
      }
      if (!send(m)) {  // the connection broke: the message goes out again after reconnection
        std::lock_guard lock(mutex);
        outbox.push_front(std::move(m));
        throw std::runtime_error("publish: the connection broke");
      }
      std::lock_guard lock(mutex);
      ++counts.published;
    }
  }

  bool send(const Message& m) {
    std::vector<amqp_table_entry_t> entries;
    std::vector<std::string> keys;
    keys.reserve(m.headers.size());
    for (const auto& [k, v] : m.headers) {
      keys.push_back(k);
      entries.push_back(amqp_table_entry_t{bytes_of(keys.back()), field_of(v)});
    }
    amqp_basic_properties_t p{};
    p._flags = AMQP_BASIC_CONTENT_TYPE_FLAG | AMQP_BASIC_HEADERS_FLAG | AMQP_BASIC_TIMESTAMP_FLAG;
    p.content_type = bytes_of(m.content_type);
    p.headers = amqp_table_t{static_cast<int>(entries.size()), entries.data()};
    p.timestamp = static_cast<std::uint64_t>(std::time(nullptr));
    if (!m.correlation_id.empty()) {
      p._flags |= AMQP_BASIC_CORRELATION_ID_FLAG;
      p.correlation_id = bytes_of(m.correlation_id);
    }
    if (!m.reply_to.empty()) {
      p._flags |= AMQP_BASIC_REPLY_TO_FLAG;
      p.reply_to = bytes_of(m.reply_to);
    }
    const int rc = amqp_basic_publish(conn, kChannel, bytes_of(config.exchange), bytes_of(m.routing_key),
                                      config.mandatory ? 1 : 0, 0, &p, bytes_of(m.body));
    if (rc != AMQP_STATUS_OK) spdlog::debug("amqp: publish: {}", amqp_error_string2(rc));
    return rc == AMQP_STATUS_OK;
  }

  // One delivery (or one other frame) when there is one; returns at once otherwise.
  void receive() {
    amqp_maybe_release_buffers(conn);
    amqp_envelope_t env;
    timeval zero{0, 1};
    const amqp_rpc_reply_t r = amqp_consume_message(conn, &env, &zero, 0);
    if (r.reply_type == AMQP_RESPONSE_NORMAL) {
      Message m = message_of(env.message.properties, env.message.body, string_of(env.routing_key));
      amqp_destroy_envelope(&env);
      {
        std::lock_guard lock(mutex);
        ++counts.received;
      }
      if (callbacks.on_message) callbacks.on_message(std::move(m));
      return;
    }
    if (r.reply_type == AMQP_RESPONSE_LIBRARY_EXCEPTION && r.library_error == AMQP_STATUS_TIMEOUT) return;
    if (r.reply_type == AMQP_RESPONSE_LIBRARY_EXCEPTION && r.library_error == AMQP_STATUS_UNEXPECTED_STATE) {
      other_frame();
      return;
    }
    throw std::runtime_error(rpc_error(r, "receive"));
  }

  // A frame that is not a delivery: a returned message, or the broker closing the channel or connection.
  void other_frame() {
    amqp_frame_t frame;
    timeval tv{1, 0};
    const int rc = amqp_simple_wait_frame_noblock(conn, &frame, &tv);
    if (rc != AMQP_STATUS_OK) throw std::runtime_error(fmt::format("receive: {}", amqp_error_string2(rc)));
    if (frame.frame_type != AMQP_FRAME_METHOD) return;
    switch (frame.payload.method.id) {
      case AMQP_BASIC_RETURN_METHOD: {
        const auto* ret = static_cast<const amqp_basic_return_t*>(frame.payload.method.decoded);
        std::string key = string_of(ret->routing_key);
        amqp_message_t msg;
        check(amqp_read_message(conn, frame.channel, &msg, 0), "returned message");
        Message m = message_of(msg.properties, msg.body, std::move(key));
        amqp_destroy_message(&msg);
        {
          std::lock_guard lock(mutex);
          ++counts.returned;
        }
        if (callbacks.on_returned) callbacks.on_returned(std::move(m));
        return;
      }
      case AMQP_CHANNEL_CLOSE_METHOD: throw std::runtime_error("the broker closed the channel");
      case AMQP_CONNECTION_CLOSE_METHOD: throw std::runtime_error("the broker closed the connection");
      default: return;
    }
  }

  // On stop: what is still queued goes out, then a clean close.
  void drain() noexcept {
    try {
      flush();
      amqp_channel_close(conn, kChannel, AMQP_REPLY_SUCCESS);
      amqp_connection_close(conn, AMQP_REPLY_SUCCESS);
    } catch (const std::exception& e) {
      spdlog::debug("amqp: closing: {}", e.what());
    }
  }
};

AmqpLink::AmqpLink(LinkConfig config, Callbacks callbacks) : impl_(std::make_unique<Impl>()) {
  impl_->config = std::move(config);
  impl_->callbacks = std::move(callbacks);
  impl_->wake_fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (impl_->wake_fd < 0) throw Exception(Error(CoreErrc::io, "amqp: cannot create an eventfd"));
  impl_->thread = std::thread([impl = impl_.get()] { impl->run(); });
}

AmqpLink::~AmqpLink() {
  stop();
  ::close(impl_->wake_fd);
}

void AmqpLink::publish(Message message) {
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->outbox.size() >= impl_->config.outbox_limit) {
      impl_->outbox.pop_front();
      ++impl_->counts.dropped;
    }
    impl_->outbox.push_back(std::move(message));
  }
  impl_->wake();
}

bool AmqpLink::connected() const noexcept { return impl_->is_connected; }

LinkCounters AmqpLink::counters() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->counts;
}

void AmqpLink::stop() noexcept {
  if (!impl_->thread.joinable()) return;
  impl_->stopping = true;
  impl_->wake();
  impl_->thread.join();
}

}  // namespace axon::actor
