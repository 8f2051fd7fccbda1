# host_tools/research/gcdiag/gcdiag.mk - rigpose-gcdiag: gc from rendered pixels against gc fed the
# renderer's true projections with the tracker's ids and lifetimes; the tracker's error by age.
# Built by `make research` (RESEARCH_TOOLS); not a test.

GCDIAG_BIN := $(REL)/rigpose-gcdiag

$(GCDIAG_BIN): host_tools/research/gcdiag/rigpose_gcdiag.cpp $(BUILD)/render/librp_render.a \
    $(REL)/librigpose_sim.a $(REL)/librigpose_core.a \
    $(wildcard host_tools/render/*.hpp core/include/rigpose/*.h)
	$(CXX) $(RENDER_CXXFLAGS) $< $(BUILD)/render/librp_render.a $(REL)/librigpose_sim.a \
	    $(REL)/librigpose_core.a -o $@ $(RENDER_LIBS)

RESEARCH_TOOLS += $(GCDIAG_BIN)
