/*
 * fuzz_image.c - libFuzzer target: image decoding as the replay source does it
 * (platform/src/rp_hal_replay.c: PNG through libpng's simplified API, else binary PGM, told
 * apart by the first bytes, at most RP_HAL_MAX_W x RP_HAL_MAX_H), through the HAL's public calls:
 * the input is written as the one image of a one-row frames.csv and grabbed once. A delivered
 * image must be as big as it says (ASan checks the last byte).
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_tmpdir.h"
#include "rigpose/rp_hal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int ready = 0;
    if (!ready) {
        static const char csv[] = "utime_us,cam0\n1000,img\n";
        fuzz_write("frames.csv", csv, sizeof csv - 1);
        ready = 1;
    }
    fuzz_write("img", data, size);
    static rp_hal_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.kind = RP_HAL_SRC_REPLAY;
    cfg.n_cams = 1;
    snprintf(cfg.replay_index, sizeof cfg.replay_index, "%s", fuzz_dir());
    rp_hal_source_t *src = NULL;
    if (rp_hal_open(&src, &cfg) != RP_HAL_OK || rp_hal_start(src) != RP_HAL_OK) {
        __builtin_trap(); /* the index is fixed and valid */
    }
    static rp_hal_set_t set;
    const rp_hal_status_t st = rp_hal_grab(src, &set);
    if (st == RP_HAL_OK) {
        const rp_image_t *im = &set.cam[0].img;
        if (im->data == NULL || im->w == 0 || im->h == 0 || im->w > RP_HAL_MAX_W ||
            im->h > RP_HAL_MAX_H || im->size != (uint32_t)im->w * im->h) {
            __builtin_trap();
        }
        volatile uint8_t last = im->data[im->size - 1];
        (void)last;
    } else if (st != RP_HAL_E_FORMAT || rp_hal_errmsg(src)[0] == '\0') {
        __builtin_trap(); /* a bad image is a format error that says why */
    }
    (void)rp_hal_stop(src);
    rp_hal_close(src);
    return 0;
}
