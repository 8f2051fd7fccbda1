/*
 * rp_prefault.h - write every page of a block once, so that a real-time loop never takes its
 * first-touch page faults (the daemon's and rigpose-frontend's pipelines).
 *
 * A pipeline's state is megabytes of static tables (zero pages the kernel maps on first write)
 * that fill as tracks, landmarks and ids come and go: without this, frame sets long after the
 * start take page faults in the loop (a latency no benchmark of the first minute shows) and the
 * resident set creeps up as new parts of the tables are first written. Each page is written
 * with what it holds, so it may be called on initialised state; call it before other threads
 * use the block.
 */
#ifndef RP_PREFAULT_H
#define RP_PREFAULT_H

#include <stddef.h>
#include <unistd.h>

static inline void rp_prefault(void *p, size_t n)
{
    const long pg = sysconf(_SC_PAGESIZE);
    const size_t step = pg > 0 ? (size_t)pg : 4096u;
    volatile unsigned char *c = (volatile unsigned char *)p;
    for (size_t i = 0; i < n; i += step) {
        c[i] = c[i];
    }
}

#endif /* RP_PREFAULT_H */
