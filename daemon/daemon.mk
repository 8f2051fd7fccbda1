# daemon/daemon.mk - the rigpose daemon (host and aarch64), its tests and its benchmark section.
#
#   $(REL)/rigpose              host daemon (double, Eigen, -O2), built by `make`
#   $(REL)/rigpose-frontend     host front end (cameras -> features over LCM), built by `make`
#   $(ARM)/daemon/rigpose       aarch64 daemon (float, Eigen), built by `make cross`
#   $(ARM)/daemon/rigpose-frontend  aarch64 front end, built by `make cross`
#   make run-daemon             the daemon on the embedded default, config/sim.yaml
#   $(BUILD)/bench/daemon.json  latency frame -> LCM publish and sets/s on the simulated rig
#   $(BUILD)/bench/distributed.json  latency frame -> pose through front-end processes
#
# Included before lcm_types/lcm_types.mk (sorted): paths to the generated bindings are spelt out.

DMN := $(BUILD)/daemon
DMN_LCM := $(BUILD)/lcmgen
DMN_INC := -Icore/include -Iplatform/include -Iplatform/sim -Idaemon -I$(DMN_LCM)/c
DMN_WARN := $(WARN) -Wdouble-promotion -Wconversion -Wno-sign-conversion
DMN_SRC := daemon/rigpose.c daemon/rp_args.c daemon/rp_est.c daemon/rp_publish.c daemon/rp_stats.c \
           daemon/rp_lcmsrc.c daemon/rp_feats.c
# rigpose-frontend: its main and what it shares with the daemon (messages, channels).
FE_SRC := daemon/rigpose_frontend.c daemon/rp_feats.c daemon/rp_publish.c
DMN_HDRS := $(wildcard core/include/rigpose/*.h platform/include/rigpose/*.h daemon/*.h \
                       platform/sim/*.h host_tools/common/*.h)
# The platform's library (platform/platform.mk): the HAL sources, the sim source and the
# configuration parser; HAL_LIBS is what it links (libyaml, libpng, libjpeg).
DMN_HAL_LIB = $(BUILD)/platform/librigpose_hal.a
DMN_HAL_SAN_LIB = $(BUILD)/platform/san/librigpose_hal.a
DMN_LDLIBS = $(HAL_LIBS) -llcm -lpthread -lstdc++ -lm
DMN_VARIANTS := double-eigen float-c

# ---- host daemon --------------------------------------------------------------------------------
DMN_REL_OBJ := $(patsubst %.c,$(DMN)/rel/%.o,$(DMN_SRC))
$(DMN)/rel/%.o: %.c $(DMN_HDRS) $(DMN_LCM)/stamp
	@mkdir -p $(dir $@)
	$(CC) $(CSTD) $(DMN_WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -O2 -g \
	    -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 -c $< -o $@

$(REL)/rigpose: $(DMN_REL_OBJ) $(DMN_LCM)/librigpose_lcm.a $(BUILD)/platform/librigpose_hal.a \
                $(REL)/librigpose_sim.a $(REL)/librigpose_core.a
	$(CC) $(DMN_REL_OBJ) $(DMN_LCM)/librigpose_lcm.a $(DMN_HAL_LIB) $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ $(DMN_LDLIBS)

FE_REL_OBJ := $(patsubst %.c,$(DMN)/rel/%.o,$(FE_SRC))
$(REL)/rigpose-frontend: $(FE_REL_OBJ) $(DMN_LCM)/librigpose_lcm.a $(BUILD)/platform/librigpose_hal.a \
                         $(REL)/librigpose_sim.a $(REL)/librigpose_core.a
	$(CC) $(FE_REL_OBJ) $(DMN_LCM)/librigpose_lcm.a $(DMN_HAL_LIB) $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ $(DMN_LDLIBS)

EXTRA_TOOLS += $(REL)/rigpose $(REL)/rigpose-frontend

.PHONY: run-daemon
DAEMON_ARGS ?=
run-daemon: deps $(REL)/rigpose
	$(REL)/rigpose --config config/sim.yaml $(DAEMON_ARGS)

# ---- tests ---------------------------------------------------------------------------------------
# cmocka tests of the configuration parser, the sim source and the estimator dispatch, the
# command line, the publish path (no allocation) and the status accounting, in a double and a
# float variant (sanitised); then the LCM test between processes (script).
define DMN_TEST
$(DMN)/$(1)/test_config: daemon/tests/test_config.c platform/src/rp_config.c $(DMN_HDRS) \
                         tests/rp_test.h $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a
	@mkdir -p $$(dir $$@)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) \
	    daemon/tests/test_config.c platform/src/rp_config.c $(BUILD)/$(1)/librigpose_sim.a \
	    $(BUILD)/$(1)/librigpose_core.a \
	    -o $$@ $(SAN) -lyaml -lcmocka -lstdc++ -lm
$(DMN)/$(1)/test_est: daemon/tests/test_est.c daemon/rp_est.c platform/src/rp_config.c \
                      platform/src/rp_hal_sim.c $(DMN_HDRS) tests/rp_test.h \
                      $(BUILD)/platform/san/librigpose_hal.a \
                      $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a
	@mkdir -p $$(dir $$@)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) \
	    daemon/tests/test_est.c daemon/rp_est.c platform/src/rp_config.c \
	    platform/src/rp_hal_sim.c $$(DMN_HAL_SAN_LIB) $(BUILD)/$(1)/librigpose_sim.a \
	    $(BUILD)/$(1)/librigpose_core.a -o $$@ $(SAN) -lcmocka $$(HAL_LIBS) -lstdc++ -lm
$(DMN)/$(1)/test_args: daemon/tests/test_args.c daemon/rp_args.c platform/src/rp_config.c \
                       $(DMN_HDRS) tests/rp_test.h $(BUILD)/$(1)/librigpose_sim.a \
                       $(BUILD)/$(1)/librigpose_core.a
	@mkdir -p $$(dir $$@)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) \
	    daemon/tests/test_args.c daemon/rp_args.c platform/src/rp_config.c \
	    $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a \
	    -o $$@ $(SAN) -lyaml -lcmocka -lstdc++ -lm
$(DMN)/$(1)/test_stats: daemon/tests/test_stats.c daemon/rp_stats.c $(DMN_HDRS) tests/rp_test.h \
                        $(DMN_LCM)/stamp $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a
	@mkdir -p $$(dir $$@)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) \
	    daemon/tests/test_stats.c daemon/rp_stats.c $(BUILD)/$(1)/librigpose_sim.a \
	    $(BUILD)/$(1)/librigpose_core.a -o $$@ $(SAN) -lcmocka -lstdc++ -lm
# The publish path under an allocation counter: malloc, calloc, realloc and free wrapped.
$(DMN)/$(1)/test_publish: daemon/tests/test_publish.c daemon/rp_publish.c daemon/rp_stats.c \
                          $(DMN_HDRS) tests/rp_test.h $(DMN_LCM)/librigpose_lcm.a \
                          $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a
	@mkdir -p $$(dir $$@)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) \
	    daemon/tests/test_publish.c daemon/rp_publish.c daemon/rp_stats.c \
	    $(DMN_LCM)/librigpose_lcm.a $(BUILD)/$(1)/librigpose_sim.a \
	    $(BUILD)/$(1)/librigpose_core.a -o $$@ $(SAN) \
	    -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free -lcmocka -llcm -lstdc++ -lm
# The lcm source on memq://, fed by the front end's publishing code.
$(DMN)/$(1)/test_lcmsrc: daemon/tests/test_lcmsrc.c daemon/rp_lcmsrc.c daemon/rp_feats.c \
                         daemon/rp_publish.c $(DMN_HDRS) tests/rp_test.h $(DMN_LCM)/librigpose_lcm.a \
                         $(BUILD)/platform/san/librigpose_hal.a \
                         $(BUILD)/$(1)/librigpose_sim.a $(BUILD)/$(1)/librigpose_core.a
	@mkdir -p $$(dir $$@)
	$(CC) $(CSTD) $(WARN) -D_POSIX_C_SOURCE=200809L $(DMN_INC) -Itests -O1 -g $(SAN) $(VDEF_$(1)) \
	    daemon/tests/test_lcmsrc.c daemon/rp_lcmsrc.c daemon/rp_feats.c daemon/rp_publish.c \
	    $(DMN_LCM)/librigpose_lcm.a $$(DMN_HAL_SAN_LIB) $(BUILD)/$(1)/librigpose_sim.a \
	    $(BUILD)/$(1)/librigpose_core.a -o $$@ $(SAN) -lcmocka -llcm $$(HAL_LIBS) -lstdc++ -lm
endef
$(foreach v,$(DMN_VARIANTS),$(eval $(call DMN_TEST,$(v))))

# The threads of the daemon (the pool, the HAL's per-camera decoding, the trackers on the
# pool: identical estimates on 1..4 threads) under ThreadSanitizer: core, simulator, HAL and the
# daemon's estimator all built with -fsanitize=thread.
$(DMN)/tsan/test_threads: daemon/tests/test_threads.c daemon/rp_est.c $(wildcard platform/src/*.c)                           $(DMN_HDRS) tests/rp_test.h tests/img_fixture.h                           $(BUILD)/tsan/librigpose_sim.a $(BUILD)/tsan/librigpose_core.a
	@mkdir -p $(dir $@)
	$(CC) $(CSTD) $(WARN) -Wno-format-truncation -D_DEFAULT_SOURCE $(DMN_INC) -Itests -O1 -g \
	    $(TSAN) $(VDEF_double-eigen) daemon/tests/test_threads.c daemon/rp_est.c \
	    $(wildcard platform/src/*.c) $(BUILD)/tsan/librigpose_sim.a \
	    $(BUILD)/tsan/librigpose_core.a -o $@ $(TSAN) -lcmocka $(HAL_LIBS) -lstdc++ -lm

# The LCM test runs the release daemon and Python; its wrapper passes this build's folder.
$(DMN)/run_test_lcm: daemon/tests/test_lcm.sh daemon/tests/lcm_sub.py
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s/daemon/tests/test_lcm.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

# The blank-replay test: the release daemon on a rendered replay gone blank (file:// log only).
$(DMN)/run_test_blank: daemon/tests/test_blank.sh
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s/daemon/tests/test_blank.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

# The release daemon's poses on 1, 2 and 4 threads, bit for bit (rendered replay, file:// logs).
$(DMN)/run_test_threads: daemon/tests/test_threads.sh daemon/tests/pose_log_diff.py \
                         daemon/tests/rig_subset.py
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s/daemon/tests/test_threads.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

# Every failure class of the release daemon (exit codes, messages naming file / camera), on
# replay folders it writes; LCM on memq:// only, so it runs in parallel with the others.
$(DMN)/run_test_failures: daemon/tests/test_failures.sh
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s/daemon/tests/test_failures.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

# Front ends as separate processes: four rigpose-frontend and the daemon with source lcm on a
# rendered replay, udpm ttl=0 (the multicast group: serial), against the in-process daemon.
$(DMN)/run_test_frontend: daemon/tests/test_frontend.sh daemon/tests/lcm_rec.py
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s/daemon/tests/test_frontend.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

DMN_TESTS := $(foreach v,$(DMN_VARIANTS),$(DMN)/$(v)/test_config $(DMN)/$(v)/test_est \
                                     $(DMN)/$(v)/test_args $(DMN)/$(v)/test_publish \
                                     $(DMN)/$(v)/test_stats $(DMN)/$(v)/test_lcmsrc) \
             $(DMN)/tsan/test_threads
HOST_EXTRA_TESTS += $(DMN_TESTS) $(DMN)/run_test_lcm $(DMN)/run_test_blank $(DMN)/run_test_failures \
                    $(DMN)/run_test_threads $(DMN)/run_test_frontend
SERIAL_TESTS += $(DMN)/run_test_lcm $(DMN)/run_test_frontend
test: $(DMN_TESTS) $(DMN)/run_test_lcm $(DMN)/run_test_blank $(DMN)/run_test_failures \
      $(DMN)/run_test_threads $(DMN)/run_test_frontend $(REL)/rigpose $(REL)/rigpose-frontend \
      $(REL)/rigpose-render $(DMN_LCM)/stamp

# ---- benchmark -----------------------------------------------------------------------------------
# 300 simulated frame sets as fast as the daemon takes them, published on udpm (ttl=0: this host).
BENCH_PARTS += $(BUILD)/bench/daemon.json
$(BUILD)/bench/daemon.json: $(REL)/rigpose FORCE
	@mkdir -p $(dir $@)
	@$(REL)/rigpose --config config/sim.yaml --frames 300 --fast --quiet \
	    --pose-channel RIGPOSE_BENCH_POSE_$$$$ --status-channel RIGPOSE_BENCH_STATUS_$$$$ \
	    --stats-json $@ >/dev/null
	@$(PY) -c 'import json, sys; d = json.load(open(sys.argv[1])); \
	    print("daemon: simulated rig, stereo4, 300 sets as fast as it goes, LCM udpm ttl=0"); \
	    [print("  %-24s %10.3f" % kv) for kv in d.items()]' $@

# Frame -> pose latency through four rigpose-frontend processes and the daemon (source lcm)
# against the in-process daemon, on one rendered 640x480 replay played live (the script says how).
BENCH_PARTS += $(BUILD)/bench/distributed.json
$(BUILD)/bench/distributed.json: daemon/bench_distributed.sh daemon/tests/restamp.py $(REL)/rigpose \
                                 $(REL)/rigpose-frontend $(REL)/rigpose-render FORCE
	@mkdir -p $(dir $@)
	@daemon/bench_distributed.sh $(BUILD) $@

# ---- aarch64 daemon --------------------------------------------------------------------------------
# The board's libraries (LCM, libyaml, libpng, libjpeg, zlib) as Debian arm64 packages, fetched
# with `apt-get download` and unpacked into a private sysroot $(ARM)/sysroot: never installed.
# (Debian's liblcm-dev:arm64 cannot be installed beside the host's liblcm-dev: no Multi-Arch;
# libpng-dev:arm64 / libjpeg-dev:arm64 would pull libc6-dev:arm64 and upgrade host packages.)
# On the board, `apt install liblcm1 libyaml-0-2 libpng16-16 libjpeg62-turbo` provides them.
ARM_SYSROOT := $(ARM)/sysroot
ARM_SYSROOT_DEBS := liblcm1:arm64 liblcm-dev:arm64 libyaml-0-2:arm64 libyaml-dev:arm64 \
    libpng16-16:arm64 libpng-dev:arm64 zlib1g:arm64 zlib1g-dev:arm64 libjpeg62-turbo:arm64 \
    libjpeg62-turbo-dev:arm64 libglib2.0-0:arm64 libpcre2-8-0:arm64
$(ARM_SYSROOT)/stamp: daemon/daemon.mk
	rm -rf $(ARM_SYSROOT) && mkdir -p $(ARM_SYSROOT)/debs
	cd $(ARM_SYSROOT)/debs && apt-get download $(ARM_SYSROOT_DEBS)
	for d in $(ARM_SYSROOT)/debs/*.deb; do dpkg-deb -x $$d $(ARM_SYSROOT); done
	touch $@

ARM_SYSLIB := $(ARM_SYSROOT)/usr/lib/aarch64-linux-gnu
DMN_ARM_SRC := $(DMN_SRC) $(sort $(wildcard platform/src/*.c))
DMN_ARM_OBJ := $(patsubst %.c,$(ARM)/daemon/%.o,$(DMN_ARM_SRC)) \
               $(patsubst lcm_types/%.lcm,$(ARM)/daemon/lcm/%.o,$(wildcard lcm_types/*.lcm))
$(ARM)/daemon/%.o: %.c $(DMN_HDRS) $(wildcard platform/src/*.h) $(DMN_LCM)/stamp \
                   $(ARM_SYSROOT)/stamp
	@mkdir -p $(dir $@)
	$(CROSS_PREFIX)gcc $(CSTD) $(DMN_WARN) -Wno-format-truncation -D_DEFAULT_SOURCE $(DMN_INC) \
	    -idirafter $(ARM_SYSROOT)/usr/include -idirafter $(ARM_SYSROOT)/usr/include/aarch64-linux-gnu \
	    -O2 -g $(ARMDEF_float) -c $< -o $@
$(ARM)/daemon/lcm/%.o: $(DMN_LCM)/c/%.c $(DMN_LCM)/stamp $(ARM_SYSROOT)/stamp
	@mkdir -p $(dir $@)
	$(CROSS_PREFIX)gcc -std=c99 -O2 -g -Wall -I$(DMN_LCM)/c -idirafter $(ARM_SYSROOT)/usr/include \
	    -c $< -o $@
ARM_LDFLAGS = -L$(ARM_SYSLIB) -Wl,-rpath-link,$(ARM_SYSLIB) -Wl,--allow-shlib-undefined \
    -llcm -lyaml -lpng -ljpeg -lz -lpthread -lstdc++ -lm
$(ARM)/daemon/rigpose: $(DMN_ARM_OBJ) $(ARM)/float/librigpose_sim.a $(ARM)/float/librigpose_core.a
	$(CROSS_PREFIX)gcc $(DMN_ARM_OBJ) $(ARM)/float/librigpose_sim.a $(ARM)/float/librigpose_core.a \
	    -o $@ $(ARM_LDFLAGS)
	@file $@ | sed 's/, BuildID.*//'
# The front end: its objects and the daemon's platform and LCM objects (no daemon main).
FE_ARM_OBJ := $(patsubst %.c,$(ARM)/daemon/%.o,$(FE_SRC) $(sort $(wildcard platform/src/*.c))) \
              $(patsubst lcm_types/%.lcm,$(ARM)/daemon/lcm/%.o,$(wildcard lcm_types/*.lcm))
$(ARM)/daemon/rigpose-frontend: $(FE_ARM_OBJ) $(ARM)/float/librigpose_sim.a \
                                $(ARM)/float/librigpose_core.a
	$(CROSS_PREFIX)gcc $(FE_ARM_OBJ) $(ARM)/float/librigpose_sim.a $(ARM)/float/librigpose_core.a \
	    -o $@ $(ARM_LDFLAGS)
	@file $@ | sed 's/, BuildID.*//'

cross: $(ARM)/daemon/rigpose $(ARM)/daemon/rigpose-frontend
