# host_tools/research/realdata/realdata.mk - rigpose-realdata: rigpose's stereo layout on real camera data
# (KITTI 00, EuRoC MH01 in ../shared/data; included by the top-level Makefile).
#
#   make $(REL)/rigpose-realdata   the program
#   make test                      test_realdata_conv (conversions, scoring, loaders) and
#                                  test_realdata.sh: 20 frames of each sequence within the
#                                  targets (both skip the data's part if it is absent),
#                                  both built with ASan + UBSan ($(BUILD)/realdata-san)
#   make bench                     $(BUILD)/bench/realdata.json, every clip with the core's
#                                  default settings (no --config): kitti00_ate_percent,
#                                  euroc_mh01_ate_m, kitti_raw0005_* ... (QUICK=1: 40 frames
#                                  of each); also
#                                  kitti00_from14_* (frames 14-99: past the ground truth's
#                                  extrapolated start, README.md) and the two yardsticks
#                                  (OpenCV stereo PnP; dense direct odometry, rp_direct.hpp),
#                                  and each clip's mirror image (*_mirror_*, --mirror);
#                                  realdata_table.py prints them against the data README's
#                                  targets (met? at or below the best yardstick? mirror diff)
#   mirror_ate.sh                  in make test (ASan + UBSan build): each clip's ATE against
#                                  its mirror image's, within 10 %
#
# The images are larger than the default build's tracker limit (640x480: KITTI is 1241x376,
# EuRoC 752x480), so the program links its own release build of the core with
# RP_TRACK_MAX_W x RP_TRACK_MAX_H = 1248 x 480 (double, Eigen, -O2), in $(BUILD)/realdata; its
# own sources must see the same limits (the structs' sizes follow them).

RD_DIR := $(BUILD)/realdata
RD_BIN := $(REL)/rigpose-realdata
RD_DEFS := -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 -DRP_TRACK_MAX_W=1248 -DRP_TRACK_MAX_H=480
$(eval $(call CORE_LIB,realdata,$(RD_DIR),$(CC),$(CXX),-O2 -g -DNDEBUG $(RD_DEFS),ar))

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
RD_CXXFLAGS = -std=c++17 -O2 -g -DNDEBUG $(RD_DEFS) $(WARN) \
    $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) $(INC) -Iplatform/include \
    -Ihost_tools/research/realdata
RD_LIBS = -lopencv_calib3d -lopencv_video -lopencv_imgproc -lopencv_imgcodecs -lopencv_core -lyaml -lm

# --config FILE: the daemon's parser (platform/src/rp_config.c), compiled with the same limits
# as this core (its rp_pipe_cfg_t and rp_rig_t must be the tool's).
RD_CONFIG_O := $(RD_DIR)/rp_config.o
$(RD_CONFIG_O): platform/src/rp_config.c platform/include/rigpose/rp_config.h $(RD_HDR_CORE) | deps
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(CORE_WARN) -Wno-format-truncation -D_DEFAULT_SOURCE -Iplatform/include $(INC) \
	    -O2 -g -DNDEBUG $(RD_DEFS) -c $< -o $@
RD_LIB_SRC := host_tools/research/realdata/rp_realdata.cpp host_tools/research/realdata/rp_direct.cpp \
    host_tools/research/realdata/rp_mirror.cpp host_tools/research/realdata/rp_rectify.cpp \
    host_tools/calib/rp_timesync.cpp
# --tracks-out: the tracks file of rigpose-ba (host_tools/ba/rp_tracks.hpp), compiled with this
# core's limits.
RD_SRC := host_tools/research/realdata/rigpose_realdata.cpp $(RD_LIB_SRC) host_tools/ba/rp_tracks.cpp
RD_HDR_CORE := $(wildcard core/include/rigpose/*.h platform/include/rigpose/*.h)
RD_HDR := $(wildcard host_tools/research/realdata/*.hpp) host_tools/ba/rp_tracks.hpp host_tools/calib/rp_timesync.hpp $(RD_HDR_CORE)

$(RD_BIN): $(RD_SRC) $(RD_HDR) $(RD_CONFIG_O) $(RD_DIR)/librigpose_core.a | deps
	mkdir -p $(REL)
	$(CXX) $(RD_CXXFLAGS) $(RD_SRC) $(RD_CONFIG_O) $(RD_DIR)/librigpose_core.a -o $@ $(RD_LIBS)

RESEARCH_TOOLS += $(RD_BIN)

# The data: ../shared/data beside the repository, or $RIGPOSE_DATA.
RD_DATA = $(or $(RIGPOSE_DATA),$(abspath $(CURDIR)/../shared/data))

# Conversions, scoring and loaders (host_tools/research/realdata/test_realdata_conv.cpp).
RD_TEST := $(RD_DIR)/test_realdata_conv
$(RD_TEST): host_tools/research/realdata/test_realdata_conv.cpp $(RD_LIB_SRC) $(RD_HDR) \
            $(RD_DIR)/librigpose_core.a | deps
	$(CXX) $(RD_CXXFLAGS) $< $(RD_LIB_SRC) $(RD_DIR)/librigpose_core.a -o $@ $(RD_LIBS)

# make test runs the tool and its unit test under ASan + UBSan (the paths that read real images,
# calibration and ground truth): a core of the same limits built with the sanitizers, in
# $(BUILD)/realdata-san (OpenCV itself is not instrumented). The bench uses the release build.
RD_SAN_DIR := $(BUILD)/realdata-san
RD_SAN_FLAGS := -O1 -g $(SAN) $(RD_DEFS)
$(eval $(call CORE_LIB,realdata-san,$(RD_SAN_DIR),$(CC),$(CXX),$(RD_SAN_FLAGS),ar))
RD_SAN_CXXFLAGS = $(subst -O2 -g -DNDEBUG,$(RD_SAN_FLAGS),$(RD_CXXFLAGS))
RD_SAN_BIN := $(RD_SAN_DIR)/rigpose-realdata
RD_SAN_TEST := $(RD_SAN_DIR)/test_realdata_conv
$(RD_SAN_DIR)/rp_config.o: platform/src/rp_config.c platform/include/rigpose/rp_config.h $(RD_HDR_CORE) | deps
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(CORE_WARN) -Wno-format-truncation -D_DEFAULT_SOURCE -Iplatform/include $(INC) \
	    $(RD_SAN_FLAGS) -c $< -o $@
$(RD_SAN_BIN): $(RD_SRC) $(RD_HDR) $(RD_SAN_DIR)/rp_config.o $(RD_SAN_DIR)/librigpose_core.a | deps
	$(CXX) $(RD_SAN_CXXFLAGS) $(RD_SRC) $(RD_SAN_DIR)/rp_config.o $(RD_SAN_DIR)/librigpose_core.a \
	    -o $@ $(SAN) $(RD_LIBS)
$(RD_SAN_TEST): host_tools/research/realdata/test_realdata_conv.cpp $(RD_LIB_SRC) $(RD_HDR) \
                $(RD_SAN_DIR)/librigpose_core.a | deps
	$(CXX) $(RD_SAN_CXXFLAGS) $< $(RD_LIB_SRC) $(RD_SAN_DIR)/librigpose_core.a -o $@ $(SAN) $(RD_LIBS)

HOST_EXTRA_TESTS += $(RD_SAN_TEST) host_tools/research/realdata/test_realdata.sh \
    host_tools/research/realdata/mirror_ate.sh
test: $(RD_SAN_BIN) $(RD_SAN_TEST)
export RP_REALDATA_BIN = $(RD_SAN_BIN)

RD_BENCH_KITTI ?= $(if $(filter 1,$(QUICK)),40,100)
RD_BENCH_EUROC ?= $(if $(filter 1,$(QUICK)),40,150)
BENCH_PARTS += $(BUILD)/bench/realdata.json
# One run of rigpose-realdata per clip and per mirror image, all with the core's defaults; then
# realdata_table.py prints them against the data README's targets.
RD_RUN = $(RD_BIN) --quiet --json-out $(RD_DIR)/$(1).json --name $(1) $(2)
RD_K00 = --kitti $(RD_DATA)/kitti00_000-099 --frames $(RD_BENCH_KITTI)
RD_RAW = --kitti $(RD_DATA)/kitti_raw_0926_0005_000-090 --frames $(RD_BENCH_KITTI)
RD_EU = --euroc $(RD_DATA)/euroc_mh01_000-149 --frames $(RD_BENCH_EUROC)
RD_REFS = --opencv-ref --direct-ref
RD_PARTS = kitti00 kitti00_from14 euroc_mh01 kitti00_mirror kitti00_from14_mirror \
    euroc_mh01_mirror kitti_raw0005 kitti_raw0005_mirror euroc_offset50 euroc_from1 euroc_gc
# The unsynchronised-cameras experiment (docs/time.md): the right camera one frame late, its
# offset from the rotation rates, regrouped by capture time, refined by the filter; and the
# correctly paired run on the same frames. gc: the two cameras as a non-overlapping rig.
RD_OFF50 = $(RD_EU) --pair-shift 1 --sync-rotation --regroup --estimate-offsets 1
RD_FROM1 = --euroc $(RD_DATA)/euroc_mh01_000-149 --first 1 --frames $$(( $(RD_BENCH_EUROC) - 1 ))
$(BUILD)/bench/realdata.json: $(RD_BIN) FORCE
	@mkdir -p $(BUILD)/bench $(RD_DIR)
	@if [ -d "$(RD_DATA)/kitti00_000-099" ] && [ -d "$(RD_DATA)/euroc_mh01_000-149" ]; then \
	  $(call RD_RUN,kitti00,$(RD_K00) $(RD_REFS) --splice 14) && \
	  $(call RD_RUN,kitti00_from14,$(RD_K00) --first 14 $(RD_REFS)) && \
	  $(call RD_RUN,euroc_mh01,$(RD_EU) $(RD_REFS)) && \
	  $(call RD_RUN,kitti00_mirror,$(RD_K00) --mirror) && \
	  $(call RD_RUN,kitti00_from14_mirror,$(RD_K00) --first 14 --mirror) && \
	  $(call RD_RUN,euroc_mh01_mirror,$(RD_EU) --mirror) && \
	  $(call RD_RUN,euroc_offset50,$(RD_OFF50)) && \
	  $(call RD_RUN,euroc_from1,$(RD_FROM1)) && \
	  $(call RD_RUN,euroc_gc,$(RD_EU) --layout gc) && \
	  echo '{}' > $(RD_DIR)/kitti_raw0005.json && echo '{}' > $(RD_DIR)/kitti_raw0005_mirror.json && \
	  { [ ! -d "$(RD_DATA)/kitti_raw_0926_0005_000-090" ] || \
	    { $(call RD_RUN,kitti_raw0005,$(RD_RAW) $(RD_REFS)) && \
	      $(call RD_RUN,kitti_raw0005_mirror,$(RD_RAW) --mirror); }; } && \
	  $(PY) host_tools/research/bench/merge_json.py $@ $(foreach p,$(RD_PARTS),$(RD_DIR)/$(p).json) && \
	  $(PY) host_tools/research/realdata/realdata_table.py $@; \
	else echo "realdata: no data in $(RD_DATA) (set RIGPOSE_DATA): figures left out"; \
	  echo '{}' > $@; fi
