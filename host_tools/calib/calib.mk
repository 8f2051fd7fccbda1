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
