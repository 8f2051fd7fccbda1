# tests/soak/soak.mk - the daemon run long (issue 18 item 8; tests/soak/soak.sh says what is
# checked). Included by the top-level Makefile.
#
#   make soak      SOAK_FEAT feature-level sets of the simulated rig on the turn and SOAK_IMG
#                  image-level sets of a rendered replay, as fast as they go; writes
#                  $(BUILD)/bench/soak.json and puts its figures (soak_frames,
#                  soak_image_frames, soak_rss_growth_pct, soak_sets_per_s) into
#                  $(BUILD)/bench.json
#   make test      the same, short: 10,000 and 300 sets (build/soak/run_test_soak)

SOAK_FEAT ?= 1000000
SOAK_IMG ?= 100000
SOAK_NEEDS := $(REL)/rigpose $(REL)/rigpose-render $(BUILD)/lcmgen/stamp

.PHONY: soak
soak: deps $(SOAK_NEEDS)
	@mkdir -p $(BUILD)/bench
	tests/soak/soak.sh $(BUILD) $(SOAK_FEAT) $(SOAK_IMG) $(BUILD)/bench/soak.json
	@$(PY) -c 'import json, os, sys; b = sys.argv[1]; \
	    d = json.load(open(b)) if os.path.exists(b) else {}; \
	    d.update(json.load(open(sys.argv[2]))); json.dump(d, open(b, "w"), indent=1); \
	    print("soak figures written into", b)' $(BUILD)/bench.json $(BUILD)/bench/soak.json

$(BUILD)/soak/run_test_soak: tests/soak/soak.sh
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s/tests/soak/soak.sh %s 10000 300\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

HOST_EXTRA_TESTS += $(BUILD)/soak/run_test_soak
test: $(BUILD)/soak/run_test_soak $(SOAK_NEEDS)
