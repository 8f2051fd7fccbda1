# rigpose - one Makefile for everything (host build, tests, cross build, benchmarks).
#
#   make            host build (core library variants + tools)
#   make run        main job: the rigpose daemon on the simulated rig, poses printed and on LCM
#   make test       every host test, in every numeric / linear-algebra variant, under ASan+UBSan
#   make cross      aarch64 build of the core (float) and tools that need only the core
#   make test-arm   the core's tests, cross-built for aarch64, run under qemu-aarch64
#   make bench      benchmarks; prints figures and writes build/bench.json (QUICK=1: short)
#
# Every target first runs scripts/install-deps.sh, which installs only what is missing.

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

# ---- sources ---------------------------------------------------------------------------------
CORE_C   := $(sort $(wildcard core/src/*.c))
CORE_CXX := $(sort $(wildcard core/src/*.cpp))
SIMLIB_C := $(sort $(wildcard host_tools/sim/lib/*.c))
TESTS    := $(sort $(basename $(notdir $(wildcard tests/test_*.c))))

INC := -Icore/include -Ihost_tools/sim/lib

WARN      := -Wall -Wextra -Werror -Wshadow
CORE_WARN := $(WARN) -Wdouble-promotion -Wconversion -Wno-sign-conversion
CSTD      := -std=c99
CXXSTD    := -std=c++14 -fno-exceptions -fno-rtti
EIGEN     := -I/usr/include/eigen3 -DEIGEN_NO_MALLOC -DEIGEN_DONT_PARALLELIZE
SAN       := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer

# ---- variants --------------------------------------------------------------------------------
# name: real type x linear-algebra backend; tests run in all of them.
VARIANTS := double-eigen float-eigen double-c float-c
VDEF_double-eigen := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1
VDEF_float-eigen  := -DRP_REAL_IS_FLOAT=1 -DRP_LINALG_EIGEN=1
VDEF_double-c     := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=0
VDEF_float-c      := -DRP_REAL_IS_FLOAT=1 -DRP_LINALG_EIGEN=0

.PHONY: all deps deps-cross run test test-arm cross bench clean tools check-nomalloc FORCE
all: deps tools

# `deps` covers the host build and the Python side (.venv/ with PyPI's lcm and evo).
deps:
	@scripts/install-deps.sh py
deps-cross:
	@scripts/install-deps.sh cross

# On a fresh machine the packages must be in place before any rule runs, also under -jN (a
# prerequisite `deps` runs beside the others: lcm-gen, Eigen or cmocka would be missing). An
# included makefile is brought up to date before make reads on and starts on the goals, so its
# rule installs first; the stamps live in $(BUILD), so a clean clone or `make clean` installs
# (that is, checks) again.
ifneq ($(filter-out clean,$(or $(MAKECMDGOALS),all)),)
include $(BUILD)/.deps/host.mk
ifneq ($(filter cross test-arm,$(MAKECMDGOALS)),)
include $(BUILD)/.deps/cross.mk
endif
endif
$(BUILD)/.deps/host.mk: scripts/install-deps.sh
	@scripts/install-deps.sh py && mkdir -p $(@D) && echo '# host packages installed' > $@
$(BUILD)/.deps/cross.mk: scripts/install-deps.sh
	@scripts/install-deps.sh cross && mkdir -p $(@D) && echo '# cross packages installed' > $@

# Template: $(1) variant, $(2) object dir, $(3) cc, $(4) cxx, $(5) extra flags, $(6) ar
define CORE_LIB
$(2)/core/%.o: core/src/%.c $$(wildcard core/include/rigpose/*.h) | $(2)/core
	$(3) $$(CSTD) $$(CORE_WARN) $$(INC) $(5) -c $$< -o $$@
$(2)/core/%.o: core/src/%.cpp $$(wildcard core/include/rigpose/*.h) | $(2)/core
	$(4) $$(CXXSTD) $$(WARN) $$(EIGEN) $$(INC) $(5) -c $$< -o $$@
$(2)/sim/%.o: host_tools/sim/lib/%.c $$(wildcard core/include/rigpose/*.h host_tools/sim/lib/*.h) | $(2)/sim
	$(3) $$(CSTD) $$(WARN) -D_POSIX_C_SOURCE=200809L $$(INC) $(5) -c $$< -o $$@
$(2)/librigpose_core.a: $$(patsubst core/src/%.c,$(2)/core/%.o,$$(CORE_C)) $$(patsubst core/src/%.cpp,$(2)/core/%.o,$$(CORE_CXX))
	rm -f $$@ && $(6) rcs $$@ $$^
$(2)/librigpose_sim.a: $$(patsubst host_tools/sim/lib/%.c,$(2)/sim/%.o,$$(SIMLIB_C))
	rm -f $$@ && $(6) rcs $$@ $$^
$(2)/core $(2)/sim $(2)/tests:
	mkdir -p $$@
endef

# Host test variants (sanitised, -O1 -g).
define HOST_VARIANT
$(call CORE_LIB,$(1),$(BUILD)/$(1),$(CC),$(CXX),-O1 -g $(SAN) $(VDEF_$(1)),ar)
$(BUILD)/$(1)/tests/%: tests/%.c $$(wildcard tests/*.h) $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a | $(BUILD)/$(1)/tests
	$(CC) $$(CSTD) $$(WARN) -D_POSIX_C_SOURCE=200809L $$(INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) $$< \
	    $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a -o $$@ \
	    $(SAN) -lcmocka -lstdc++ -lm
endef
$(foreach v,$(VARIANTS),$(eval $(call HOST_VARIANT,$(v))))

HOST_TEST_BINS := $(foreach v,$(VARIANTS),$(addprefix $(BUILD)/$(v)/tests/,$(TESTS)))

# Release build for the tools (double, Eigen, -O2).
REL := $(BUILD)/release
$(eval $(call CORE_LIB,release,$(REL),$(CC),$(CXX),-O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1,ar))

TOOLS := $(REL)/rigpose-sim
tools: $(TOOLS)

$(REL)/rigpose-sim: host_tools/sim/rigpose_sim.c $(REL)/librigpose_sim.a $(REL)/librigpose_core.a
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(INC) -O2 -g $< $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ -lpthread -lstdc++ -lm

# ---- the main job ----------------------------------------------------------------------------
# The daemon on the embedded default (config/sim.yaml: the simulated rig of Table 1, stereo4,
# paced at 30 Hz), printing poses with their error against the simulated truth and publishing
# them on LCM; 300 frame sets (10 s) by default, RUN_ARGS= runs until Ctrl-C.
RUN_ARGS ?= --frames 300
run: deps $(REL)/rigpose
	$(REL)/rigpose --config config/sim.yaml $(RUN_ARGS)

# ---- tests -----------------------------------------------------------------------------------
test: deps $(HOST_TEST_BINS) check-nomalloc
	@tests/run_tests.sh $(HOST_TEST_BINS) $(HOST_EXTRA_TESTS)

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
$(ARM)/$(1)/tests/%: tests/%.c $$(wildcard tests/*.h) $(ARM)/$(1)/librigpose_sim.a $(ARM)/$(1)/librigpose_core.a | $(ARM)/$(1)/tests
	$(CROSS_PREFIX)gcc $$(CSTD) $$(WARN) -D_POSIX_C_SOURCE=200809L $$(INC) -Itests -O2 -g $(ARMDEF_$(1)) $$< \
	    $(ARM)/$(1)/librigpose_sim.a $(ARM)/$(1)/librigpose_core.a -o $$@ \
	    -L/usr/lib/aarch64-linux-gnu -Wl,-rpath-link,/usr/lib/aarch64-linux-gnu -lcmocka -lstdc++ -lm
endef
$(foreach v,$(ARM_VARIANTS),$(eval $(call ARM_VARIANT,$(v))))
ARM_TEST_BINS := $(foreach v,$(ARM_VARIANTS),$(addprefix $(ARM)/$(v)/tests/,$(TESTS)))

cross: deps-cross $(ARM)/float/librigpose_core.a $(ARM)/double/librigpose_core.a
	@$(CROSS_PREFIX)size -t $(ARM)/float/librigpose_core.a | tail -1

test-arm: deps-cross $(ARM_TEST_BINS)
	@QEMU_LD_PREFIX=/usr/aarch64-linux-gnu RP_TEST_RUNNER=qemu-aarch64 tests/run_tests.sh $(ARM_TEST_BINS) $(ARM_EXTRA_TESTS)

# ---- parts in their own makefiles -------------------------------------------------------------
# Each folder that builds something beyond the core keeps a *.mk here (host_tools/<tool>/*.mk,
# platform/*.mk, lcm_types/*.mk, daemon/*.mk, tests/*.mk). A part may
#   - add host programs to EXTRA_TOOLS (built by `make`),
#   - add test programs to HOST_EXTRA_TESTS and `test: <programs>` (run by `make test`),
#   - add ARM test programs to ARM_EXTRA_TESTS and `test-arm: <programs>`,
#   - add benchmark sections to BENCH_PARTS: each is a file $(BUILD)/bench/<name>.json holding
#     one flat JSON object of figures, made by a rule that depends on FORCE (so it always runs)
#     and prints its own table; `make bench` merges them all into $(BUILD)/bench.json.
PY := .venv/bin/python
EXTRA_TOOLS :=
HOST_EXTRA_TESTS :=
ARM_EXTRA_TESTS :=
BENCH_PARTS :=
-include $(sort $(wildcard host_tools/*/*.mk platform/*.mk lcm_types/*.mk daemon/*.mk tests/*.mk))

tools: $(EXTRA_TOOLS)

bench: deps $(BENCH_PARTS)
	@$(PY) host_tools/bench/merge_json.py $(BUILD)/bench.json $(BENCH_PARTS)

FORCE:

clean:
	rm -rf $(BUILD)
