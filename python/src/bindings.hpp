// What the binding files of the `axon` module share: the submodule binders, the exception
// translation and the way blocking calls wait (GIL released, Ctrl-C checked).
#pragma once

#include <pybind11/pybind11.h>

#include <chrono>
#include <functional>
#include <future>
#include <thread>
#include <utility>

namespace axon::python {

namespace py = pybind11;

void bind_errors(py::module_& m, py::module_& can, py::module_& fps, py::module_& blmc, py::module_& c4g);
void bind_can(py::module_& m);
void bind_fps_plan(py::module_& m);
void bind_fps_client(py::module_& m);
void bind_blmc(py::module_& m);
void bind_c4g(py::module_& m);

// How often a blocking call looks for Ctrl-C.
inline constexpr auto kSignalPoll = std::chrono::milliseconds(50);

// Runs a blocking call without the GIL and answers Ctrl-C while it waits. The call runs on a
// helper thread (it only waits there: the work is on the object's own event loop); this thread
// takes the GIL every kSignalPoll to run Python's signal handlers. When one raises (SIGINT:
// KeyboardInterrupt), stop() runs (without the GIL): it must make the call end soon, e.g. stop
// the devices, and is called once; then the call's end is awaited (whatever it returned or threw
// is dropped) and the handler's exception propagates. Another thread than the main one never sees
// a signal (Python runs handlers on the main thread only), so there the call simply waits.
template <class F>
auto interruptible(F call, const std::function<void()>& stop) -> decltype(call()) {
  using T = decltype(call());
  std::packaged_task<T()> task(std::move(call));
  auto result = task.get_future();
  std::thread worker(std::move(task));
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    while (result.wait_for(kSignalPoll) != std::future_status::ready) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        interrupted = true;
        break;
      }
    }
    if (interrupted) {
      stop();
      result.wait();
    }
    worker.join();
  }
  if (interrupted) throw py::error_already_set();
  return result.get();
}

}  // namespace axon::python
