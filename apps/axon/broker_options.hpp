// Where the broker is and which exchange: the options every `axon actor ...` and `axon tell` share.
#pragma once

#include "axon/actor/amqp_link.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace axon::app {

struct BrokerOptions {
  std::string broker = "127.0.0.1:5672";
  std::string exchange{actor::kDefaultExchange};

  [[nodiscard]] actor::LinkConfig link() const {
    const auto ep = need(net::parse_endpoint(broker, 5672));
    actor::LinkConfig c;
    c.host = ep.host;
    c.port = ep.port;
    c.exchange = exchange;
    return c;
  }
};

inline void add_broker_options(CLI::App& cmd, BrokerOptions& o) {
  cmd.add_option("--broker", o.broker, "the AMQP broker, HOST[:PORT] (default 127.0.0.1:5672)");
  cmd.add_option("--exchange", o.exchange, "the topic exchange (default sdss_exchange, as clu's actors)");
}

}  // namespace axon::app
