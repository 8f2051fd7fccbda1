/*
 * static_4cam.c - the core's RAM for four cameras, compiled alone so that `size` reports it
 * (.bss): the image pipeline of rp_pipe.h (4 trackers at the build's RP_TRACK_MAX_W x H, the
 * stereo matcher, the largest estimator of its union, the frame set) and, for comparison, the
 * bare minimum of the non-overlapping layout (4 trackers + the gc estimator).
 */
#include "rigpose/rp_pipe.h"

#if BT_STATIC_PIPE
rp_pipe_t bt_static_pipe;
#else
rp_tracker_t bt_static_trackers[4];
rp_vo_gc_t bt_static_gc;
#endif
