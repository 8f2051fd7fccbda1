# host_tools/research/bench/unsync.mk - `make bench` section "unsync" (included by the top-level
# Makefile): rigpose-sim with free-running cameras against the synchronised rig
# (bench_unsync.py, docs/time.md). QUICK=1: 5 runs instead of 20.

UNSYNC_BENCH_RUNS ?= $(if $(filter 1,$(QUICK)),5,20)

BENCH_PARTS += $(BUILD)/bench/unsync.json
$(BUILD)/bench/unsync.json: $(REL)/rigpose-sim FORCE
	@mkdir -p $(dir $@)
	$(PY) host_tools/research/bench/bench_unsync.py $(REL) $@ $(UNSYNC_BENCH_RUNS)
