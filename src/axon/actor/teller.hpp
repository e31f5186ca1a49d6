// Teller: a commander on the bus. It sends one command to an actor as clu's clients do (routing
// key command.<actor>, headers commander_id and command_id, the command id as correlation id, body
// {"command_string": ...}) and hands each reply to the caller as it comes, until the final one
// (':', 'f' or '!'). What `axon tell` runs.
//
// Errors: tell() throws axon::Exception with CoreErrc::timeout when the broker cannot be reached
// or the final reply does not come in time. A command no queue takes (no such actor on the
// exchange) ends with a failure reply made up here, as clu's client does.
#pragma once

#include "axon/actor/amqp_link.hpp"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>

namespace axon::actor {

struct TellReply {
  MessageCode code = MessageCode::info;
  std::string sender;
  std::string command_id;
  nlohmann::json keywords;  // the body (an object), or {"text": body} when it was not JSON
};

struct TellOptions {
  LinkConfig link;           // broker and exchange; the queue and bindings are set here
  std::string commander = "axon_tell";
  double timeout_s = 30.0;   // connecting plus waiting for the final reply
};

// Sends `command_string` to `actor`, calls on_reply for every reply to it, returns the final one.
TellReply tell(const std::string& actor, const std::string& command_string, const TellOptions& options,
               const std::function<void(const TellReply&)>& on_reply = {});

}  // namespace axon::actor
