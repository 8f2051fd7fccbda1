# rigpose - one Makefile for everything (host build, tests, cross build, benchmarks).
#
#   make            core, platform (HAL, simulation library), the daemon and the user tools
#   make run        main job: the rigpose daemon on the simulated rig, poses printed and on LCM
#   make check      fast tier: the unit tests of the double / Eigen core, no sanitizer, parallel
#   make test       every host test, in every numeric / linear-algebra variant, under ASan+UBSan,
#                   integration, VM and real-data tests (what .ci/run runs)
#   make research   research and benchmark programs (host_tools/research/)
#   make cross      aarch64 build of the core (float, double) and the daemon
#   make test-arm   the core's tests, cross-built for aarch64, run under qemu-aarch64
#   make bench      benchmarks; prints figures and writes build/bench.json (QUICK=1: short)
#   make fuzz       every libFuzzer target of tests/fuzz/ for FUZZ_S seconds (default 60)
#
# The first make on a machine runs scripts/install-deps.sh, which installs what is missing.

SHELL := /bin/bash
BUILD ?= build
JOBS ?= $(shell nproc)

CC  ?= gcc
CXX ?= g++
ifeq ($(origin CC),default)
CC := gcc
endif
ifeq ($(origin CXX),default)
CXX := g++
endif
CROSS_PREFIX ?= aarch64-linux-gnu-
comma := ,

# ---- sources ---------------------------------------------------------------------------------
# core/src/<stage>/*.c|cpp: base, math, geometry, frontend, estimation, layouts, pipeline
# (private headers in core/src/priv/); platform/sim/: the simulation library (the paper's
# Table 1 protocol), used by the sim source, the tools and the tests.
CORE_C   := $(sort $(wildcard core/src/*/*.c))
CORE_CXX := $(sort $(wildcard core/src/*/*.cpp))
SIMLIB_C := $(sort $(wildcard platform/sim/*.c))
TESTS    := $(sort $(basename $(notdir $(wildcard tests/unit/test_*.c))))

INC := -Icore/include -Iplatform/sim
CORE_INC := $(INC) -Icore/src

WARN      := -Wall -Wextra -Werror -Wshadow
CORE_WARN := $(WARN) -Wdouble-promotion -Wconversion -Wno-sign-conversion
CSTD      := -std=c99
CXXSTD    := -std=c++14 -fno-exceptions -fno-rtti
EIGEN     := -I/usr/include/eigen3 -DEIGEN_NO_MALLOC -DEIGEN_DONT_PARALLELIZE
SAN       := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
# Header dependencies: every compile writes a .d file beside its output (read at the end).
DEPFLAGS   = -MMD -MP -MF $@.d -MT $@

# ---- variants --------------------------------------------------------------------------------
# name: real type x linear-algebra backend; tests run in all of them.
VARIANTS := double-eigen float-eigen double-c float-c
VDEF_double-eigen := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1
VDEF_float-eigen  := -DRP_REAL_IS_FLOAT=1 -DRP_LINALG_EIGEN=1
VDEF_double-c     := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=0
VDEF_float-c      := -DRP_REAL_IS_FLOAT=1 -DRP_LINALG_EIGEN=0

.PHONY: all deps deps-cross run test test-arm check cross bench research clean tools \
        check-nomalloc run-tests FORCE
all: tools

# The Python of the PyPI packages (.venv/, or $RIGPOSE_VENV); exported: the test scripts use $PY.
export PY := $(or $(RIGPOSE_VENV),$(CURDIR)/.venv)/bin/python

# Packages: scripts/install-deps.sh runs only when its stamp is missing or older than the
# script (a clean clone, `make clean`, a changed package list), never on a no-op `make`. The
# stamp is an included makefile: make brings it up to date before it reads on and starts on
# the goals, so the packages are in place before any rule runs, also under -jN (lcm-gen, Eigen
# and cmocka must exist before the first compile).
DEPS_STAMP := $(BUILD)/.deps/host.mk
ifneq ($(filter-out clean,$(or $(MAKECMDGOALS),all)),)
include $(DEPS_STAMP)
ifneq ($(filter cross test-arm,$(MAKECMDGOALS)),)
include $(BUILD)/.deps/cross.mk
endif
endif
$(DEPS_STAMP): scripts/install-deps.sh $(if $(wildcard $(PY)),,FORCE)
	@scripts/install-deps.sh py && mkdir -p $(@D) && echo '# host packages installed' > $@
$(BUILD)/.deps/cross.mk: scripts/install-deps.sh
	@scripts/install-deps.sh cross && mkdir -p $(@D) && echo '# cross packages installed' > $@
# Order-only prerequisite of rules that need the packages (already installed by the include).
deps: ;
deps-cross: ;

# Template: $(1) variant, $(2) object dir, $(3) cc, $(4) cxx, $(5) extra flags, $(6) ar
define CORE_LIB
$(2)/core/%.o: core/src/%.c
	@mkdir -p $$(@D)
	$(3) $$(CSTD) $$(CORE_WARN) $$(CORE_INC) $(5) $$(DEPFLAGS) -c $$< -o $$@
$(2)/core/%.o: core/src/%.cpp
	@mkdir -p $$(@D)
	$(4) $$(CXXSTD) $$(WARN) $$(EIGEN) $$(CORE_INC) $(5) $$(DEPFLAGS) -c $$< -o $$@
$(2)/sim/%.o: platform/sim/%.c
	@mkdir -p $$(@D)
	$(3) $$(CSTD) $$(WARN) -D_POSIX_C_SOURCE=200809L $$(INC) $(5) $$(DEPFLAGS) -c $$< -o $$@
$(2)/librigpose_core.a: $$(patsubst core/src/%.c,$(2)/core/%.o,$$(CORE_C)) $$(patsubst core/src/%.cpp,$(2)/core/%.o,$$(CORE_CXX))
	rm -f $$@ && $(6) rcs $$@ $$^
$(2)/librigpose_sim.a: $$(patsubst platform/sim/%.c,$(2)/sim/%.o,$$(SIMLIB_C))
	rm -f $$@ && $(6) rcs $$@ $$^
endef

# A test program from one C file: $(1) variant dir, $(2) cc, $(3) flags, $(4) link flags
define UNIT_TEST
$(1)/tests/%: tests/unit/%.c $(1)/librigpose_sim.a $(1)/librigpose_core.a
	@mkdir -p $$(@D)
	$(2) $$(CSTD) $$(WARN) -D_POSIX_C_SOURCE=200809L $$(CORE_INC) -Itests $(3) $$(DEPFLAGS) $$< \
	    $(1)/librigpose_sim.a $(1)/librigpose_core.a -o $$@ $(4)
endef

# Host test variants (sanitised, -O1 -g).
define HOST_VARIANT
$(call CORE_LIB,$(1),$(BUILD)/$(1),$(CC),$(CXX),-O1 -g $(SAN) $(VDEF_$(1)),ar)
$(call UNIT_TEST,$(BUILD)/$(1),$(CC),-O1 -g $(SAN) $(VDEF_$(1)),$(SAN) -lcmocka -lstdc++ -lm)
endef
$(foreach v,$(VARIANTS),$(eval $(call HOST_VARIANT,$(v))))

HOST_TEST_BINS := $(foreach v,$(VARIANTS),$(addprefix $(BUILD)/$(v)/tests/,$(TESTS)))

# Release build for the tools (double, Eigen, -O2).
REL := $(BUILD)/release
$(eval $(call CORE_LIB,release,$(REL),$(CC),$(CXX),-O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1,ar))

# ThreadSanitizer build of the core (double, Eigen) for the threaded daemon's test
# (daemon/daemon.mk: test_threads): the trackers run on the pool's threads.
TSAN := -fsanitize=thread
$(eval $(call CORE_LIB,tsan,$(BUILD)/tsan,$(CC),$(CXX),-O1 -g $(TSAN) $(VDEF_double-eigen),ar))

# The fast tier: the unit tests of one variant (double, Eigen), no sanitizer, -O1.
CHK := $(BUILD)/check
$(eval $(call CORE_LIB,check,$(CHK),$(CC),$(CXX),-O1 -g $(VDEF_double-eigen),ar))
$(eval $(call UNIT_TEST,$(CHK),$(CC),-O1 -g $(VDEF_double-eigen),-lcmocka -lstdc++ -lm))
CHECK_BINS := $(addprefix $(CHK)/tests/,$(TESTS))

TOOLS := $(REL)/rigpose-sim
tools: $(TOOLS)

$(REL)/rigpose-sim: host_tools/sim/rigpose_sim.c $(REL)/librigpose_sim.a $(REL)/librigpose_core.a
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(INC) -O2 -g $(DEPFLAGS) $< $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ -lpthread -lstdc++ -lm

# ---- the main job ----------------------------------------------------------------------------
# The daemon on the embedded default (config/sim.yaml: the simulated rig of Table 1, stereo4,
# paced at 30 Hz), printing poses with their error against the simulated truth and publishing
# them on LCM; 300 frame sets (10 s) by default; RUN_ARGS="--frames N" runs N (the simulated run
# is generated at start, up to 100,000 sets; Ctrl-C stops it earlier with the summary).
RUN_ARGS ?= --frames 300
run: deps $(REL)/rigpose
	$(REL)/rigpose --config config/sim.yaml $(RUN_ARGS)

# ---- tests -----------------------------------------------------------------------------------
# A test is a program or a script that prints cmocka's summary lines ("[  PASSED  ] N test(s)",
# "[  FAILED  ] N", "[  SKIPPED ] N test(s)..." with the reason) and exits 0 when nothing failed.
# `make test`, `make check` and `make test-arm` first build everything their tests need, then
# `run-tests` runs the list, each test into its own log under $(BUILD)/results/<set>/ (so they
# run in parallel under -jN; tests in SERIAL_TESTS share the multicast group and take a lock),
# then tests/summary.sh prints every log in order and "tests: N passed, N failed, N skipped".
SERIAL_TESTS :=
RESULTS = $(BUILD)/results/$(RESULTS_SET)
test_log = $(RESULTS)/$(subst /,__,$(1)).log
define TEST_RUN_RULE
$(call test_log,$(1)): FORCE
	@$(if $(filter $(1),$(SERIAL_TESTS)),flock $(BUILD)/results/.serial.lock )tests/run_one.sh $(1) $$@
endef

test: deps $(HOST_TEST_BINS) check-nomalloc
	@$(MAKE) --no-print-directory run-tests RESULTS_SET=host \
	    TEST_LIST="$(strip $(HOST_TEST_BINS) $(HOST_EXTRA_TESTS))"

# `make check`: the fast inner loop (unit tests of the double / Eigen core, no sanitizer).
check: deps $(CHECK_BINS)
	@$(MAKE) --no-print-directory run-tests RESULTS_SET=check TEST_LIST="$(CHECK_BINS)"

ifneq ($(TEST_LIST),)
run-tests: $(foreach t,$(TEST_LIST),$(call test_log,$(t)))
	@tests/summary.sh $^
$(foreach t,$(TEST_LIST),$(eval $(call TEST_RUN_RULE,$(t))))
endif

# The core never references the heap: check the symbols of every built core library.
check-nomalloc: $(foreach v,$(VARIANTS),$(BUILD)/$(v)/librigpose_core.a) $(REL)/librigpose_core.a
	@for lib in $^; do \
	  if nm -u $$lib | grep -wE 'malloc|calloc|realloc|free|_Znwm|_Znam|_ZdlPv|_ZdaPv'; then \
	    echo "FAIL: $$lib references the heap"; exit 1; fi; done; \
	echo "check-nomalloc: no heap symbol in $(words $^) core libraries"

# ---- cross build (aarch64) -------------------------------------------------------------------
ARM := $(BUILD)/arm64
ARM_VARIANTS := float double
ARMDEF_float  := -DRP_REAL_IS_FLOAT=1 -DRP_LINALG_EIGEN=1
ARMDEF_double := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1
define ARM_VARIANT
$(call CORE_LIB,arm-$(1),$(ARM)/$(1),$(CROSS_PREFIX)gcc,$(CROSS_PREFIX)g++,-O2 -g $(ARMDEF_$(1)),$(CROSS_PREFIX)ar)
$(call UNIT_TEST,$(ARM)/$(1),$(CROSS_PREFIX)gcc,-O2 -g $(ARMDEF_$(1)),-L/usr/lib/aarch64-linux-gnu -Wl$(comma)-rpath-link$(comma)/usr/lib/aarch64-linux-gnu -lcmocka -lstdc++ -lm)
endef
$(foreach v,$(ARM_VARIANTS),$(eval $(call ARM_VARIANT,$(v))))
ARM_TEST_BINS := $(foreach v,$(ARM_VARIANTS),$(addprefix $(ARM)/$(v)/tests/,$(TESTS)))

cross: deps-cross $(ARM)/float/librigpose_core.a $(ARM)/double/librigpose_core.a
	@$(CROSS_PREFIX)size -t $(ARM)/float/librigpose_core.a | tail -1

test-arm: deps-cross $(ARM_TEST_BINS)
	@QEMU_LD_PREFIX=/usr/aarch64-linux-gnu RP_TEST_RUNNER=qemu-aarch64 $(MAKE) --no-print-directory \
	    run-tests RESULTS_SET=arm TEST_LIST="$(strip $(ARM_TEST_BINS) $(ARM_EXTRA_TESTS))"

# ---- parts in their own makefiles -------------------------------------------------------------
# Each folder that builds something beyond the core keeps a *.mk here (host_tools/<tool>/*.mk,
# host_tools/research/<tool>/*.mk, platform/*.mk, lcm_types/*.mk, daemon/*.mk, tests/*/*.mk,
# docs/*.mk).
# A part may
#   - add what users run to EXTRA_TOOLS (built by a plain `make`),
#   - add research and benchmark programs to RESEARCH_TOOLS (built by `make research`, and by
#     `make test` / `make bench` where a test or a section needs them),
#   - add test programs to HOST_EXTRA_TESTS and `test: <what they need>` (run by `make test`),
#     and those that use the LCM multicast group to SERIAL_TESTS too,
#   - add ARM test programs to ARM_EXTRA_TESTS and `test-arm: <programs>`,
#   - add benchmark sections to BENCH_PARTS: each is a file $(BUILD)/bench/<name>.json holding
#     one flat JSON object of figures, made by a rule that depends on FORCE (so it always runs)
#     and prints its own table; `make bench` merges them all into $(BUILD)/bench.json.
EXTRA_TOOLS :=
RESEARCH_TOOLS :=
HOST_EXTRA_TESTS :=
ARM_EXTRA_TESTS :=
BENCH_PARTS :=
-include $(sort $(wildcard host_tools/*/*.mk host_tools/research/*/*.mk platform/*.mk docs/*.mk \
                           lcm_types/*.mk daemon/*.mk tests/*/*.mk))

tools: $(EXTRA_TOOLS)
research: $(RESEARCH_TOOLS)

bench: deps $(BENCH_PARTS)
	@$(PY) host_tools/research/bench/merge_json.py $(BUILD)/bench.json $(BENCH_PARTS)

FORCE:

clean:
	rm -rf $(BUILD)

# Header dependencies written by the compiles (-MMD -MP).
ifneq ($(filter-out clean,$(or $(MAKECMDGOALS),all)),)
-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
endif
