# platform/platform.mk - the HAL library, its host tests and the V4L2 test in a VM (included by
# the top-level Makefile).
#
#   $(BUILD)/platform/librigpose_hal.a       every platform/src/*.c (HAL sources, configuration),
#                                            release flags (double, Eigen, -O2): for the daemon
#   $(BUILD)/platform/san/librigpose_hal.a   the same under ASan+UBSan, for the host tests
#   $(BUILD)/platform/tests/test_*           tests/unit/platform/test_*.c (cmocka), run by make test
#   $(BUILD)/vm/vivid_capture                static capture program run inside the VM
#   $(BUILD)/vm/run_vivid_test               tests/vm/vivid_test.sh with this build's paths:
#                                            boots a Debian kernel under qemu, loads vivid with
#                                            4 devices, captures from all of them, then runs the
#                                            daemon on them (make test; make vm-test alone)
# Link a program with the HAL: $(BUILD)/platform/librigpose_hal.a $(REL)/librigpose_sim.a
# $(REL)/librigpose_core.a $(HAL_LIBS) -lstdc++ -lm.

PLAT := $(BUILD)/platform
HAL_C := $(sort $(wildcard platform/src/*.c))
HAL_H := $(wildcard platform/include/rigpose/*.h platform/src/*.h core/include/rigpose/*.h \
                    platform/sim/*.h)
HAL_INC := -Iplatform/include $(INC)
HAL_CFLAGS := $(CSTD) $(CORE_WARN) -Wno-format-truncation -D_DEFAULT_SOURCE $(HAL_INC) $(VDEF_double-eigen)
HAL_LIBS := -lyaml -lpng -ljpeg -lz -lpthread
HAL_LIB := $(PLAT)/librigpose_hal.a
HAL_SAN_LIB := $(PLAT)/san/librigpose_hal.a

$(PLAT)/obj/%.o: platform/src/%.c $(HAL_H) | deps
	@mkdir -p $(@D)
	$(CC) $(HAL_CFLAGS) -O2 -g -DNDEBUG -c $< -o $@
$(PLAT)/san/obj/%.o: platform/src/%.c $(HAL_H) | deps
	@mkdir -p $(@D)
	$(CC) $(HAL_CFLAGS) -O1 -g $(SAN) -c $< -o $@
$(HAL_LIB): $(patsubst platform/src/%.c,$(PLAT)/obj/%.o,$(HAL_C))
	rm -f $@ && ar rcs $@ $^
$(HAL_SAN_LIB): $(patsubst platform/src/%.c,$(PLAT)/san/obj/%.o,$(HAL_C))
	rm -f $@ && ar rcs $@ $^

# Host tests: sanitised, double / Eigen core (the HAL has no numerics of its own).
HAL_TESTS := $(patsubst tests/unit/platform/%.c,$(PLAT)/tests/%,$(wildcard tests/unit/platform/test_*.c))
$(PLAT)/tests/%: tests/unit/platform/%.c tests/rp_test.h $(HAL_SAN_LIB) \
                 $(BUILD)/double-eigen/librigpose_sim.a $(BUILD)/double-eigen/librigpose_core.a
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(WARN) -D_DEFAULT_SOURCE $(HAL_INC) -Itests -O1 -g $(SAN) \
	    $(VDEF_double-eigen) $< $(HAL_SAN_LIB) $(BUILD)/double-eigen/librigpose_sim.a \
	    $(BUILD)/double-eigen/librigpose_core.a -o $@ $(SAN) -lcmocka $(HAL_LIBS) -lstdc++ -lm

# The VM test: a static capture program (the guest has no libraries) and the script's wrapper.
VM := $(BUILD)/vm
VIVID_CAPTURE := $(VM)/vivid_capture
$(VIVID_CAPTURE): tests/vm/vivid_capture.c $(HAL_LIB) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(WARN) -D_DEFAULT_SOURCE $(HAL_INC) -O2 -g $(VDEF_double-eigen) $< $(HAL_LIB) \
	    $(REL)/librigpose_sim.a $(REL)/librigpose_core.a -o $@ -static $(HAL_LIBS) -lstdc++ -lm
# The daemon (daemon/daemon.mk: $(REL)/rigpose, dynamic; its libraries go into the initramfs)
# also runs in the VM on the four vivid cameras (tests/vm/vivid_rig.yaml), once it exists.
VM_DAEMON := $(if $(wildcard daemon/rigpose.c),$(REL)/rigpose)
VM_DAEMON_ARGS := $(if $(VM_DAEMON),"$(abspath $(VM_DAEMON))" "$(CURDIR)/tests/vm/vivid_rig.yaml")
$(VM)/run_vivid_test: tests/vm/vivid_test.sh tests/vm/vivid_rig.yaml $(VIVID_CAPTURE) $(VM_DAEMON)
	@mkdir -p $(@D)
	printf '#!/bin/sh\nexec %s/tests/vm/vivid_test.sh %s %s %s "$$@"\n' "$(CURDIR)" \
	    "$(abspath $(VM))" "$(abspath $(VIVID_CAPTURE))" '$(VM_DAEMON_ARGS)' > $@
	chmod +x $@

hal: $(HAL_LIB)
.PHONY: hal vm-test
vm-test: $(VM)/run_vivid_test
	$(VM)/run_vivid_test

HOST_EXTRA_TESTS += $(HAL_TESTS)
test: $(HAL_TESTS)
ifneq ($(wildcard tests/vm/vivid_test.sh),)
HOST_EXTRA_TESTS += $(VM)/run_vivid_test
test: $(VM)/run_vivid_test
endif
