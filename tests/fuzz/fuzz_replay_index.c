/*
 * fuzz_replay_index.c - libFuzzer target: the replay source's index (frames.csv and truth.csv,
 * platform/src/rp_hal_replay.c) through the HAL's public calls, as the daemon and rigpose-log
 * run it: open, start, grab until the end (at most 64 grabs), close.
 *
 * The input is frames.csv; after its first NUL byte, if any, comes truth.csv. They are written
 * into a private folder that also holds two valid images the rows may name, a.pgm (8x6 PGM) and
 * b.png (8x6 PNG). Inputs with a '/' are skipped: a path out of the folder could name a device
 * or a FIFO of this machine. Two configurations per input: one camera on the first image column,
 * and two cameras, the second on the column named cam1. Not paced (realtime 0), unless the input
 * starts with "#rt": then both are paced at the rows' times with timeout_ms 1 (a grab waits at
 * most 1 ms), which reaches the pacing arithmetic.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <png.h>

#include "fuzz_tmpdir.h"
#include "rigpose/rp_hal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void setup_images(void)
{
    static int done = 0;
    if (done) {
        return;
    }
    uint8_t px[48];
    for (int i = 0; i < 48; i++) {
        px[i] = (uint8_t)(i * 5);
    }
    char pgm[64 + 48];
    const int h = snprintf(pgm, 64, "P5\n8 6\n255\n");
    memcpy(pgm + h, px, 48);
    fuzz_write("a.pgm", pgm, (size_t)h + 48);
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = 8;
    im.height = 6;
    im.format = PNG_FORMAT_GRAY;
    char p[128];
    snprintf(p, sizeof p, "%s/b.png", fuzz_dir());
    if (!png_image_write_to_file(&im, p, 0, px, 8, NULL)) {
        abort();
    }
    done = 1;
}

static void run(uint8_t n_cams, const char *dev1, int paced)
{
    static rp_hal_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.kind = RP_HAL_SRC_REPLAY;
    cfg.n_cams = n_cams;
    cfg.realtime = (uint8_t)paced;
    cfg.timeout_ms = paced ? 1 : 0;
    if (n_cams > 1) {
        snprintf(cfg.cam[1].device, sizeof cfg.cam[1].device, "%s", dev1);
    }
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s", fuzz_dir());
    rp_hal_source_t *src = NULL;
    if (rp_hal_open(&src, &cfg) != RP_HAL_OK) {
        (void)rp_hal_errmsg(NULL);
        return;
    }
    if (rp_hal_start(src) == RP_HAL_OK) {
        static rp_hal_set_t set;
        for (int i = 0; i < 64; i++) {
            const rp_hal_status_t st = rp_hal_grab(src, &set);
            if (st == RP_HAL_E_END) {
                break;
            }
            if (st == RP_HAL_OK) { /* every delivered image is readable to its last byte */
                for (uint8_t k = 0; k < set.n_cams; k++) {
                    const rp_image_t *im = &set.cam[k].img;
                    if (im->data != NULL && im->size > 0) {
                        volatile uint8_t last = im->data[im->size - 1];
                        (void)last;
                    }
                }
            } else if (rp_hal_errmsg(src)[0] == '\0') {
                __builtin_trap(); /* a failure always says why */
            }
        }
        (void)rp_hal_stop(src);
    }
    rp_hal_close(src);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (memchr(data, '/', size) != NULL) {
        return 0;
    }
    setup_images();
    const uint8_t *nul = memchr(data, '\0', size);
    const size_t nf = nul != NULL ? (size_t)(nul - data) : size;
    fuzz_write("frames.csv", data, nf);
    char p[128];
    snprintf(p, sizeof p, "%s/truth.csv", fuzz_dir());
    if (nul != NULL) {
        fuzz_write("truth.csv", nul + 1, size - nf - 1);
    } else {
        unlink(p);
    }
    const int paced = size >= 3 && memcmp(data, "#rt", 3) == 0;
    run(1, "", paced);
    run(2, "cam1", paced);
    return 0;
}
