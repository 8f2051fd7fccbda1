# host_tools/sim/sim.mk - the layout study's section of `make bench` (included by the Makefile).
#
# Runs `rigpose-sim --layout-study` (the built-in grid of 27 cam2/cam4 placements, gc only,
# LAYOUT_RUNS runs each, seed 1), prints the ranking and writes $(BUILD)/bench/layout.json:
# the best placement's and the paper's gc errors (layout_best_*, layout_paper_*), the paper's
# rank and the best placement's cam2 offset and yaw (cam4 is its mirror image).

LAYOUT_RUNS ?= $(if $(filter 1,$(QUICK)),3,20)

BENCH_PARTS += $(BUILD)/bench/layout.json
$(BUILD)/bench/layout.json: $(REL)/rigpose-sim host_tools/sim/layout_bench.py FORCE
	@mkdir -p $(BUILD)/bench
	$(REL)/rigpose-sim --layout-study --methods gc --runs $(LAYOUT_RUNS) --seed 1 --json \
	    > $(BUILD)/bench/layout_study.json
	$(PY) host_tools/sim/layout_bench.py $(BUILD)/bench/layout_study.json $@

# `make test`: rigpose-sim's score of the filters' clock-offset states (test_sim_offsets.sh).
HOST_EXTRA_TESTS += host_tools/sim/test_sim_offsets.sh
test: $(REL)/rigpose-sim
