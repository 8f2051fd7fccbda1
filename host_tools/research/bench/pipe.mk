# host_tools/research/bench/pipe.mk - `make bench` section "pipe" (included by the top-level Makefile): stereo
# matching (rp_smatch) and the image pipeline (rp_pipe) on rendered frames of the paper's rig in
# a textured room (host_tools/research/bench/bench_pipe.c, release core: double, Eigen, -O2). QUICK=1: 8 frames.

PIPE_BENCH := $(REL)/bench_pipe
PIPE_BENCH_FRAMES ?= $(if $(filter 1,$(QUICK)),8,30)

$(PIPE_BENCH): host_tools/research/bench/bench_pipe.c tests/img_fixture.h $(REL)/librigpose_sim.a \
               $(REL)/librigpose_core.a $(wildcard core/include/rigpose/*.h platform/sim/*.h)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(INC) -Itests -Ihost_tools/research/bench -O2 -g -DNDEBUG \
	    -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 $< $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ -lstdc++ -lm

BENCH_PARTS += $(BUILD)/bench/pipe.json
$(BUILD)/bench/pipe.json: $(PIPE_BENCH) FORCE
	@mkdir -p $(BUILD)/bench
	$(PIPE_BENCH) --frames $(PIPE_BENCH_FRAMES) --out $@

RESEARCH_TOOLS += $(PIPE_BENCH)
