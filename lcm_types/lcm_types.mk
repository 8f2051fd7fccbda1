# lcm_types/lcm_types.mk - generate the LCM bindings of lcm_types/*.lcm with lcm-gen during the
# build, one folder per language under $(BUILD)/lcmgen:
#   c/        C (compiled into librigpose_lcm.a for the daemon and the tools)
#   cpp/      C++ headers (lcm-gen -x, C++11): #include <rigpose/pose_t.hpp>, link -llcm
#   python/   Python package `rigpose` (PYTHONPATH=that folder), and the same as a wheel
#             rigpose_lcm-$(LCM_PY_VERSION)-py3-none-any.whl (`pip install build/lcmgen/*.whl`)
#   java/     Java sources, compiled against Debian's liblcm-java into rigpose_lcm.jar: with it
#             on CLASSPATH, lcm-spy decodes every rigpose channel
# Never committed: regenerated whenever a .lcm file changes.

LCMGEN := $(BUILD)/lcmgen
LCM_DEFS := $(sort $(wildcard lcm_types/*.lcm))
LCM_GEN_C := $(patsubst lcm_types/%.lcm,$(LCMGEN)/c/%.c,$(LCM_DEFS))
LCM_JAR_SYS := /usr/share/java/lcm.jar
LCM_JAR := $(LCMGEN)/rigpose_lcm.jar
LCM_PY_VERSION := 1.0
LCM_WHEEL := $(LCMGEN)/rigpose_lcm-$(LCM_PY_VERSION)-py3-none-any.whl

$(LCMGEN)/stamp: $(LCM_DEFS) lcm_types/lcm_types.mk
	rm -rf $(LCMGEN)/c $(LCMGEN)/python $(LCMGEN)/cpp $(LCMGEN)/java
	mkdir -p $(LCMGEN)/c $(LCMGEN)/python $(LCMGEN)/cpp $(LCMGEN)/java/src
	lcm-gen -c --c-cpath $(LCMGEN)/c --c-hpath $(LCMGEN)/c $(LCM_DEFS)
	lcm-gen -p --ppath $(LCMGEN)/python $(LCM_DEFS)
	lcm-gen -x --cpp-std c++11 --cpp-hpath $(LCMGEN)/cpp $(LCM_DEFS)
	lcm-gen -j --jpath $(LCMGEN)/java/src $(LCM_DEFS)
	touch $@

$(LCM_GEN_C): $(LCMGEN)/stamp

# Generated code: its own warnings are not ours to fix, but it must compile cleanly anyway.
$(LCMGEN)/obj/%.o: $(LCMGEN)/c/%.c $(LCMGEN)/stamp
	@mkdir -p $(dir $@)
	$(CC) -std=c99 -O2 -g -Wall -I$(LCMGEN)/c -c $< -o $@

$(LCMGEN)/librigpose_lcm.a: $(patsubst $(LCMGEN)/c/%.c,$(LCMGEN)/obj/%.o,$(LCM_GEN_C))
	rm -f $@ && ar rcs $@ $^

# Java: the generated classes against Debian's lcm.jar, into one jar (generated code: its lint
# warnings, redundant casts, are not ours).
$(LCM_JAR): $(LCMGEN)/stamp
	rm -rf $(LCMGEN)/java/classes && mkdir -p $(LCMGEN)/java/classes
	javac -nowarn --release 11 -cp $(LCM_JAR_SYS) -d $(LCMGEN)/java/classes \
	    $$(find $(LCMGEN)/java/src -name '*.java')
	jar cf $@ -C $(LCMGEN)/java/classes .

# Python: a wheel of the generated package, written by lcm_types/make_wheel.py (no network).
$(LCM_WHEEL): $(LCMGEN)/stamp lcm_types/make_wheel.py
	$(PY) lcm_types/make_wheel.py $(LCMGEN)/python $(LCM_PY_VERSION) $(LCMGEN)

EXTRA_TOOLS += $(LCMGEN)/librigpose_lcm.a $(LCM_JAR) $(LCM_WHEEL)

# ---- test: a C++ and a Java subscriber receive the daemon's poses --------------------------------
# The C++ subscriber is built like every host test: -Wall -Wextra -Werror, ASan + UBSan.
LCMT := $(BUILD)/lcm_types
$(LCMT)/sub_cpp: lcm_types/tests/sub_cpp.cpp $(LCMGEN)/stamp
	@mkdir -p $(@D)
	$(CXX) -std=c++11 $(WARN) -O1 -g $(SAN) -isystem $(LCMGEN)/cpp $< -o $@ $(SAN) -llcm
$(LCMT)/SubJava.class: lcm_types/tests/SubJava.java $(LCM_JAR)
	@mkdir -p $(@D)
	javac -Xlint:all -Werror --release 11 -cp $(LCM_JAR_SYS):$(LCM_JAR) -d $(LCMT) $<
$(LCMT)/run_test_bindings: lcm_types/tests/test_bindings.sh
	@mkdir -p $(@D)
	printf '#!/bin/sh\nexec %s/lcm_types/tests/test_bindings.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

HOST_EXTRA_TESTS += $(LCMT)/run_test_bindings
SERIAL_TESTS += $(LCMT)/run_test_bindings
test: $(LCMT)/sub_cpp $(LCMT)/SubJava.class $(LCMT)/run_test_bindings $(LCM_JAR) $(LCM_WHEEL) \
      $(REL)/rigpose
