# tests/fuzz/fuzz.mk - libFuzzer targets of whatever parses outside input (included by the
# top-level Makefile, last: it uses the HAL's and lcm_types' variables). tests/fuzz/README.md.
#
#   make fuzz FUZZ_BUDGET_S=N  the same with N seconds shared out evenly (at least 5 s a target)
#   make fuzz FUZZ_S=N         every target for N seconds (default 60), one after the other, on its
#                              growing corpus $(BUILD)/fuzz/corpus/<target> and the seeds; prints
#                              executions and corpus size per target; a crash, sanitizer report,
#                              leak or hang (> 25 s) is copied to tests/fuzz/regress/<target>/ and
#                              fails the run
#   $(BUILD)/fuzz/fuzz_<t>     the targets (clang -fsanitize=fuzzer,address,undefined)
#   $(BUILD)/fuzz/test_<t>     make test: target <t> once over its seeds and regression inputs
#
# The code under test is compiled here by clang with the fuzzer's coverage instrumentation and
# ASan + UBSan: the HAL (platform/src/*.c: configuration, replay, V4L2's MJPEG decoder), the LCM
# log reader (host_tools/common/rp_lcmlog.c) and lcm-gen's C bindings. The core and simulation
# libraries they call are linked from the release build (gcc, not instrumented).

FUZZ := $(BUILD)/fuzz
FUZZ_CC ?= clang
FUZZ_S ?= 60
FUZZ_SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
FUZZ_INSTR := -g -O1 -fsanitize=fuzzer-no-link $(FUZZ_SAN) -Wno-unknown-warning-option
FUZZ_LINK := -fsanitize=fuzzer $(FUZZ_SAN)
FUZZ_CFLAGS := $(CSTD) $(WARN) $(FUZZ_INSTR) -D_DEFAULT_SOURCE $(HAL_INC) $(VDEF_double-eigen) \
    -Itests/fuzz -Ihost_tools/common

FUZZ_LCM_TYPES := $(patsubst lcm_types/%.lcm,%,$(LCM_DEFS))
FUZZ_TARGETS := config replay_index image mjpeg lcmlog $(addprefix lcm_,$(FUZZ_LCM_TYPES))
FUZZ_BINS := $(addprefix $(FUZZ)/fuzz_,$(FUZZ_TARGETS))
FUZZ_TESTS := $(addprefix $(FUZZ)/test_,$(FUZZ_TARGETS))
ifneq ($(FUZZ_BUDGET_S),)
override FUZZ_S := $(shell n=$$(( $(FUZZ_BUDGET_S) / $(words $(FUZZ_TARGETS)) )); echo $$(( n < 5 ? 5 : n )))
endif

# The HAL, instrumented (every source: rp_hal_common.c dispatches to all three).
FUZZ_HAL_OBJ := $(patsubst platform/src/%.c,$(FUZZ)/hal/%.o,$(HAL_C))
$(FUZZ)/hal/%.o: platform/src/%.c $(HAL_H) | deps
	@mkdir -p $(@D)
	$(FUZZ_CC) $(HAL_CFLAGS) $(FUZZ_INSTR) -c $< -o $@
FUZZ_HAL_LIBS = $(FUZZ_HAL_OBJ) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a $(HAL_LIBS) \
    -lstdc++ -lm

$(FUZZ)/fuzz_config: tests/fuzz/fuzz_config.c $(FUZZ)/hal/rp_config.o $(REL)/librigpose_core.a
	$(FUZZ_CC) $(FUZZ_CFLAGS) $< $(FUZZ)/hal/rp_config.o $(REL)/librigpose_core.a -o $@ \
	    $(FUZZ_LINK) -lyaml -lstdc++ -lm

$(FUZZ)/fuzz_replay_index $(FUZZ)/fuzz_image: $(FUZZ)/fuzz_%: tests/fuzz/fuzz_%.c \
        tests/fuzz/fuzz_tmpdir.h $(FUZZ_HAL_OBJ) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a
	$(FUZZ_CC) $(FUZZ_CFLAGS) $< -o $@ $(FUZZ_LINK) $(FUZZ_HAL_LIBS)

$(FUZZ)/fuzz_mjpeg: tests/fuzz/fuzz_mjpeg.c $(FUZZ_HAL_OBJ) $(REL)/librigpose_sim.a \
                    $(REL)/librigpose_core.a
	$(FUZZ_CC) $(FUZZ_CFLAGS) $< -o $@ $(FUZZ_LINK) $(FUZZ_HAL_LIBS)

$(FUZZ)/fuzz_lcmlog: tests/fuzz/fuzz_lcmlog.c host_tools/common/rp_lcmlog.c \
                     host_tools/common/rp_lcmlog.h | deps
	@mkdir -p $(@D)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -D_POSIX_C_SOURCE=200809L tests/fuzz/fuzz_lcmlog.c \
	    host_tools/common/rp_lcmlog.c -o $@ $(FUZZ_LINK)

# One target per LCM type; the generated code has warnings of its own (lcm_types.mk).
FUZZ_DECODE_rigpose_image_t := -DFUZZ_DECODE=rp_image_t_decode_checked \
    -DFUZZ_DECODE_HEADER='"rp_lcm_image.h"'
$(FUZZ)/lcm/%.o: $(LCMGEN)/c/%.c $(LCMGEN)/stamp
	@mkdir -p $(@D)
	$(FUZZ_CC) $(CSTD) -Wall $(FUZZ_INSTR) -I$(LCMGEN)/c -c $< -o $@
$(FUZZ)/fuzz_lcm_%: tests/fuzz/fuzz_lcm_msg.c $(FUZZ)/lcm/%.o $(wildcard host_tools/common/*.h)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -isystem $(LCMGEN)/c -DFUZZ_TYPE=$* -DFUZZ_HEADER='"$*.h"' \
	    $(FUZZ_DECODE_$*) $< $(FUZZ)/lcm/$*.o -o $@ $(FUZZ_LINK) -llcm

# Seeds of the LCM types made from the bindings at build time (beside the committed ones, which a
# changed type would leave behind its fingerprint).
$(FUZZ)/gen/stamp: tests/fuzz/lcm_seeds.py $(LCMGEN)/stamp
	@rm -rf $(@D) && mkdir -p $(@D)
	PYTHONPATH=$(LCMGEN)/python $(PY) tests/fuzz/lcm_seeds.py $(@D) $(LCM_DEFS)
	@touch $@

# make test: each target once over its corpus (seeds, generated seeds, regression inputs).
$(FUZZ)/test_%: tests/fuzz/run_corpus.sh $(FUZZ)/fuzz_% $(FUZZ)/gen/stamp
	printf '#!/bin/sh\nexec %s/tests/fuzz/run_corpus.sh %s "$$@"\n' "$(CURDIR)" \
	    "$(abspath $(FUZZ))/fuzz_$*" > $@
	chmod +x $@

# Built through pattern rules: not intermediates to delete.
.SECONDARY: $(FUZZ_BINS) $(patsubst %,$(FUZZ)/lcm/%.o,$(FUZZ_LCM_TYPES))

.PHONY: fuzz fuzz-build
fuzz-build: $(FUZZ_BINS) $(FUZZ)/gen/stamp
fuzz: deps fuzz-build
	tests/fuzz/run_fuzz.sh $(FUZZ) $(FUZZ_S) $(FUZZ_TARGETS)

HOST_EXTRA_TESTS += $(FUZZ_TESTS)
test: $(FUZZ_TESTS)
