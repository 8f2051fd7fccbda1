# host_tools/common/common.mk - what the host tools share that is compiled (included by the
# top-level Makefile, before eval/ and log/): the LCM log reader (rp_lcmlog.h) and its tests.
#
#   $(LCMLOG_OBJ)                         the reader, release flags, linked by rigpose-eval and
#                                         rigpose-log
#   $(BUILD)/common/test_lcmlog           its cmocka test (ASan + UBSan), run by make test
#   host_tools/common/test_lcmlog_cli.sh  rigpose-eval and rigpose-log replay on a log with a
#                                         0x7fffffff length, a truncated one and one with garbage
#                                         mid-way (one line with the offset, exit 1; --tolerant),
#                                         and rigpose-log mcap (rigpose-view, rp_lcmlog.py) on them

CMN := $(BUILD)/common
LCMLOG_OBJ := $(CMN)/rp_lcmlog.o
CMN_CFLAGS := $(CSTD) $(WARN) -Wconversion -D_POSIX_C_SOURCE=200809L -Ihost_tools/common

$(LCMLOG_OBJ): host_tools/common/rp_lcmlog.c host_tools/common/rp_lcmlog.h
	@mkdir -p $(@D)
	$(CC) $(CMN_CFLAGS) -O2 -g -c $< -o $@

$(CMN)/test_lcmlog: host_tools/common/test_lcmlog.c host_tools/common/rp_lcmlog.c \
                    host_tools/common/rp_lcmlog.h | deps
	@mkdir -p $(@D)
	$(CC) $(CMN_CFLAGS) -O1 -g $(SAN) host_tools/common/test_lcmlog.c host_tools/common/rp_lcmlog.c \
	    -o $@ $(SAN) -lcmocka -llcm

HOST_EXTRA_TESTS += $(CMN)/test_lcmlog host_tools/common/test_lcmlog_cli.sh
test: $(CMN)/test_lcmlog $(REL)/rigpose-eval $(REL)/rigpose-log $(REL)/rigpose-view
export RP_LCMLOG_WORK = $(CMN)/work
