# host_tools/ba/ba.mk - rigpose-ba, the offline optimum as a yardstick (issue 16; included by the
# top-level Makefile). Host-only C++ on Ceres Solver (Debian libceres-dev), never linked into
# core/ or the daemon.
#
#   make $(REL)/rigpose-ba      the program (also built by `make research`)
#   make test                   $(BUILD)/ba/test_ba (ASan + UBSan, the sanitised double/Eigen
#                               core): the residual against the core's eq. 2, the noise-free
#                               optimum, the bound's scaling and gauge, batch vs rigpose vs bound
#                               on a few simulated runs
#   make bench                  section "ba": $(BUILD)/bench/ba.json, the Table 1 protocol
#                               (BA_RUNS runs, seed 1) for stereo4, stereo2 and gc:
#                               ba_<method>_ratio_t / _r (rigpose / batch optimum, mean abs.
#                               translation / rotation error), ba_<method>_crb_t / _r ...; and
#                               per real clip in $(RD_DATA) rigpose's ATE beside the batch
#                               optimum over rigpose's own tracks (rigpose-realdata
#                               --tracks-out): ba_<clip>_rigpose_ate_m, _batch_ate_m, _ratio_ate

# This file is read before eval.mk, common.mk, lcm_types.mk and realdata.mk (the includes are
# sorted), so their variables are not set yet where prerequisites are expanded: the paths of
# their outputs are spelled out here (rp_eval.o, rp_lcmlog.o, the LCM bindings, rigpose-realdata).
BA_DIR := $(BUILD)/ba
BA_BIN := $(REL)/rigpose-ba
BA_TEST := $(BA_DIR)/test_ba
BA_LIB_SRC := host_tools/ba/rp_ba.cpp host_tools/ba/rp_tracks.cpp
BA_HDR := $(wildcard host_tools/ba/*.hpp core/include/rigpose/*.h platform/sim/*.h) \
    host_tools/eval/rp_eval.hpp

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
BA_CXXFLAGS = -std=c++17 -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 $(WARN) \
    -isystem /usr/include/eigen3 $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) \
    $(INC) -Ihost_tools/ba -Ihost_tools/eval
BA_LIBS = -lceres -lglog -lgflags -lpthread -lm

BA_EVAL_OBJ := $(BUILD)/eval/rp_eval.o $(BUILD)/common/rp_lcmlog.o
$(BA_BIN): host_tools/ba/rigpose_ba.cpp $(BA_LIB_SRC) $(BA_HDR) $(BA_EVAL_OBJ) \
           $(BUILD)/lcmgen/librigpose_lcm.a $(REL)/librigpose_sim.a $(REL)/librigpose_core.a | deps
	@mkdir -p $(@D)
	$(CXX) $(BA_CXXFLAGS) -O2 -g -DNDEBUG $< $(BA_LIB_SRC) $(BA_EVAL_OBJ) \
	    $(REL)/librigpose_sim.a -o $@ $(EVAL_LIBS) $(BA_LIBS)

# The test: sanitised, against the sanitised double/Eigen core and simulator (Ceres, glog and
# OpenCV themselves are not instrumented).
BA_SAN_CORE := $(BUILD)/double-eigen
$(BA_TEST): host_tools/ba/test_ba.cpp $(BA_LIB_SRC) $(BA_HDR) $(BA_SAN_CORE)/librigpose_sim.a \
            $(BA_SAN_CORE)/librigpose_core.a | deps
	@mkdir -p $(@D)
	$(CXX) $(BA_CXXFLAGS) -O1 -g $(SAN) $< $(BA_LIB_SRC) $(BA_SAN_CORE)/librigpose_sim.a \
	    $(BA_SAN_CORE)/librigpose_core.a -o $@ $(SAN) $(BA_LIBS)

RESEARCH_TOOLS += $(BA_BIN)
HOST_EXTRA_TESTS += $(BA_TEST)
test: $(BA_TEST)

# ---- make bench: section "ba" ----------------------------------------------------------------
BA_RUNS ?= $(if $(filter 1,$(QUICK)),5,50)
BA_CLIP_FRAMES ?= $(if $(filter 1,$(QUICK)),40,)
# clip name, folder option, frames (empty: the whole clip)
BA_CLIPS := kitti00:--kitti:kitti00_000-099 kitti_raw0005:--kitti:kitti_raw_0926_0005_000-090 \
    euroc_mh01:--euroc:euroc_mh01_000-149
BA_CLIP_ARGS = $(if $(BA_CLIP_FRAMES),--frames $(BA_CLIP_FRAMES),)
BENCH_PARTS += $(BUILD)/bench/ba.json
$(BUILD)/bench/ba.json: $(BA_BIN) $(REL)/rigpose-realdata FORCE
	@mkdir -p $(BUILD)/bench $(BA_DIR)
	nice $(BA_BIN) --sim --methods stereo4,stereo2,gc --runs $(BA_RUNS) --seed 1 \
	    --json $(BA_DIR)/sim.json
	@parts="$(BA_DIR)/sim.json"; \
	for c in $(BA_CLIPS); do \
	  name=$${c%%:*}; rest=$${c#*:}; opt=$${rest%%:*}; dir=$(RD_DATA)/$${rest#*:}; \
	  if [ -d "$$dir" ]; then \
	    echo "ba: $$name: rigpose-realdata $$opt $$dir --tracks-out $(BA_DIR)/$$name.tracks"; \
	    nice $(RD_BIN) $$opt $$dir $(BA_CLIP_ARGS) --quiet --tracks-out $(BA_DIR)/$$name.tracks \
	        > $(BA_DIR)/$$name.realdata.txt || exit 1; \
	    nice $(BA_BIN) --tracks $(BA_DIR)/$$name.tracks --name $$name \
	        --json $(BA_DIR)/$$name.json || exit 1; \
	    parts="$$parts $(BA_DIR)/$$name.json"; \
	  else echo "ba: $$name: no data in $$dir (set RIGPOSE_DATA): figures left out"; fi; \
	done; \
	$(PY) host_tools/research/bench/merge_json.py $@ $$parts
