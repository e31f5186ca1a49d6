// AmqpLink without a broker: it keeps trying, counts its failures and keeps a bounded outbox.
#include "axon/actor/amqp_link.hpp"

#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

namespace axon::actor {
namespace {

// A loopback port nobody listens on (bound, then closed).
std::uint16_t closed_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

TEST(AmqpLink, KeepsTryingWithoutABrokerAndDropsTheOldestBeyondItsOutbox) {
  LinkConfig c;
  c.port = closed_port();
  c.backoff_min_s = 0.01;
  c.backoff_max_s = 0.02;
  c.outbox_limit = 2;
  AmqpLink link(c, {});
  for (int i = 0; i < 3; ++i) link.publish(Message{"reply.broadcast", {}, "", "", "text/json", "{}"});
  EXPECT_EQ(link.counters().dropped, 1u);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (link.counters().connect_failures < 3 && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_GE(link.counters().connect_failures, 3u);  // it retried, with back-off, and never crashed
  EXPECT_FALSE(link.connected());
  EXPECT_EQ(link.counters().published, 0u);
  link.stop();  // while disconnected: returns, the outbox is given up
}

TEST(AmqpLink, APeerThatNeverAnswersTheLoginIsGivenUpAndRetried) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);  // the kernel accepts; nobody speaks AMQP
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(fd, 16), 0);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  LinkConfig c;
  c.port = ntohs(a.sin_port);
  c.connect_timeout_s = 0.1;
  c.backoff_min_s = 0.01;
  {
    AmqpLink link(c, {});
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (link.counters().connect_failures < 2 && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    EXPECT_GE(link.counters().connect_failures, 2u);
    EXPECT_FALSE(link.connected());
  }
  ::close(fd);
}

}  // namespace
}  // namespace axon::actor
