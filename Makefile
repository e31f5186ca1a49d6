# axon: the two set-up commands are `make run` and `make test` (see README.md).
# Each installs missing Debian packages, configures with CMake presets and builds with Ninja.
.PHONY: all deps release debug run test test-soak bench soak asan test-asan tsan test-tsan fuzz fuzz-smoke fuzz-long clean

JOBS ?= $(shell nproc)
# ctest runs two tests per core: most of the suite waits on sockets, timers and child processes (at
# -j4 on the 2-core VM the machine stayed 69 % idle and `make test`'s tests took 376 s instead of
# 579 s at -j2). The tests that must not share the machine say so themselves in CMake (RUN_SERIAL,
# RESOURCE_LOCK): the documented examples, the soaks, the 1 kHz and c4g reply-window tests.
TEST_JOBS ?= $(shell echo $$(( $$(nproc) * 2 )))
# ccache (when installed) shares compiled objects between clones of the project on one machine.
export CCACHE_BASEDIR := $(CURDIR)
export CCACHE_NOHASHDIR := 1
CMAKE_EXTRA ?=

all: release

deps:
	@bash scripts/install-deps.sh

release: deps
	@cmake --preset release $(CMAKE_EXTRA) >/dev/null
	@cmake --build --preset release -j $(JOBS)

debug: deps
	@cmake --preset debug $(CMAKE_EXTRA) >/dev/null
	@cmake --build --preset debug -j $(JOBS)

run: release
	./build/release/axon demo

# On failure, scripts/test-failures.sh repeats what each failed test said as the last lines.
test: release
	ctest --preset release -j $(TEST_JOBS) -LE soak || { bash scripts/test-failures.sh build/release; exit 1; }

# The one-minute soaks (ctest label soak): what CI runs after `make test`. fps and blmc side by side,
# then c4g alone (soak/CMakeLists.txt says why).
test-soak: release
	ctest --preset release -j 2 -L soak || { bash scripts/test-failures.sh build/release; exit 1; }

bench: release
	@bash bench/run-all.sh build/release

# The soak programs (soak/, docs/reliability.md), each for SOAK_MINUTES, one after the other.
SOAK_MINUTES ?= 30
SOAK_SEED ?= 1
soak: release
	@bash soak/run.sh build/release $(SOAK_MINUTES) $(SOAK_SEED)

# The sanitizer builds (clang) compile only the unit tests, the libraries they use and, in the
# asan build, the libFuzzer targets: one instrumented build serves both.
asan: deps
	@cmake --preset asan $(CMAKE_EXTRA) >/dev/null
	@cmake --build --preset asan -j $(JOBS) --target axon_unit_tests_all axon_fuzz_all

test-asan: asan
	ctest --preset asan -j $(JOBS) -L unit || { bash scripts/test-failures.sh build/asan; exit 1; }

tsan: deps
	@cmake --preset tsan $(CMAKE_EXTRA) >/dev/null
	@cmake --build --preset tsan -j $(JOBS) --target axon_unit_tests_all

test-tsan: tsan
	ctest --preset tsan -j $(JOBS) -L unit || { bash scripts/test-failures.sh build/tsan; exit 1; }

fuzz: deps
	@cmake --preset asan $(CMAKE_EXTRA) >/dev/null
	@cmake --build --preset asan -j $(JOBS) --target axon_fuzz_all

# A short run of every fuzz target (CI); FUZZ_SECONDS per target.
FUZZ_SECONDS ?= 10
fuzz-smoke: fuzz
	@bash fuzz/smoke.sh build/asan $(FUZZ_SECONDS)

# The long campaign: 30 minutes per target, FUZZ_JOBS at a time, each target's corpus kept in
# build/fuzz-work/ from run to run (FUZZ_TARGETS="a b" for some of them). docs/reliability.md.
FUZZ_LONG_SECONDS ?= 1800
FUZZ_JOBS ?= 1
fuzz-long: fuzz
	@mkdir -p build/fuzz-work
	@JOBS=$(FUZZ_JOBS) FUZZ_WORK=$(CURDIR)/build/fuzz-work bash fuzz/smoke.sh build/asan $(FUZZ_LONG_SECONDS)

clean:
	rm -rf build
