# host_tools/log/log.mk - rigpose-log and its test (included by the top-level Makefile).
# Host C++ linked with the platform HAL ($(BUILD)/platform/librigpose_hal.a: v4l2 / replay
# sources and the configuration parser, platform/platform.mk), the release core and simulator,
# and the LCM bindings of lcm_types/ (rigpose.image_t).
#
#   make $(REL)/rigpose-log           the program
#   host_tools/log/test_log.sh        record a rendered replay folder into a folder and an LCM log
#                                     (with the daemon's poses), replay both, same poses

LOG_BIN := $(REL)/rigpose-log
LOG_LCM := $(BUILD)/lcmgen
LOG_HAL := $(BUILD)/platform/librigpose_hal.a

LOG_CXXFLAGS = -std=c++14 -O2 -g -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 $(WARN) \
    -Iplatform/include $(INC) -Ihost_tools/common -isystem $(LOG_LCM)/c
LOG_LIBS = $(LCMLOG_OBJ) $(LOG_HAL) $(LOG_LCM)/librigpose_lcm.a $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
    -llcm -lyaml -lpng -ljpeg -lz -lpthread -lstdc++ -lm

$(LOG_BIN): host_tools/log/rigpose_log.cpp $(LCMLOG_OBJ) $(wildcard host_tools/common/*.h) \
            $(LOG_HAL) $(LOG_LCM)/librigpose_lcm.a \
            $(REL)/librigpose_sim.a $(REL)/librigpose_core.a $(wildcard platform/include/rigpose/*.h)
	@mkdir -p $(@D)
	$(CXX) $(LOG_CXXFLAGS) $< -o $@ $(LOG_LIBS)

EXTRA_TOOLS += $(LOG_BIN)
HOST_EXTRA_TESTS += host_tools/log/test_log.sh
SERIAL_TESTS += host_tools/log/test_log.sh
test: $(LOG_BIN) $(REL)/rigpose $(REL)/rigpose-render $(REL)/rigpose-eval
export RP_LOG_BIN = $(LOG_BIN)
export RP_LOG_WORK = $(BUILD)/log/work
export RP_LCM_PY = $(LOG_LCM)/python
