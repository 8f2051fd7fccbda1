/*
 * fuzz_config.c - libFuzzer target: the configuration parser (platform/src/rp_config.c) on any
 * bytes, through its memory entry point rp_config_parse, as the daemon and the tools load a
 * file. Finds crashes, sanitizer reports and hangs (libFuzzer's -timeout); an input is refused or
 * accepted, nothing else is checked (the parser's own tests check the messages).
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rigpose/rp_config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static rp_config_t cfg;
    char err[RP_CFG_ERR_MAX];
    const rp_cfg_status_t st = rp_config_parse((const char *)data, size, "fuzz/rig.yaml", &cfg,
                                               err, sizeof err);
    /* a refusal says something; the message is a terminated string either way */
    if (memchr(err, '\0', sizeof err) == NULL || (st != RP_CFG_OK && err[0] == '\0')) {
        __builtin_trap();
    }
    return 0;
}
