# host_tools/research/e2e/e2e.mk - rigpose-e2e: rendered pixels -> the core's image pipeline -> poses,
# scored like rigpose-sim (included by the top-level Makefile; this file is read before
# host_tools/render/render.mk, so the render library's path is spelled out here).
#
#   make $(REL)/rigpose-e2e     the program
#   make test                   runs host_tools/research/e2e/test_e2e.sh (a short run, loose bounds)
#   make bench                  $(BUILD)/bench/render.json (render_stereo4_tx_m, render_gc_tx_m),
#                               render_points.json (the same on the points scene) and
#                               render_moving.json (the moving object, bench_moving.py)

E2E_BIN := $(REL)/rigpose-e2e
E2E_RENDER_LIB := $(BUILD)/render/librp_render.a
E2E_DEPS := host_tools/research/e2e/rigpose_e2e.cpp $(E2E_RENDER_LIB) $(REL)/librigpose_sim.a \
    $(REL)/librigpose_core.a $(wildcard host_tools/render/*.hpp core/include/rigpose/*.h)

$(E2E_BIN): $(E2E_DEPS)
	$(CXX) $(RENDER_CXXFLAGS) $< $(E2E_RENDER_LIB) $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ $(RENDER_LIBS)

RESEARCH_TOOLS += $(E2E_BIN)

# make test: 320x240, 25 frames, one run, stereo4 and gc with loose bounds on the mean tx error.
HOST_EXTRA_TESTS += host_tools/research/e2e/test_e2e.sh
test: $(E2E_BIN)
export RP_E2E_BIN = $(E2E_BIN)

# make bench: the issue's figures at 640x480, 100 frames, the paper's motion (QUICK=1: 1 run), one sample per pixel.
E2E_BENCH_RUNS ?= $(if $(filter 1,$(QUICK)),1,3)
BENCH_PARTS += $(BUILD)/bench/render.json
$(BUILD)/bench/render.json: $(E2E_BIN) FORCE
	@mkdir -p $(BUILD)/bench
	$(E2E_BIN) --methods stereo4,gc --runs $(E2E_BENCH_RUNS) --frames 100 --ss 1 --json-out $@

# The same on the points scene (rp_sim's own points as discs): render_points_<method>_..._m.
BENCH_PARTS += $(BUILD)/bench/render_points.json
$(BUILD)/bench/render_points.json: $(E2E_BIN) FORCE
	@mkdir -p $(BUILD)/bench
	$(E2E_BIN) --methods stereo4,gc --runs $(E2E_BENCH_RUNS) --frames 100 --ss 1 --points \
	    --json-out $@

# The moving object, with and without 1-point RANSAC, against render.json's static runs.
BENCH_PARTS += $(BUILD)/bench/render_moving.json
$(BUILD)/bench/render_moving.json: $(E2E_BIN) $(BUILD)/bench/render.json FORCE
	@mkdir -p $(BUILD)/bench
	$(PY) host_tools/research/e2e/bench_moving.py $(E2E_BIN) $(BUILD)/bench/render.json $@ \
	    $(E2E_BENCH_RUNS)
