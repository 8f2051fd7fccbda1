# host_tools/research/bench/threads.mk - `make bench` section "threads" (included by the
# top-level Makefile): the daemon's image pipeline on 1 and 2 threads, on a rendered 4-camera
# 640x480 replay (bench_threads.sh). QUICK=1: 30 sets instead of 100.

THREADS_BENCH_FRAMES ?= $(if $(filter 1,$(QUICK)),30,100)

BENCH_PARTS += $(BUILD)/bench/threads.json
$(BUILD)/bench/threads.json: $(REL)/rigpose $(REL)/rigpose-render $(BUILD)/lcmgen/stamp FORCE
	@mkdir -p $(dir $@)
	host_tools/research/bench/bench_threads.sh $(BUILD) $@ $(THREADS_BENCH_FRAMES)
