/*
 * test_idmap.c - the feature id -> slot map: lookups stay right through long random runs of
 * inserts and removals (held against a plain array), a slot never moves while its id lives,
 * group counts and "drop unmarked" follow the group mask, a full map refuses, bad input is
 * refused.
 */
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_idmap.h"

static rp_idmap_t map;

static void test_insert_find_remove(void **state)
{
    (void)state;
    assert_ok(rp_idmap_clear(&map));
    uint16_t s[3], f;
    assert_ok(rp_idmap_insert(&map, 7, 0, &s[0]));
    assert_ok(rp_idmap_insert(&map, 0, 2, &s[1]));
    assert_ok(rp_idmap_insert(&map, 123456789u, 2, &s[2]));
    assert_int_equal(map.n, 3);
    assert_int_equal(map.n_group[0], 1);
    assert_int_equal(map.n_group[2], 2);
    assert_true(s[0] != s[1] && s[1] != s[2] && s[0] != s[2]);
    assert_ok(rp_idmap_find(&map, 0, &f));
    assert_int_equal(f, s[1]);
    assert_int_equal(map.slot_id[s[2]], 123456789u);
    assert_status(rp_idmap_find(&map, 8, &f), RP_E_NOT_FOUND);
    assert_ok(rp_idmap_remove(&map, 0));
    assert_status(rp_idmap_find(&map, 0, &f), RP_E_NOT_FOUND);
    assert_status(rp_idmap_remove(&map, 0), RP_E_NOT_FOUND);
    assert_int_equal(map.n, 2);
    assert_int_equal(map.n_group[2], 1);
    assert_int_equal(map.slot_id[s[1]], RP_IDMAP_EMPTY);
    assert_ok(rp_idmap_find(&map, 7, &f));
    assert_int_equal(f, s[0]);
}

/* Random inserts and removals with ids from a small range (long probe runs, wrap-around at
 * the end of the table), at fills up to the limit; checked against a plain array after every
 * operation batch. */
static void test_random_runs_match_a_plain_array(void **state)
{
    (void)state;
    enum { ID_RANGE = 4 * RP_IDMAP_MAX_SLOTS };
    static uint16_t ref[ID_RANGE]; /* slot + 1 of each id, 0 if not held */
    memset(ref, 0, sizeof(ref));
    assert_ok(rp_idmap_clear(&map));
    uint32_t held = 0, ops = 0, full_seen = 0;
    for (int round = 0; round < 40; ++round) {
        /* Fill towards a target (varies per round), then empty part of it again. */
        const uint32_t target = (uint32_t)(rp_test_urand(0.2, 1.05) * RP_IDMAP_MAX_SLOTS);
        for (int k = 0; k < 3000; ++k, ++ops) {
            const uint32_t id = (uint32_t)rp_test_urand(0, ID_RANGE);
            uint16_t slot;
            if (held < target && !ref[id]) {
                rp_status_t st = rp_idmap_insert(&map, id, (uint8_t)(id % RP_IDMAP_MAX_GROUPS), &slot);
                if (held == RP_IDMAP_MAX_SLOTS) {
                    assert_status(st, RP_E_FULL);
                    full_seen++;
                } else {
                    assert_ok(st);
                    assert_true(slot < RP_IDMAP_MAX_SLOTS);
                    ref[id] = (uint16_t)(slot + 1);
                    held++;
                }
            } else if (ref[id]) {
                if (held > target / 2) {
                    assert_ok(rp_idmap_remove(&map, id));
                    ref[id] = 0;
                    held--;
                }
            } else {
                assert_status(rp_idmap_remove(&map, id), RP_E_NOT_FOUND);
            }
        }
        assert_int_equal(map.n, held);
        uint32_t per_group[RP_IDMAP_MAX_GROUPS] = {0};
        for (uint32_t id = 0; id < ID_RANGE; ++id) {
            uint16_t slot = 0;
            rp_status_t st = rp_idmap_find(&map, id, &slot);
            if (ref[id]) {
                assert_ok(st);
                assert_int_equal(slot + 1, ref[id]); /* the slot never moved */
                assert_int_equal(map.slot_id[slot], id);
                per_group[id % RP_IDMAP_MAX_GROUPS]++;
            } else {
                assert_status(st, RP_E_NOT_FOUND);
            }
        }
        for (uint32_t g = 0; g < RP_IDMAP_MAX_GROUPS; ++g) {
            assert_int_equal(map.n_group[g], per_group[g]);
        }
    }
    assert_true(full_seen > 0);
    printf("  idmap: %u random operations on %d slots (%u refused as full) matched the array\n",
           ops, RP_IDMAP_MAX_SLOTS, full_seen);
}

static void test_drop_unmarked_follows_the_group_mask(void **state)
{
    (void)state;
    assert_ok(rp_idmap_clear(&map));
    uint16_t slot[60];
    for (uint32_t id = 0; id < 60; ++id) {
        assert_ok(rp_idmap_insert(&map, 1000u + id, (uint8_t)(id % 3), &slot[id]));
    }
    for (uint32_t id = 0; id < 60; id += 2) {
        assert_ok(rp_idmap_mark(&map, slot[id])); /* even ids observed */
    }
    uint16_t dropped = 0;
    /* Groups 0 and 1 had an image; group 2 did not and keeps its unmarked ids. */
    assert_ok(rp_idmap_drop_unmarked(&map, 0x3u, &dropped));
    uint32_t want_dropped = 0;
    for (uint32_t id = 0; id < 60; ++id) {
        uint16_t f;
        const int gone = (id % 2 == 1) && (id % 3 != 2);
        want_dropped += (uint32_t)gone;
        assert_status(rp_idmap_find(&map, 1000u + id, &f), gone ? RP_E_NOT_FOUND : RP_OK);
        if (!gone) {
            assert_int_equal(f, slot[id]);
            assert_int_equal(map.slot_mark[f], 0); /* marks cleared */
        }
    }
    assert_int_equal(dropped, want_dropped);
    assert_int_equal(map.n, 60 - want_dropped);
    /* Nothing marked now: dropping over every group empties the map. */
    assert_ok(rp_idmap_drop_unmarked(&map, RP_IDMAP_ALL_GROUPS, &dropped));
    assert_int_equal(dropped, 60 - want_dropped);
    assert_int_equal(map.n, 0);
    for (uint32_t g = 0; g < RP_IDMAP_MAX_GROUPS; ++g) {
        assert_int_equal(map.n_group[g], 0);
    }
    /* Freed slots are handed out again. */
    uint16_t s;
    assert_ok(rp_idmap_insert(&map, 5, 0, &s));
    assert_true(s < RP_IDMAP_MAX_SLOTS);
    assert_ok(rp_idmap_mark(&map, s));
    assert_ok(rp_idmap_clear_marks(&map));
    assert_int_equal(map.slot_mark[s], 0);
}

static void test_bad_input_is_refused(void **state)
{
    (void)state;
    uint16_t s, t;
    assert_status(rp_idmap_clear(NULL), RP_E_ARG);
    assert_ok(rp_idmap_clear(&map));
    assert_status(rp_idmap_insert(NULL, 1, 0, &s), RP_E_ARG);
    assert_status(rp_idmap_insert(&map, 1, 0, NULL), RP_E_ARG);
    assert_status(rp_idmap_insert(&map, RP_IDMAP_EMPTY, 0, &s), RP_E_ARG);
    assert_status(rp_idmap_insert(&map, 1, RP_IDMAP_MAX_GROUPS, &s), RP_E_ARG);
    assert_int_equal(map.n, 0);
    assert_ok(rp_idmap_insert(&map, 1, 0, &s));
    assert_status(rp_idmap_insert(&map, 1, 1, &t), RP_E_ARG); /* already held */
    assert_int_equal(t, s);
    assert_int_equal(map.n, 1);
    assert_int_equal(map.n_group[1], 0);
    assert_status(rp_idmap_find(NULL, 1, &s), RP_E_ARG);
    assert_status(rp_idmap_find(&map, 1, NULL), RP_E_ARG);
    assert_status(rp_idmap_find(&map, RP_IDMAP_EMPTY, &t), RP_E_NOT_FOUND);
    assert_status(rp_idmap_remove(NULL, 1), RP_E_ARG);
    assert_status(rp_idmap_remove(&map, RP_IDMAP_EMPTY), RP_E_NOT_FOUND);
    assert_status(rp_idmap_mark(NULL, s), RP_E_ARG);
    assert_status(rp_idmap_mark(&map, RP_IDMAP_MAX_SLOTS), RP_E_ARG);
    assert_status(rp_idmap_mark(&map, (uint16_t)(s + 1)), RP_E_ARG); /* a free slot */
    assert_status(rp_idmap_drop_unmarked(NULL, RP_IDMAP_ALL_GROUPS, NULL), RP_E_ARG);
    assert_status(rp_idmap_clear_marks(NULL), RP_E_ARG);
    assert_ok(rp_idmap_find(&map, 1, &t)); /* still usable */
    assert_int_equal(t, s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_insert_find_remove),
        cmocka_unit_test(test_random_runs_match_a_plain_array),
        cmocka_unit_test(test_drop_unmarked_follows_the_group_mask),
        cmocka_unit_test(test_bad_input_is_refused),
    };
    return cmocka_run_group_tests_name("idmap", tests, NULL, NULL);
}
