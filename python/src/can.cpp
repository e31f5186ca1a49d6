// axon.can: frames, buses from a spec string (can::BlockingBus), candump logs.
#include "bindings.hpp"

#include "axon/can/blocking_bus.hpp"
#include "axon/can/candump_log.hpp"

#include <pybind11/operators.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace axon::python {

namespace {

using can::Frame;

Frame make_frame(std::uint32_t id, py::bytes data, std::optional<bool> extended, bool remote, std::optional<int> dlc) {
  const auto fmt = extended.value_or(id > Frame::kMaxStandardId) ? can::IdFormat::extended : can::IdFormat::standard;
  const std::string bytes = data;
  if (remote) return value_or_throw(Frame::remote(id, fmt, static_cast<std::uint8_t>(dlc.value_or(0))));
  const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
  return value_or_throw(Frame::data(id, fmt, {p, bytes.size()}));
}

double seconds_of(core::WallTime t) { return std::chrono::duration<double>(t).count(); }

void bind_frame(py::module_& m) {
  py::class_<Frame>(m, "Frame", "A classic CAN frame: 11-bit or 29-bit id, 0..8 data bytes or a remote request.")
      .def(py::init(&make_frame), py::arg("id"), py::arg("data") = py::bytes(), py::kw_only(),
           py::arg("extended") = py::none(), py::arg("remote") = false, py::arg("dlc") = py::none(),
           "extended: None picks it from the id (above 0x7FF: 29-bit). Raises axon.can.InvalidFrame.")
      .def_static("parse", [](const std::string& text) { return value_or_throw(Frame::parse(text)); },
                  py::arg("text"), "cansend notation: '123#DEADBEEF', '12345678#11.22', '123#R4'.")
      .def_property_readonly("id", &Frame::id)
      .def_property_readonly("is_extended", &Frame::is_extended)
      .def_property_readonly("is_remote", &Frame::is_remote)
      .def_property_readonly("dlc", &Frame::dlc)
      .def_property_readonly("data", [](const Frame& f) {
        const auto p = f.payload();
        return py::bytes(reinterpret_cast<const char*>(p.data()), p.size());
      })
      .def_property_readonly("timestamp", [](const Frame& f) { return seconds_of(f.timestamp()); },
                             "Seconds since the Unix epoch when received or logged; 0 when unknown.")
      .def("__str__", &Frame::to_string)
      .def("__repr__", [](const Frame& f) { return fmt::format("axon.can.Frame('{}')", f.to_string()); })
      .def(py::self == py::self)
      .def("__hash__", [](const Frame& f) { return py::hash(py::str(f.to_string())); });
}

void bind_stats(py::module_& m) {
  py::class_<can::BusStats>(m, "BusStats", "Counters of one bus since it was opened.")
      .def_readonly("frames_in", &can::BusStats::frames_in)
      .def_readonly("frames_out", &can::BusStats::frames_out)
      .def_readonly("rx_filtered", &can::BusStats::rx_filtered)
      .def_readonly("rx_dropped", &can::BusStats::rx_dropped)
      .def_readonly("tx_dropped", &can::BusStats::tx_dropped)
      .def_readonly("protocol_errors", &can::BusStats::protocol_errors)
      .def_readonly("error_frames", &can::BusStats::error_frames)
      .def("__repr__", [](const can::BusStats& s) {
        return fmt::format("BusStats(frames_in={}, frames_out={}, rx_dropped={}, tx_dropped={})", s.frames_in,
                           s.frames_out, s.rx_dropped, s.tx_dropped);
      });
}

// receive(None) waits without end; in slices, so that Ctrl-C reaches Python between them.
std::optional<Frame> receive(can::BlockingBus& bus, std::optional<double> timeout_s) {
  constexpr double kSlice = 0.05;
  double left = timeout_s.value_or(std::numeric_limits<double>::infinity());
  do {
    const double wait = std::min(left, kSlice);
    std::optional<Frame> f;
    {
      py::gil_scoped_release release;
      f = bus.receive(wait);
    }
    if (f) return f;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    left -= wait;
  } while (left > 0);
  return std::nullopt;
}

void bind_bus(py::module_& m) {
  py::class_<can::BlockingBus>(m, "Bus",
                               "A CAN bus opened from its spec: virtual:NAME (in this process), "
                               "socketcand://HOST:PORT/CHANNEL, cannet://HOST:PORT/N, socketcan:IFACE.")
      .def(py::init([](const std::string& spec, double connect_timeout_s) {
             can::BlockingBusOptions o;
             o.connect_timeout_s = connect_timeout_s;
             py::gil_scoped_release release;
             return std::make_unique<can::BlockingBus>(spec, o);
           }),
           py::arg("spec"), py::kw_only(), py::arg("connect_timeout_s") = 5.0)
      .def("send", [](can::BlockingBus& b, const Frame& f) {
             py::gil_scoped_release release;
             b.send(f);
           }, py::arg("frame"), "Waits until the transport took the frame.")
      .def("recv", &receive, py::arg("timeout_s") = py::none(),
           "The next frame, waiting at most timeout_s seconds (None: until one comes, Ctrl-C ends the wait); "
           "None when nothing came.")
      .def("set_filters", [](can::BlockingBus& b, const std::vector<std::string>& filters) {
             std::vector<can::Filter> f;
             for (const auto& text : filters) f.push_back(value_or_throw(can::Filter::parse(text)));
             b.set_filters(std::move(f));
           }, py::arg("filters"), "candump's ID:MASK filters (hex); a frame passes when any matches; [] passes all.")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](can::BlockingBus& b) {
             try {
               return *receive(b, std::nullopt);
             } catch (const Exception& e) {
               if (e.code() == can::CanErrc::closed) throw py::stop_iteration();
               throw;
             }
           },
           "Iterating a bus yields frames as they come (until Ctrl-C or the bus closes).")
      .def_property_readonly("name", &can::BlockingBus::name)
      .def_property_readonly("stats", &can::BlockingBus::stats)
      .def_property_readonly("state", [](const can::BlockingBus& b) { return can::to_string(b.state()); },
                             "active, error_warning, error_passive, bus_off or closed.")
      .def("close", &can::BlockingBus::close, py::call_guard<py::gil_scoped_release>())
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](can::BlockingBus& b, py::args) { b.close(); });
}

struct LogEntryView {
  Frame frame;
  std::string iface;
  bool error_frame;
  std::string direction;
};

const char* direction_name(can::LogDirection d) {
  switch (d) {
    case can::LogDirection::rx: return "rx";
    case can::LogDirection::tx: return "tx";
    default: return "";
  }
}

void bind_logs(py::module_& m) {
  py::class_<LogEntryView>(m, "LogEntry", "One line of a candump log.")
      .def_readonly("frame", &LogEntryView::frame)
      .def_readonly("iface", &LogEntryView::iface)
      .def_readonly("error_frame", &LogEntryView::error_frame)
      .def_readonly("direction", &LogEntryView::direction, "'rx', 'tx' (python-can logs) or ''.")
      .def_property_readonly("timestamp", [](const LogEntryView& e) { return seconds_of(e.frame.timestamp()); })
      .def("__repr__", [](const LogEntryView& e) {
        return fmt::format("axon.can.LogEntry('{}')", can::format_candump_line(e.frame, e.iface));
      });
  py::class_<can::CandumpReader>(m, "LogReader", "Reads a candump log (candump -l, python-can) entry by entry.")
      .def(py::init([](const std::string& path, bool skip_bad) {
             can::CandumpReadOptions o;
             o.skip_bad = skip_bad;
             return value_or_throw(can::CandumpReader::open(path, o));
           }),
           py::arg("path"), py::kw_only(), py::arg("skip_bad") = false)
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](can::CandumpReader& r) {
        auto e = value_or_throw(r.next());
        if (!e) throw py::stop_iteration();
        return LogEntryView{e->frame, e->iface, e->error_frame, direction_name(e->direction)};
      })
      .def_property_readonly("lines_read", &can::CandumpReader::lines_read)
      .def_property_readonly("lines_skipped", &can::CandumpReader::lines_skipped)
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](can::CandumpReader&, py::args) {});
  py::class_<can::CandumpWriter>(m, "LogWriter", "Writes a candump log file.")
      .def(py::init([](const std::string& path, bool append) {
             return value_or_throw(can::CandumpWriter::create(path, can::CandumpWriter::Flush::every_line, append));
           }),
           py::arg("path"), py::kw_only(), py::arg("append") = false)
      .def("write", [](can::CandumpWriter& w, const Frame& f, const std::string& iface) { value_or_throw(w.write(f, iface)); },
           py::arg("frame"), py::arg("iface") = "can0")
      .def_property_readonly("lines_written", &can::CandumpWriter::lines_written)
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](can::CandumpWriter& w, py::args) { (void)w.flush(); });
}

}  // namespace

void bind_can(py::module_& m) {
  bind_frame(m);
  bind_stats(m);
  bind_bus(m);
  bind_logs(m);
}

}  // namespace axon::python
