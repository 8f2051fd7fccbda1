# host_tools/research/benchtrack/benchtrack.mk - `make bench` section "track" (included by the top-level
# Makefile): rigpose's tracker against OpenCV's goodFeaturesToTrack + calcOpticalFlowPyrLK on the
# same rendered frames (time per 4-camera frame set, accuracy against the known warp), the
# instruction count of steady-state frame sets through rp_pipe (callgrind), and the core's static
# memory for 4 cameras at 640x480 (`size`). QUICK=1: fewer frames and repetitions.
#
#   make bench                         all sections; this one writes $(BUILD)/bench/track.json
#   make $(BUILD)/bench/track.json     this section alone

BT_DIR     := $(BUILD)/benchtrack
BT_BENCH   := $(REL)/rigpose-bench-track
BT_DRIVER  := $(REL)/rigpose-frameset-driver
BT_SCENE_O := $(BT_DIR)/bt_scene.o
BT_HDRS     = $(wildcard core/include/rigpose/*.h platform/sim/*.h host_tools/research/benchtrack/*.h)
BT_FRAMES  ?= $(if $(filter 1,$(QUICK)),20,60)
BT_REPS    ?= $(if $(filter 1,$(QUICK)),2,3)

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
BT_CXXFLAGS = -std=c++14 -O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 $(WARN) \
    $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) $(INC) -Ihost_tools/research/benchtrack
BT_CFLAGS := $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L -O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 \
    -DRP_LINALG_EIGEN=1 $(INC) -Ihost_tools/research/benchtrack

$(BT_SCENE_O): host_tools/research/benchtrack/bt_scene.c $(BT_HDRS)
	@mkdir -p $(BT_DIR)
	$(CC) $(BT_CFLAGS) -c $< -o $@

$(BT_BENCH): host_tools/research/benchtrack/bench_track.cpp $(BT_SCENE_O) $(REL)/librigpose_sim.a \
             $(REL)/librigpose_core.a $(BT_HDRS) | deps
	$(CXX) $(BT_CXXFLAGS) $< $(BT_SCENE_O) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
	    -o $@ -lopencv_video -lopencv_imgproc -lopencv_core -lm

$(BT_DRIVER): host_tools/research/benchtrack/frameset_driver.c $(BT_SCENE_O) $(REL)/librigpose_sim.a \
              $(REL)/librigpose_core.a $(BT_HDRS)
	$(CC) $(BT_CFLAGS) $< $(BT_SCENE_O) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
	    -o $@ -lstdc++ -lm

# The core's RAM for 4 cameras at the default limits (640x480), as the board builds it (float).
$(BT_DIR)/static_pipe.o $(BT_DIR)/static_gc.o: host_tools/research/benchtrack/static_4cam.c $(BT_HDRS)
	@mkdir -p $(BT_DIR)
	$(CC) $(CSTD) $(CORE_WARN) -O2 -DRP_REAL_IS_FLOAT=1 -DRP_LINALG_EIGEN=1 $(INC) \
	    -DBT_STATIC_PIPE=$(if $(findstring pipe,$@),1,0) -c $< -o $@

RESEARCH_TOOLS += $(BT_BENCH) $(BT_DRIVER)

BENCH_PARTS += $(BUILD)/bench/track.json
$(BUILD)/bench/track.json: $(BT_BENCH) $(BT_DRIVER) $(BT_DIR)/static_pipe.o $(BT_DIR)/static_gc.o \
                           $(REL)/librigpose_core.a FORCE
	@mkdir -p $(BUILD)/bench
	$(PY) host_tools/research/benchtrack/bench_track.py --bench $(BT_BENCH) --driver $(BT_DRIVER) \
	    --static-pipe $(BT_DIR)/static_pipe.o --static-gc $(BT_DIR)/static_gc.o \
	    --core-lib $(REL)/librigpose_core.a --frames $(BT_FRAMES) --reps $(BT_REPS) --out $@
