// What every soak program shares: its arguments, the process's resident memory and open
// descriptors, and the one summary line it ends with:
//
//   SOAK <name> minutes=30.0 cycles=... faults=... lost=0 unsafe=0 rss_growth_kb=... fd_growth=0 [more]
//
// `lost` counts what should have arrived or been answered and was not (and was not reported),
// `unsafe` every moment a device was left in a state the family's promise forbids
// (docs/reliability.md). The program exits 0 only when both are 0 and its own checks held.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace axon::soak {

struct Args {
  double minutes = 30;
  std::uint64_t seed = 1;
};

// --minutes M (may be fractional) and --seed N; anything else prints the usage and exits 2.
inline Args parse_args(int argc, char** argv, std::string_view name) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    char* end = nullptr;
    if (arg == "--minutes" && i + 1 < argc) {
      a.minutes = std::strtod(argv[++i], &end);
      if (*end == '\0' && a.minutes > 0) continue;
    } else if (arg == "--seed" && i + 1 < argc) {
      a.seed = std::strtoull(argv[++i], &end, 10);
      if (*end == '\0') continue;
    }
    std::fprintf(stderr, "usage: axon_soak_%.*s [--minutes M (>0, default 30)] [--seed N]\n",
                 static_cast<int>(name.size()), name.data());
    std::exit(2);
  }
  return a;
}

// Resident set size of this process (VmRSS), kB; 0 if /proc cannot tell.
inline long rss_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  return 0;
}

// Open file descriptors of this process.
inline long open_fds() {
  long n = 0;
  std::error_code ec;
  for (auto it = std::filesystem::directory_iterator("/proc/self/fd", ec); !ec && it != std::filesystem::directory_iterator();
       it.increment(ec))
    ++n;
  return n;
}

// Resource use from a baseline taken after warm-up (the first cycle) to the end.
struct Baseline {
  long rss = rss_kb();
  long fds = open_fds();
};

struct Summary {
  std::string name;
  double minutes = 0;
  std::uint64_t cycles = 0;
  std::uint64_t faults = 0;  // faults injected
  std::uint64_t lost = 0;
  std::uint64_t unsafe = 0;
  long rss_growth_kb = 0;
  long fd_growth = 0;
  std::vector<std::pair<std::string, std::string>> more;  // family figures, key=value
  std::vector<std::string> failures;                      // checks that did not hold (one line each)

  void finish(const Baseline& b, std::chrono::steady_clock::duration ran) {
    rss_growth_kb = rss_kb() - b.rss;
    fd_growth = open_fds() - b.fds;
    minutes = std::chrono::duration<double>(ran).count() / 60.0;
  }
  [[nodiscard]] bool ok() const { return lost == 0 && unsafe == 0 && failures.empty(); }
  // Prints the failures (stderr) and the summary line (stdout); returns the exit code.
  int report() const {
    for (const auto& f : failures) std::fprintf(stderr, "SOAK %s FAILED: %s\n", name.c_str(), f.c_str());
    std::printf("SOAK %s minutes=%.1f cycles=%llu faults=%llu lost=%llu unsafe=%llu rss_growth_kb=%ld fd_growth=%ld",
                name.c_str(), minutes, static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(faults),
                static_cast<unsigned long long>(lost), static_cast<unsigned long long>(unsafe), rss_growth_kb, fd_growth);
    for (const auto& [k, v] : more) std::printf(" %s=%s", k.c_str(), v.c_str());
    std::printf(" result=%s\n", ok() ? "pass" : "FAIL");
    std::fflush(stdout);
    return ok() ? 0 : 1;
  }
};

}  // namespace axon::soak
