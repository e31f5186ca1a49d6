// The axon.Error hierarchy and the translation of axon::Exception into it (docs/python.md,
// "Errors"). An exception's class follows its error code: first the code itself (e.g.
// HostErrc::locked -> axon.fps.MotionLocked), then its category (axon.fps.host -> axon.fps.Error),
// then axon.Error. Every instance carries `category` (the C++ category's name, "axon.fps.host"),
// `code` (the enum's value), `reason` (the category's message for it) and `detail` (the context).
#include "bindings.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/blmc/protocol/error.hpp"
#include "axon/c4g/protocol/error.hpp"
#include "axon/can/error.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/host/error.hpp"
#include "axon/fps/plan/error.hpp"
#include "axon/fps/plc/error.hpp"
#include "axon/fps/protocol/error.hpp"
#include "axon/net/error.hpp"

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace axon::python {

namespace {

using fps::host::HostErrc;
using fps::plan::PlanErrc;
using fps::plc::PlcErrc;

// The classes, made once at import and kept for the life of the interpreter (a module's
// exception types are never freed).
struct Classes {
  std::map<std::pair<const std::error_category*, int>, PyObject*> by_code;
  std::map<const std::error_category*, PyObject*> by_category;
  PyObject* base = nullptr;             // axon.Error
  PyObject* collision_locked = nullptr;  // axon.fps.CollisionLocked
};
Classes& classes() {
  static Classes* c = new Classes();  // never destroyed: the interpreter may outlive static destructors
  return *c;
}

PyObject* make_class(py::module_& where, const char* name, std::vector<PyObject*> bases, const char* doc) {
  // Named as the package shows them: axon.fps.MotionLocked, not _axon.fps.MotionLocked.
  std::string qualified = std::string(py::str(where.attr("__name__"))) + "." + name;
  if (const auto at = qualified.find("._axon"); at != std::string::npos) qualified.erase(at, 6);  // axon._axon.fps
  if (qualified.rfind("_axon", 0) == 0) qualified.erase(0, 1);                                      // _axon.fps
  py::tuple b(bases.size());
  for (std::size_t i = 0; i < bases.size(); ++i) b[i] = py::reinterpret_borrow<py::object>(bases[i]);
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, b.ptr(), nullptr);
  if (!cls) throw py::error_already_set();
  where.add_object(name, py::reinterpret_borrow<py::object>(cls));
  return cls;
}

void map_codes(std::initializer_list<std::error_code> codes, PyObject* cls) {
  for (const auto& ec : codes) classes().by_code[{&ec.category(), ec.value()}] = cls;
}

template <class E>
void map_category(E any_code, PyObject* cls) {
  classes().by_category[&std::error_code(any_code).category()] = cls;
}

// HostErrc::locked for a lock a collision set (the array's reasons, fps/host/array.cpp, start with
// "collision"; the refusal's detail is "positioner N: REASON..." or "broadcast: REASON...").
bool locked_by_collision(const Error& e) {
  return e.code == HostErrc::locked && e.detail.find(": collision") != std::string::npos;
}

PyObject* class_for(const Error& e) {
  auto& c = classes();
  if (locked_by_collision(e)) return c.collision_locked;
  if (auto it = c.by_code.find({&e.code.category(), e.code.value()}); it != c.by_code.end()) return it->second;
  if (auto it = c.by_category.find(&e.code.category()); it != c.by_category.end()) return it->second;
  return c.base;
}

void raise(const Exception& ex) {
  const Error& e = ex.error();
  py::object instance = py::reinterpret_borrow<py::object>(class_for(e))(ex.what());
  instance.attr("category") = e.code.category().name();
  instance.attr("code") = e.code.value();
  instance.attr("reason") = e.code.message();
  instance.attr("detail") = e.detail;
  PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(instance.ptr())), instance.ptr());
}

struct Common {
  PyObject* error;
  PyObject* invalid;
  PyObject* timeout;
  PyObject* closed;
  PyObject* cancelled;
  PyObject* connection;
};

Common bind_common(py::module_& m) {
  auto& c = classes();
  c.base = make_class(m, "Error", {PyExc_Exception},
                      "Base of every error axon raises: category, code, reason and detail say what failed.");
  Common k{c.base, nullptr, nullptr, nullptr, nullptr, nullptr};
  k.invalid = make_class(m, "InvalidArgument", {k.error, PyExc_ValueError}, "A bad value or file from the caller.");
  k.timeout = make_class(m, "TimeoutError", {k.error, PyExc_TimeoutError},
                         "Nothing answered in time, or a blocking call overran its bound (its devices were stopped).");
  k.closed = make_class(m, "ClosedError", {k.error}, "The connection or device was closed.");
  k.cancelled = make_class(m, "Cancelled", {k.error}, "The operation was cancelled (its client stopped).");
  k.connection = make_class(m, "ConnectionError", {k.error, PyExc_ConnectionError},
                            "A connection could not be made (address, port, peer down).");
  map_category(CoreErrc::io, k.error);
  map_codes({CoreErrc::invalid_argument, CoreErrc::config_syntax, CoreErrc::config_missing_key,
             CoreErrc::config_bad_value, CoreErrc::config_unknown_key},
            k.invalid);
  map_codes({CoreErrc::timeout}, k.timeout);
  map_codes({CoreErrc::closed}, k.closed);
  map_codes({CoreErrc::cancelled}, k.cancelled);
  map_category(net::NetErrc::timeout, k.error);
  map_codes({net::NetErrc::timeout}, k.timeout);
  map_codes({net::NetErrc::closed}, k.closed);
  map_codes({net::NetErrc::resolve_failed, net::NetErrc::bind_failed}, k.connection);
  return k;
}

void bind_can_errors(py::module_& can, const Common& k) {
  auto* error = make_class(can, "Error", {k.error}, "A CAN bus, frame or log error.");
  map_category(can::CanErrc::io, error);
  map_codes({can::CanErrc::invalid_id, can::CanErrc::invalid_length},
            make_class(can, "InvalidFrame", {error, k.invalid}, "An id or length that does not fit a CAN frame."));
  map_codes({can::CanErrc::parse_error, can::CanErrc::bad_spec},
            make_class(can, "ParseError", {error, k.invalid}, "A frame, log line or bus spec that does not parse."));
  map_codes({can::CanErrc::bus_off}, make_class(can, "BusOff", {error}, "The CAN controller is bus-off."));
  map_codes({can::CanErrc::closed}, make_class(can, "Closed", {error, k.closed}, "The bus was closed."));
  map_codes({can::CanErrc::timeout}, make_class(can, "Timeout", {error, k.timeout}, "Nothing arrived in time."));
  map_codes({can::CanErrc::connect_failed},
            make_class(can, "ConnectFailed", {error, k.connection}, "The gateway or daemon did not accept a connection."));
}

void bind_fps_errors(py::module_& fps, const Common& k) {
  auto* error = make_class(fps, "Error", {k.error}, "A fiber positioner error (protocol, host, planner, PLC).");
  for (auto* cat : {&fps::protocol::protocol_category(), &fps::host::host_category(), &fps::plan::plan_category(),
                    &fps::plc::plc_category()})
    classes().by_category[cat] = error;
  auto* locked = make_class(fps, "MotionLocked", {error},
                            "The array is locked (collision, operator, signal, timeout): every robot was stopped and "
                            "moves are refused until unlock().");
  map_codes({HostErrc::locked}, locked);
  classes().collision_locked = make_class(fps, "CollisionLocked", {locked},
                                          "A collision locked the array: every robot was stopped; inspect, then unlock().");
  map_codes({HostErrc::collision}, classes().collision_locked);
  map_codes({HostErrc::timeout, PlcErrc::timeout}, make_class(fps, "Timeout", {error, k.timeout}, "A robot or the PLC did not answer in time."));
  map_codes({HostErrc::unknown_positioner},
            make_class(fps, "UnknownPositioner", {error, PyExc_KeyError}, "A robot id the array (or layout) does not have."));
  map_codes({HostErrc::not_ready}, make_class(fps, "NotReady", {error}, "A robot is not in a state to do this."));
  map_codes({HostErrc::cancelled}, make_class(fps, "Cancelled", {error, k.cancelled}, "The client stopped while the request waited."));
  map_codes({HostErrc::closed}, make_class(fps, "Closed", {error, k.closed}, "The bus closed under the client."));
  map_codes({HostErrc::invalid_argument, PlcErrc::invalid_argument},
            make_class(fps, "InvalidArgument", {error, k.invalid}, "A bad option or input."));
  map_codes({PlcErrc::connect_failed}, make_class(fps, "PlcConnectFailed", {error, k.connection}, "The PLC did not accept a connection."));
  auto* plan = make_class(fps, "PlanError", {error}, "The planner or a target set refused the request.");
  classes().by_category[&fps::plan::plan_category()] = plan;
  map_codes({PlanErrc::too_close, PlanErrc::too_far, PlanErrc::outside_hard_stops, PlanErrc::unknown_robot,
             PlanErrc::unknown_fibre, PlanErrc::duplicate_target, PlanErrc::bad_target_file, PlanErrc::bad_trajectory},
            make_class(fps, "BadTarget", {plan, k.invalid}, "A target or trajectory that cannot be used."));
  map_codes({PlanErrc::robot_collision, PlanErrc::obstacle_collision},
            make_class(fps, "PlanCollision", {plan}, "Poses that collide, or robots that cannot reach their targets."));
}

void bind_blmc_errors(py::module_& blmc, const Common& k) {
  using blmc::host::HostErrc;
  auto* error = make_class(blmc, "Error", {k.error}, "A motor driver board error (protocol or host).");
  map_category(HostErrc::timeout, error);
  map_category(blmc::protocol::ProtocolErrc::wrong_id, error);
  map_codes({HostErrc::timeout}, make_class(blmc, "Timeout", {error, k.timeout}, "The board did not answer in time."));
  map_codes({HostErrc::not_ready}, make_class(blmc, "NotReady", {error}, "The motors did not finish their alignment in time."));
  map_codes({HostErrc::board_error}, make_class(blmc, "BoardError", {error}, "The board reports an error code (the motors are off)."));
  map_codes({HostErrc::safety_fault, HostErrc::stale_data},
            make_class(blmc, "SafetyFault", {error}, "A safety check stopped the motors (zero current, disabled)."));
  map_codes({HostErrc::invalid_argument},
            make_class(blmc, "InvalidArgument", {error, k.invalid}, "A bad setting, action or input."));
  map_codes({HostErrc::not_enabled}, make_class(blmc, "NotEnabled", {error}, "The call needs the motors enabled (enable() first)."));
  map_codes({HostErrc::cyclic_active}, make_class(blmc, "ControlRunning", {error}, "The control loop owns the board (stop() first)."));
  map_codes({HostErrc::not_cyclic}, make_class(blmc, "NotRunning", {error}, "The call needs a control run (start() first)."));
  map_codes({HostErrc::interrupted}, make_class(blmc, "Interrupted", {error}, "The wait was interrupted (interrupt())."));
  map_codes({HostErrc::closed}, make_class(blmc, "Closed", {error, k.closed}, "The bus or the board was closed."));
  map_codes({HostErrc::homing_failed}, make_class(blmc, "HomingFailed", {error}, "No encoder index found."));
}

void bind_c4g_errors(py::module_& c4g) {
  // Settings and trajectories the caller got wrong are axon.InvalidArgument (CoreErrc), a port in
  // use axon.ConnectionError (NetErrc); what is c4g's own is the protocol's.
  map_category(c4g::protocol::ProtocolErrc::wrong_size,
               make_class(c4g, "Error", {classes().base}, "A C4G open-interface error: a datagram or initialization packet that does not decode."));
}

}  // namespace

void bind_errors(py::module_& m, py::module_& can, py::module_& fps, py::module_& blmc, py::module_& c4g) {
  const Common k = bind_common(m);
  bind_can_errors(can, k);
  bind_fps_errors(fps, k);
  bind_blmc_errors(blmc, k);
  bind_c4g_errors(c4g);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Exception& e) {
      raise(e);
    }
  });
}

}  // namespace axon::python
