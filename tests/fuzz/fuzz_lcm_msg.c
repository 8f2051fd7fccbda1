/*
 * fuzz_lcm_msg.c - libFuzzer target: decoding one LCM message type from any bytes, as the tools
 * do (lcm-gen's C binding in $(BUILD)/lcmgen/c). Built once per type of lcm_types/ with
 * -DFUZZ_TYPE=rigpose_pose_t -DFUZZ_HEADER='"rigpose_pose_t.h"' (etc.); -DFUZZ_DECODE=fn
 * -DFUZZ_DECODE_HEADER='"h"' name the decoder the tools use when it is not the generated one
 * (rigpose.image_t: rp_image_t_decode_checked of host_tools/common/rp_lcm_image.h).
 * A message that decodes must encode back to exactly the bytes it was decoded from.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define FUZZ_CAT2(a, b) a##b
#define FUZZ_CAT(a, b) FUZZ_CAT2(a, b)
#include FUZZ_HEADER
#ifdef FUZZ_DECODE_HEADER
#include FUZZ_DECODE_HEADER
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > 1u << 24) {
        return 0;
    }
    FUZZ_TYPE m;
    memset(&m, 0, sizeof m);
#ifdef FUZZ_DECODE
    const int used = FUZZ_DECODE(data, (int)size, &m);
#else
    const int used = FUZZ_CAT(FUZZ_TYPE, _decode)(data, 0, (int)size, &m);
#endif
    if (used < 0) {
        return 0;
    }
    const int n = FUZZ_CAT(FUZZ_TYPE, _encoded_size)(&m);
    uint8_t *back = malloc(n > 0 ? (size_t)n : 1);
    if (back == NULL || n != used || (size_t)used > size ||
        FUZZ_CAT(FUZZ_TYPE, _encode)(back, 0, n, &m) != n || memcmp(back, data, (size_t)n) != 0) {
        __builtin_trap();
    }
    free(back);
    FUZZ_CAT(FUZZ_TYPE, _decode_cleanup)(&m);
    return 0;
}
