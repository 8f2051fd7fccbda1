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

# `make test`: rigpose-sim's score of the filters' clock-offset states (test_sim_offsets.sh), and
# gc's published covariance on a fresh seed (test_sim_nees.sh).
HOST_EXTRA_TESTS += host_tools/sim/test_sim_offsets.sh host_tools/sim/test_sim_nees.sh
test: $(REL)/rigpose-sim

# The consistency of the published pose covariances (issue 16): mean NEES of stereo4, stereo2
# and gc over NEES_RUNS runs of the Table 1 protocol on NEES_SEED, a seed chosen after gc's
# consider terms were set on seed 1 (rp_vo_gc.h step 5), so one they never saw; the test above
# uses it too. Writes $(BUILD)/bench/nees.json (nees_<method>, _t, _r; nees_seed).
NEES_SEED ?= 20261205
export NEES_SEED
NEES_RUNS ?= $(if $(filter 1,$(QUICK)),10,50)

BENCH_PARTS += $(BUILD)/bench/nees.json
$(BUILD)/bench/nees.json: $(REL)/rigpose-sim FORCE
	@mkdir -p $(BUILD)/bench
	$(REL)/rigpose-sim --methods stereo4,stereo2,gc --runs $(NEES_RUNS) --seed $(NEES_SEED) \
	    --json > $(BUILD)/bench/nees_sim.json
	$(PY) -c 'import json, sys; d = json.load(open(sys.argv[1])); \
	    f = {"nees_seed": d["seed"], "nees_runs": d["runs"]}; \
	    [f.update({"nees_%s%s" % (r["method"], s): r["nees" + s] for s in ("", "_t", "_r")}) \
	     for r in d["rows"]]; \
	    print("nees (mean, 6 / 3 / 3 for a consistent covariance):", json.dumps(f, sort_keys=True)); \
	    json.dump(f, open(sys.argv[2], "w"), indent=1, sort_keys=True)' \
	    $(BUILD)/bench/nees_sim.json $@

# Issue 14's gross outliers on the Table 1 protocol: stereo4 and gc clean, with 30 % of every
# camera's features uniform pixels (rigpose-sim --outliers), and the same with the plain gated
# update (--plain-update): the ratios to the clean runs (outliers_30_<method>_<col>_ratio,
# outliers_30_plain_...) in $(BUILD)/bench/outliers.json. Target: the defaults within 1.5.
OUTLIER_RUNS ?= $(if $(filter 1,$(QUICK)),5,50)
OUTLIER_SIM = $(REL)/rigpose-sim --methods stereo4,gc --runs $(OUTLIER_RUNS) --seed 1 --json

BENCH_PARTS += $(BUILD)/bench/outliers.json
$(BUILD)/bench/outliers.json: $(REL)/rigpose-sim host_tools/sim/outliers_bench.py FORCE
	@mkdir -p $(BUILD)/bench
	$(OUTLIER_SIM) > $(BUILD)/bench/outliers_clean.json
	$(OUTLIER_SIM) --outliers 0.3 > $(BUILD)/bench/outliers_robust.json
	$(OUTLIER_SIM) --outliers 0.3 --plain-update > $(BUILD)/bench/outliers_plain.json
	$(PY) host_tools/sim/outliers_bench.py $(BUILD)/bench/outliers_clean.json \
	    $(BUILD)/bench/outliers_robust.json $(BUILD)/bench/outliers_plain.json $@
