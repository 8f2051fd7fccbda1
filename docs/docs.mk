# docs/docs.mk - the pictures of docs/ and the test of README's code (included by the Makefile).
#
#   make docs-figures        regenerates docs/lcm-spy.png (scripts/lcm-spy-screenshot.sh),
#                            docs/rigpose_eval_render.png (host_tools/eval/plot_render_run.sh) and
#                            the Foxglove layout (make view-layout)
#   docs/test_readme.sh      README's C, C++ and Python subscribers, compiled and run against the
#                            daemon (make test)

.PHONY: docs-figures
docs-figures: deps $(REL)/rigpose $(REL)/rigpose-render $(REL)/rigpose-eval $(BUILD)/lcmgen/rigpose_lcm.jar view-layout
	scripts/lcm-spy-screenshot.sh $(BUILD) docs/lcm-spy.png
	host_tools/eval/plot_render_run.sh $(BUILD) docs/rigpose_eval_render.png 100 320x240

$(BUILD)/docs/run_test_readme: docs/test_readme.sh
	@mkdir -p $(@D)
	printf '#!/bin/sh\nexec %s/docs/test_readme.sh %s "$$@"\n' "$(CURDIR)" "$(BUILD)" > $@
	chmod +x $@

HOST_EXTRA_TESTS += $(BUILD)/docs/run_test_readme
SERIAL_TESTS += $(BUILD)/docs/run_test_readme
test: $(BUILD)/docs/run_test_readme $(REL)/rigpose $(BUILD)/lcmgen/librigpose_lcm.a \
      $(BUILD)/lcmgen/rigpose_lcm-1.0-py3-none-any.whl
