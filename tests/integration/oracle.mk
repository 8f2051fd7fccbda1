# tests/integration/oracle.mk - C++ tests that hold the core to OpenCV as an oracle (included by the top-level
# Makefile; see HOST_EXTRA_TESTS there). They link the release core (double, Eigen, -O2, no
# sanitizer: OpenCV is not built with one) and run under `make test`.

ORACLE_DIR := $(BUILD)/oracle
ORACLE_TRACK := $(ORACLE_DIR)/oracle_track

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
ORACLE_CXXFLAGS = -std=c++14 -O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 $(WARN) \
    $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) $(INC)
ORACLE_LIBS = -lopencv_video -lopencv_imgproc -lopencv_core -lm

$(ORACLE_TRACK): tests/integration/oracle_track.cpp $(REL)/librigpose_core.a \
                 $(wildcard core/include/rigpose/*.h) | deps
	mkdir -p $(ORACLE_DIR)
	$(CXX) $(ORACLE_CXXFLAGS) $< $(REL)/librigpose_core.a -o $@ $(ORACLE_LIBS)

HOST_EXTRA_TESTS += $(ORACLE_TRACK)
test: $(ORACLE_TRACK)
