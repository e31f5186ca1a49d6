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

// What every `axon actor ...` shares besides the broker: its name, the status period, how long it
// runs and its live page.
struct ActorOptions {
  std::string name;
  double status_period_s = 10.0;
  double duration_s = 0;
  std::string http;  // HOST:PORT of the live page, /api/state and /metrics (empty: none)
};

inline void add_actor_options(CLI::App& cmd, ActorOptions& o, const std::string& default_name) {
  o.name = default_name;
  cmd.add_option("--name", o.name, "the actor's name: its queue takes command.NAME.# (default " + default_name + ")");
  cmd.add_option("--status-period", o.status_period_s, "seconds between status broadcasts (default 10; 0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--duration", o.duration_s, "stop after this many seconds (default: until Ctrl-C)")->check(CLI::NonNegativeNumber);
  cmd.add_option("--http", o.http,
                 "serve the live page, /api/state and /metrics on HOST:PORT (PORT alone: 127.0.0.1; port 0: any free "
                 "port, printed as 'listening http HOST:PORT' on stderr; docs/dashboard.md)");
}

inline void add_broker_options(CLI::App& cmd, BrokerOptions& o) {
  cmd.add_option("--broker", o.broker, "the AMQP broker, HOST[:PORT] (default 127.0.0.1:5672)");
  cmd.add_option("--exchange", o.exchange, "the topic exchange (default sdss_exchange, as clu's actors)");
}

}  // namespace axon::app
