# lcm_types/lcm_types.mk - generate the LCM bindings of lcm_types/*.lcm with lcm-gen during the
# build: C into $(BUILD)/lcmgen/c (compiled into librigpose_lcm.a for the daemon), Python into
# $(BUILD)/lcmgen/python (package `rigpose`, for subscribers and tests: PYTHONPATH=that folder).
# Never committed: regenerated whenever a .lcm file changes.

LCMGEN := $(BUILD)/lcmgen
LCM_DEFS := $(sort $(wildcard lcm_types/*.lcm))
LCM_GEN_C := $(patsubst lcm_types/%.lcm,$(LCMGEN)/c/%.c,$(LCM_DEFS))

$(LCMGEN)/stamp: $(LCM_DEFS) lcm_types/lcm_types.mk
	rm -rf $(LCMGEN)/c $(LCMGEN)/python && mkdir -p $(LCMGEN)/c $(LCMGEN)/python
	lcm-gen -c --c-cpath $(LCMGEN)/c --c-hpath $(LCMGEN)/c $(LCM_DEFS)
	lcm-gen -p --ppath $(LCMGEN)/python $(LCM_DEFS)
	touch $@

$(LCM_GEN_C): $(LCMGEN)/stamp

# Generated code: its own warnings are not ours to fix, but it must compile cleanly anyway.
$(LCMGEN)/obj/%.o: $(LCMGEN)/c/%.c $(LCMGEN)/stamp
	@mkdir -p $(dir $@)
	$(CC) -std=c99 -O2 -g -Wall -I$(LCMGEN)/c -c $< -o $@

$(LCMGEN)/librigpose_lcm.a: $(patsubst $(LCMGEN)/c/%.c,$(LCMGEN)/obj/%.o,$(LCM_GEN_C))
	rm -f $@ && ar rcs $@ $^

EXTRA_TOOLS += $(LCMGEN)/librigpose_lcm.a
