// fps_status: find every fiber positioner on the buses and print its status table (state,
// firmware, arm angles), with axon's blocking fps client. With no argument it starts the six-robot
// benchtop plane simulated in this process and checks that every robot of it answered, ready to
// move. Against real robots, give your gateways' buses:
//   fps_status cannet://10.25.1.11:19228/1 cannet://10.25.1.11:19228/2
#include <axon/fps/host/client.hpp>
#include <axon/fps/sim/simulated_plane.hpp>

#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

int main(int argc, char** argv) try {
  std::unique_ptr<axon::fps::sim::SimulatedPlane> simulated;
  std::vector<std::string> buses(argv + 1, argv + argc);
  if (buses.empty()) {
    simulated = std::make_unique<axon::fps::sim::SimulatedPlane>("benchtop");
    buses = simulated->bus_specs();
  }

  axon::fps::Client fps;  // its own event loop, on its own thread
  fps.open(buses);
  const auto robots = fps.discover();  // GET_ID on every bus, then firmware and status of each robot

  std::printf("%5s  %-11s  %-9s  %8s  %8s  %s\n", "robot", "state", "firmware", "alpha", "beta", "bus");
  std::size_t ready = 0;
  for (const auto& r : robots) {
    ready += r.ready ? 1 : 0;
    if (r.position)
      std::printf("%5u  %-11s  %-9s  %8.3f  %8.3f  %s\n", unsigned{r.id}, r.state.c_str(), r.firmware.c_str(),
                  r.position->alpha, r.position->beta, r.bus.c_str());
    else
      std::printf("%5u  %-11s  %-9s  %8s  %8s  %s  %s\n", unsigned{r.id}, r.state.c_str(), r.firmware.c_str(), "-", "-",
                  r.bus.c_str(), r.error.c_str());
  }
  std::printf("%zu robots, %zu ready\n", robots.size(), ready);

  const std::size_t expected = simulated ? simulated->plane().robots().size() : robots.size();
  const bool ok = !robots.empty() && robots.size() == expected && ready == robots.size();
  std::printf("check: %zu robots expected, every one found and ready: %s\n", expected, ok ? "yes" : "NO");
  return ok ? 0 : 1;
} catch (const std::exception& e) {  // axon::Exception: what failed, and its error code
  std::fprintf(stderr, "fps_status: %s\n", e.what());
  return 1;
}
