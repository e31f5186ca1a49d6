// The extension module _axon: what the package axon (python/axon/) re-exports.
#include "bindings.hpp"

PYBIND11_MODULE(_axon, m) {
  namespace py = axon::python::py;
  m.doc() = "axon's C++ libraries (re-exported by the package axon; see docs/python.md)";
  m.attr("__version__") = AXON_VERSION;
  auto can = m.def_submodule("can", "CAN buses, frames and candump logs");
  auto fps = m.def_submodule("fps", "fiber positioner arrays: layouts, planner, client, simulated plane");
  auto blmc = m.def_submodule("blmc", "motor driver boards: enable, measurements, a Python front end to the 1 kHz loop, simulated board");
  auto c4g = m.def_submodule("c4g", "robot controllers' open interface: the server with its applications, cycle statistics, simulated controller");
  axon::python::bind_errors(m, can, fps, blmc, c4g);
  axon::python::bind_can(can);
  axon::python::bind_fps_plan(fps);
  axon::python::bind_fps_client(fps);
  axon::python::bind_blmc(blmc);
  axon::python::bind_c4g(c4g);
}
