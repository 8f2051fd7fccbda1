# host_tools/calib/calib.mk - rigpose-calib and its tests (included by the top-level Makefile).
# Host-only C++ with OpenCV; no core code is needed.
#
#   make $(REL)/rigpose-calib      the program
#   $(BUILD)/calib/test_calib      library test: opencv-doc's chessboards, hand-eye on synthetic data
#   host_tools/calib/test_calib_cli.sh   the program on bad input (missing partner, corrupt file)

CALIB_DIR := $(BUILD)/calib
CALIB_BIN := $(REL)/rigpose-calib
CALIB_TEST := $(CALIB_DIR)/test_calib
CALIB_HDR := host_tools/calib/rp_calib.hpp

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
CALIB_CXXFLAGS = -std=c++14 -O2 -g $(WARN) \
    $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) -Ihost_tools/calib
CALIB_LIBS = -lopencv_calib3d -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -lm

$(CALIB_DIR)/rp_calib.o: host_tools/calib/rp_calib.cpp $(CALIB_HDR) | deps
	@mkdir -p $(@D)
	$(CXX) $(CALIB_CXXFLAGS) -c $< -o $@

$(CALIB_BIN): host_tools/calib/rigpose_calib.cpp $(CALIB_DIR)/rp_calib.o $(CALIB_HDR)
	@mkdir -p $(@D)
	$(CXX) $(CALIB_CXXFLAGS) $< $(CALIB_DIR)/rp_calib.o -o $@ $(CALIB_LIBS)

$(CALIB_TEST): host_tools/calib/test_calib.cpp $(CALIB_DIR)/rp_calib.o $(CALIB_HDR)
	$(CXX) $(CALIB_CXXFLAGS) $< $(CALIB_DIR)/rp_calib.o -o $@ $(CALIB_LIBS)

EXTRA_TOOLS += $(CALIB_BIN)
HOST_EXTRA_TESTS += $(CALIB_TEST) host_tools/calib/test_calib_cli.sh
test: $(CALIB_TEST) $(CALIB_BIN)
export RP_CALIB_BIN = $(CALIB_BIN)
export RP_CALIB_WORK = $(CALIB_DIR)/work

# Round trip: rigpose-calib's YAML through the daemon's own parser (once the platform has it).
ifneq ($(wildcard platform/src/rp_config.c),)
CALIB_CFG_CHECK := $(CALIB_DIR)/cfg_check
$(CALIB_CFG_CHECK): host_tools/calib/cfg_check.c platform/src/rp_config.c $(REL)/librigpose_sim.a \
                    $(REL)/librigpose_core.a $(wildcard platform/include/rigpose/*.h)
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L -Iplatform/include $(INC) -O2 -g \
	    $(VDEF_double-eigen) $< platform/src/rp_config.c $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ -lyaml -lstdc++ -lm
test: $(CALIB_CFG_CHECK)
export RP_CFG_CHECK = $(CALIB_CFG_CHECK)
endif

# rigpose-timesync: each camera's clock offset from the rig's rotation (rp_timesync.hpp), read
# through the HAL (replay folder or V4L2); OpenCV for the tracks and rotations. It runs no
# tracker of the core, so its HAL, parser and core are built with the realdata limits (images up
# to 1248x480: the parser and the replay source refuse larger than the tracker's limit).
TIMESYNC_BIN := $(REL)/rigpose-timesync
TIMESYNC_DIR := $(CALIB_DIR)/timesync
TIMESYNC_DEFS := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 -DRP_TRACK_MAX_W=1248 -DRP_TRACK_MAX_H=480
TIMESYNC_CXXFLAGS = $(CALIB_CXXFLAGS) $(TIMESYNC_DEFS) -Iplatform/include $(INC)
TIMESYNC_HAL_O := $(patsubst platform/src/%.c,$(TIMESYNC_DIR)/hal/%.o,$(wildcard platform/src/*.c))
TIMESYNC_CORE := $(BUILD)/realdata/librigpose_core.a
$(TIMESYNC_DIR)/hal/%.o: platform/src/%.c $(wildcard platform/include/rigpose/*.h platform/src/*.h \
                                                   core/include/rigpose/*.h platform/sim/*.h) | deps
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(CORE_WARN) -Wno-format-truncation -D_DEFAULT_SOURCE -Iplatform/include $(INC) \
	    $(TIMESYNC_DEFS) -O2 -g -DNDEBUG -c $< -o $@
$(TIMESYNC_DIR)/rp_timesync.o: host_tools/calib/rp_timesync.cpp host_tools/calib/rp_timesync.hpp \
                               $(wildcard core/include/rigpose/*.h) | deps
	@mkdir -p $(@D)
	$(CXX) $(TIMESYNC_CXXFLAGS) -c $< -o $@
$(TIMESYNC_BIN): host_tools/calib/rigpose_timesync.cpp $(TIMESYNC_DIR)/rp_timesync.o \
                 host_tools/calib/rp_timesync.hpp $(TIMESYNC_HAL_O) $(TIMESYNC_CORE) \
                 $(REL)/librigpose_sim.a $(wildcard platform/include/rigpose/*.h)
	@mkdir -p $(@D)
	$(CXX) $(TIMESYNC_CXXFLAGS) $< $(TIMESYNC_DIR)/rp_timesync.o $(TIMESYNC_HAL_O) -o $@ \
	    $(REL)/librigpose_sim.a $(TIMESYNC_CORE) -lopencv_video $(CALIB_LIBS) \
	    -lyaml -lpng -ljpeg -lz -lpthread -lm
EXTRA_TOOLS += $(TIMESYNC_BIN)
HOST_EXTRA_TESTS += host_tools/calib/test_timesync.sh
test: $(TIMESYNC_BIN) $(REL)/rigpose-render $(REL)/rigpose-offsets $(REL)/rigpose-realdata
export RP_TIMESYNC_BIN = $(TIMESYNC_BIN)
