# host_tools/view/view.mk - rigpose-view (Python, PyPI foxglove-sdk) and its tests (included by
# the top-level Makefile).
#
#   $(REL)/rigpose-view             wrapper: the venv's Python, the generated `rigpose` package,
#                                   host_tools/view/rigpose_view.py
#   host_tools/view/test_view.sh    the README's quick start (daemon, rigpose-view --mcap, check);
#                                   every pose of a 300-set run in the MCAP (PyPI mcap); an LCM log
#                                   through `rigpose-log mcap`; a WebSocket client on the live
#                                   server receives the poses; camera images of a rendered run

# $(call py_tool,SCRIPT): the recipe of a wrapper that runs SCRIPT with the venv's Python and
# the generated `rigpose` package.
define py_tool
	@mkdir -p $(@D)
	printf '#!/bin/sh\n# %s of %s (%s)\nPYTHONPATH="%s$${PYTHONPATH:+:$$PYTHONPATH}" exec "%s" "%s" "$$@"\n' \
	    "$(notdir $@)" "$(CURDIR)" "$(1)" "$(abspath $(BUILD)/lcmgen/python)" "$(PY)" "$(CURDIR)/$(1)" > $@
	chmod +x $@
endef

VIEW_BIN := $(REL)/rigpose-view
$(VIEW_BIN): host_tools/view/view.mk $(BUILD)/lcmgen/stamp
	$(call py_tool,host_tools/view/rigpose_view.py)

EXTRA_TOOLS += $(VIEW_BIN)

# rigpose-offsets: the cameras' clock offsets of a status message, written back into a
# configuration file (host_tools/view/rigpose_offsets.py, docs/time.md); its test.
OFFSETS_BIN := $(REL)/rigpose-offsets
$(OFFSETS_BIN): host_tools/view/view.mk $(BUILD)/lcmgen/stamp
	$(call py_tool,host_tools/view/rigpose_offsets.py)
EXTRA_TOOLS += $(OFFSETS_BIN)

$(BUILD)/view/run_test_offsets: host_tools/view/test_offsets.sh
	@mkdir -p $(@D)
	printf '#!/bin/sh\nexec %s/host_tools/view/test_offsets.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@
HOST_EXTRA_TESTS += $(BUILD)/view/run_test_offsets
test: $(BUILD)/view/run_test_offsets $(OFFSETS_BIN) $(REL)/rigpose
HOST_EXTRA_TESTS += host_tools/view/test_view.sh
SERIAL_TESTS += host_tools/view/test_view.sh
test: $(VIEW_BIN) $(REL)/rigpose $(REL)/rigpose-log $(REL)/rigpose-render
export RP_VIEW_BIN = $(VIEW_BIN)

# The Foxglove layout for these topics, regenerated from host_tools/view/make_layout.py
# (test_view.sh checks the committed file is what the script writes).
.PHONY: view-layout
view-layout: deps
	$(PY) host_tools/view/make_layout.py host_tools/view/rigpose.layout.json
