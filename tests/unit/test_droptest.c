/*
 * test_droptest.c - Page's CUSUM drop test (rp_droptest.h): a landmark whose observations the
 * updates keep leaving out is dropped, at once on clean frame sets and only after a run of
 * frame sets when many sound ones are left out too; one taken in is never dropped; a reset
 * slot starts afresh; bad input is refused.
 */
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_droptest.h"

static rp_droptest_t dt;

/* n observations, one per slot 0..n-1, slot `bad` always left out and every slot below
 * n_noisy left out at frame sets where (frame + slot) % period == 0; returns the first frame
 * set at which `bad`'s landmark is dropped (or frames if never), and counts the others
 * dropped in *n_sound_dropped. */
static int frames_to_drop(uint32_t n, uint16_t bad, uint32_t n_noisy, int period, int frames,
                          int *n_sound_dropped)
{
    uint16_t slot[64];
    uint8_t in[64], keep[64];
    for (uint16_t s = 0; s < n; ++s) {
        assert_ok(rp_droptest_reset_slot(&dt, s));
        slot[s] = s;
    }
    int dropped_at = frames;
    *n_sound_dropped = 0;
    for (int f = 0; f < frames; ++f) {
        for (uint16_t s = 0; s < n; ++s) {
            in[s] = (uint8_t)!(s == bad || (s < n_noisy && (f + s) % period == 0));
        }
        assert_ok(rp_droptest_run(&dt, slot, in, n, 10, RP_C(100.0), keep));
        for (uint16_t s = 0; s < n; ++s) {
            if (!keep[s] && s == bad && dropped_at == frames) {
                dropped_at = f;
            } else if (!keep[s] && s != bad) {
                ++*n_sound_dropped;
            }
        }
    }
    return dropped_at;
}

static void test_a_track_always_left_out_is_dropped(void **state)
{
    (void)state;
    int sound = 0;
    /* clean: eps ~ 1/40: log(0.9 / eps) ~ 3.6 per frame set against log(100) = 4.6: two */
    const int clean = frames_to_drop(40, 39, 0, 1, 20, &sound);
    assert_true(clean <= 2);
    assert_int_equal(sound, 0);
    /* a third of the sound ones left out every third frame set (eps ~ 1/3): it takes longer,
     * and the sound ones, each out one frame set in three, are kept */
    const int noisy = frames_to_drop(40, 39, 39, 3, 40, &sound);
    print_message("dropped after %d frame sets clean, %d with eps 1/3\n", clean + 1, noisy + 1);
    assert_true(noisy > clean);
    assert_true(noisy < 40);
    assert_int_equal(sound, 0);
}

static void test_slots_without_a_landmark_are_passed_through(void **state)
{
    (void)state;
    const uint16_t slot[3] = {0, RP_IDMAP_MAX_SLOTS, 1};
    const uint8_t in[3] = {1, 0, 1};
    uint8_t keep[3];
    assert_ok(rp_droptest_reset_slot(&dt, 0));
    assert_ok(rp_droptest_reset_slot(&dt, 1));
    assert_ok(rp_droptest_run(&dt, slot, in, 3, 1, RP_C(100.0), keep));
    assert_int_equal(keep[0], 1);
    assert_int_equal(keep[1], 0); /* no landmark: its own judgement */
    assert_int_equal(keep[2], 1);
}

static void test_bad_input_is_refused(void **state)
{
    (void)state;
    const uint16_t slot[1] = {0};
    const uint8_t in[1] = {1};
    uint8_t keep[1];
    assert_status(rp_droptest_reset_slot(NULL, 0), RP_E_ARG);
    assert_status(rp_droptest_reset_slot(&dt, RP_IDMAP_MAX_SLOTS), RP_E_ARG);
    assert_status(rp_droptest_run(NULL, slot, in, 1, 1, RP_C(100.0), keep), RP_E_ARG);
    assert_status(rp_droptest_run(&dt, NULL, in, 1, 1, RP_C(100.0), keep), RP_E_ARG);
    assert_status(rp_droptest_run(&dt, slot, in, 1, 1, RP_C(1.0), keep), RP_E_ARG);
    assert_status(rp_droptest_run(&dt, slot, in, 1, 1, (rp_real)NAN, keep), RP_E_ARG);
    assert_ok(rp_droptest_run(&dt, NULL, NULL, 0, 1, RP_C(100.0), NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_track_always_left_out_is_dropped),
        cmocka_unit_test(test_slots_without_a_landmark_are_passed_through),
        cmocka_unit_test(test_bad_input_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
