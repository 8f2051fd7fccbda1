# host_tools/render/render.mk - rigpose-render and the rendering library (included by the
# top-level Makefile). Host-only C++ with OpenCV, linked with the release core and simulator
# (double, Eigen): the library's rp_real must match it.
#
#   make $(REL)/rigpose-render        the program
#   $(BUILD)/render/librp_render.a    the library (also used by host_tools/research/e2e)

RENDER_DIR := $(BUILD)/render
RENDER_LIB := $(RENDER_DIR)/librp_render.a
RENDER_BIN := $(REL)/rigpose-render
RENDER_HDR := $(wildcard host_tools/render/*.hpp core/include/rigpose/*.h platform/sim/*.h)

# Recursively expanded: pkg-config runs when the recipe runs, after `deps` installed OpenCV.
RENDER_CXXFLAGS = -std=c++14 -O2 -g -DNDEBUG -DRP_REAL_IS_FLOAT=0 -DRP_LINALG_EIGEN=1 $(WARN) \
    $(patsubst -I%,-isystem %,$(shell pkg-config --cflags opencv4)) $(INC) -Ihost_tools/render
RENDER_LIBS = -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -lpthread -lm

$(RENDER_DIR)/%.o: host_tools/render/%.cpp $(RENDER_HDR) | deps
	mkdir -p $(RENDER_DIR)
	$(CXX) $(RENDER_CXXFLAGS) -c $< -o $@

$(RENDER_LIB): $(RENDER_DIR)/rp_render.o $(RENDER_DIR)/rp_discs.o
	rm -f $@ && ar rcs $@ $^

$(RENDER_BIN): host_tools/render/rigpose_render.cpp $(RENDER_LIB) $(REL)/librigpose_sim.a \
               $(REL)/librigpose_core.a $(RENDER_HDR)
	$(CXX) $(RENDER_CXXFLAGS) $< $(RENDER_LIB) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
	    -o $@ $(RENDER_LIBS)

EXTRA_TOOLS += $(RENDER_BIN)

# The test: determinism, a rendered spot lands where rp_camera projects it (with distortion).
RENDER_TEST := $(RENDER_DIR)/test_render
$(RENDER_TEST): host_tools/render/test_render.cpp $(RENDER_LIB) $(REL)/librigpose_sim.a \
                $(REL)/librigpose_core.a $(RENDER_HDR)
	$(CXX) $(RENDER_CXXFLAGS) $< $(RENDER_LIB) $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
	    -o $@ $(RENDER_LIBS)

HOST_EXTRA_TESTS += $(RENDER_TEST)
test: $(RENDER_TEST)
