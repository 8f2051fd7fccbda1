# host_tools/research/bench/bench.mk - `make bench` (included by the top-level Makefile).
#
#   make bench            all sections (BENCH_PARTS); prints tables, writes $(BUILD)/bench.json
#   make bench QUICK=1    short version (3 runs instead of 20)
#   make $(REL)/rigpose-bench   just the program
#
# The program (host_tools/research/bench/bench_pose.cpp) links the release core and the simulator
# with OpenGV and OpenCV. It is host-only C++ with exceptions (OpenCV needs them) and
# heap-using Eigen (OpenGV), so it does not use the core's CXXSTD / EIGEN flags; the core's
# scalar choice must match the release library (double, Eigen backend).

BENCH_BIN  := $(REL)/rigpose-bench
BENCH_SRC  := host_tools/research/bench/bench_pose.cpp
BENCH_RUNS ?= $(if $(filter 1,$(QUICK)),3,20)
BENCH_FRAMES ?= 100
BENCH_SEED ?= 1
BENCH_ARGS ?= --runs $(BENCH_RUNS) --frames $(BENCH_FRAMES) --seed $(BENCH_SEED)

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
BENCH_CXXFLAGS = -std=c++14 -O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 \
    $(WARN) -isystem /usr/include/eigen3 \
    $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) $(INC)
BENCH_LIBS = -lopengv -lopencv_calib3d -lopencv_core -lpthread -lm

$(BENCH_BIN): $(BENCH_SRC) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
              $(wildcard core/include/rigpose/*.h platform/sim/*.h) | deps
	$(CXX) $(BENCH_CXXFLAGS) $(BENCH_SRC) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
	    -o $@ $(BENCH_LIBS)

BENCH_PARTS += $(BUILD)/bench/pose.json
$(BUILD)/bench/pose.json: $(BENCH_BIN) FORCE
	@mkdir -p $(BUILD)/bench
	$(BENCH_BIN) $(BENCH_ARGS) --out $@

RESEARCH_TOOLS += $(BENCH_BIN)
