/*
 * test_lmtab.c - the estimators' landmark table: insert / find / slot, gathering a frame set's
 * observations (camera order, group filter, non-finite pixels, capacity), marking and dropping,
 * refining the points of used observations, and bad input.
 */
#include <math.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_lmtab.h"
#include "rp_sim.h"

static rp_lmtab_t tab; /* large: static, as the estimators hold it */
static rp_frameset_t fs;
static rp_obs_t obs[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM];
static uint32_t ids[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM];

static rp_point3_t point(rp_real x, rp_real y, rp_real z)
{
    rp_point3_t p;
    memset(&p, 0, sizeof(p));
    p.M[0] = x;
    p.M[1] = y;
    p.M[2] = z;
    p.C[0] = p.C[3] = p.C[5] = RP_C(0.01);
    return p;
}

static void feat(uint8_t cam, uint32_t id, rp_real u, rp_real v)
{
    rp_feat_t *f = &fs.f[cam][fs.n[cam]++];
    f->id = id;
    f->uv[0] = u;
    f->uv[1] = v;
}

static void test_insert_find_and_slot(void **state)
{
    (void)state;
    assert_ok(rp_lmtab_clear(&tab));
    const rp_point3_t p = point(RP_C(1.0), RP_C(2.0), RP_C(3.0));
    uint16_t s, t;
    assert_ok(rp_lmtab_insert(&tab, 42, 1, &p, &s));
    assert_ok(rp_lmtab_find(&tab, 42, &t));
    assert_int_equal(s, t);
    uint32_t id;
    uint8_t group;
    rp_point3_t q;
    assert_ok(rp_lmtab_slot(&tab, s, &id, &group, &q));
    assert_int_equal(id, 42);
    assert_int_equal(group, 1);
    assert_memory_equal(&q, &p, sizeof(p));
    assert_status(rp_lmtab_find(&tab, 43, &t), RP_E_NOT_FOUND);
    assert_status(rp_lmtab_insert(&tab, 42, 0, &p, NULL), RP_E_ARG); /* held already */
    assert_status(rp_lmtab_slot(&tab, (uint16_t)(s + 1), NULL, NULL, NULL), RP_E_NOT_FOUND);
    assert_int_equal(tab.map.n, 1);
    /* full: every slot taken, the next is refused and nothing changes */
    for (uint32_t i = 1; tab.map.n < RP_IDMAP_MAX_SLOTS; ++i) {
        assert_ok(rp_lmtab_insert(&tab, 1000 + i, 0, &p, NULL));
    }
    assert_status(rp_lmtab_insert(&tab, 7, 0, &p, NULL), RP_E_FULL);
    assert_status(rp_lmtab_find(&tab, 7, &t), RP_E_NOT_FOUND);
    assert_ok(rp_lmtab_clear(&tab));
    assert_int_equal(tab.map.n, 0);
}

static void test_gather_follows_camera_order_and_groups(void **state)
{
    (void)state;
    assert_ok(rp_lmtab_clear(&tab));
    memset(&fs, 0, sizeof(fs));
    rp_point3_t p1 = point(RP_C(0.1), RP_C(0.0), RP_C(1.0));
    rp_point3_t p2 = point(RP_C(0.2), RP_C(0.0), RP_C(1.0));
    rp_point3_t p3 = point(RP_C(0.3), RP_C(0.0), RP_C(1.0));
    assert_ok(rp_lmtab_insert(&tab, 1, 0, &p1, NULL)); /* held by camera 0 */
    assert_ok(rp_lmtab_insert(&tab, 2, 2, &p2, NULL)); /* held by camera 2 */
    assert_ok(rp_lmtab_insert(&tab, 3, 2, &p3, NULL));
    feat(0, 1, RP_C(10.0), RP_C(11.0));
    feat(0, 9, RP_C(12.0), RP_C(13.0));      /* not held */
    feat(2, 2, RP_C(20.0), RP_C(21.0));
    feat(2, 3, (rp_real)NAN, RP_C(31.0));    /* non-finite: skipped */
    feat(2, 1, RP_C(40.0), RP_C(41.0));      /* held, but by camera 0 */
    const uint8_t cams[2] = {2, 0};
    uint32_t n = 0;
    assert_ok(rp_lmtab_gather(&tab, &fs, cams, 2, 0, obs, ids, 16, &n));
    assert_int_equal(n, 3); /* camera 2 first: ids 2, 1, then camera 0: id 1 */
    assert_int_equal(ids[0], 2);
    assert_int_equal(ids[1], 1);
    assert_int_equal(ids[2], 1);
    assert_int_equal(obs[0].cam, 2);
    assert_int_equal(obs[2].cam, 0);
    assert_true(obs[0].uv[0] == RP_C(20.0) && obs[0].M[0] == p2.M[0] && obs[0].w == RP_C(1.0));
    assert_true(obs[1].M[0] == p1.M[0]);
    /* own_group: a landmark counts only in the camera that holds it */
    assert_ok(rp_lmtab_gather(&tab, &fs, cams, 2, 1, obs, ids, 16, &n));
    assert_int_equal(n, 2);
    assert_int_equal(ids[0], 2);
    assert_int_equal(ids[1], 1);
    assert_int_equal(obs[1].cam, 0);
    /* capacity: the first cap are kept */
    assert_status(rp_lmtab_gather(&tab, &fs, cams, 2, 0, obs, ids, 2, &n), RP_E_FULL);
    assert_int_equal(n, 2);
}

static void test_marks_and_drops(void **state)
{
    (void)state;
    assert_ok(rp_lmtab_clear(&tab));
    const rp_point3_t p = point(RP_C(0.0), RP_C(0.0), RP_C(1.0));
    for (uint32_t id = 1; id <= 6; ++id) {
        assert_ok(rp_lmtab_insert(&tab, id, (uint8_t)(id % 2), &p, NULL)); /* groups 1,0,1,0,1,0 */
    }
    const uint32_t seen[4] = {1, 2, 3, 99};
    const uint8_t used[4] = {1, 0, 1, 1};
    assert_ok(rp_lmtab_mark_ids(&tab, seen, used, 4)); /* marks 1 and 3; 99 is not held */
    uint16_t dropped = 0;
    assert_ok(rp_lmtab_drop_unmarked(&tab, 1u << 1, &dropped)); /* group 1's unmarked: 5 */
    assert_int_equal(dropped, 1);
    uint16_t s;
    assert_status(rp_lmtab_find(&tab, 5, &s), RP_E_NOT_FOUND);
    assert_ok(rp_lmtab_find(&tab, 2, &s)); /* group 0: kept though unmarked */
    /* the marks were cleared: dropping everything unmarked now drops them all */
    assert_ok(rp_lmtab_drop_unmarked(&tab, 0, &dropped)); /* mask 0: only clears marks */
    assert_int_equal(dropped, 0);
    assert_ok(rp_lmtab_mark_ids(&tab, seen, NULL, 3)); /* NULL used: every id */
    assert_ok(rp_lmtab_drop_unmarked(&tab, RP_IDMAP_ALL_GROUPS, &dropped));
    assert_int_equal(dropped, 2); /* 4 and 6 */
    assert_int_equal(tab.map.n, 3);
}

static void test_refine_moves_only_used_points(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_rig_t rig;
    rp_sim_default_cfg(&cfg);
    rp_sim_make_rig(&cfg, &rig);
    assert_ok(rp_lmtab_clear(&tab));
    const rp_real M_true[3] = {RP_C(0.1), RP_C(-0.05), RP_C(0.8)};
    const rp_real p0[6] = {0};
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p0));
    rp_real uv[2];
    assert_ok(rp_rig_project(&rig, RP_SIM_CAM1, &pl, M_true, uv, NULL, NULL));
    /* two copies of the same wrong point, both seen at the true pixel; only one observation used */
    const rp_point3_t start = point(RP_C(0.12), RP_C(-0.03), RP_C(0.8));
    assert_ok(rp_lmtab_insert(&tab, 1, RP_SIM_CAM1, &start, NULL));
    assert_ok(rp_lmtab_insert(&tab, 2, RP_SIM_CAM1, &start, NULL));
    rp_obs_t o[2];
    memset(o, 0, sizeof(o));
    for (int i = 0; i < 2; ++i) {
        o[i].uv[0] = uv[0];
        o[i].uv[1] = uv[1];
        o[i].cam = RP_SIM_CAM1;
        o[i].w = RP_C(1.0);
    }
    const uint32_t oid[2] = {1, 2};
    const uint8_t used[2] = {1, 0};
    assert_ok(rp_lmtab_refine(&tab, &rig, p0, NULL, NULL, o, oid, used, 2, RP_C(0.5), RP_C(0.0)));
    uint16_t s1, s2;
    assert_ok(rp_lmtab_find(&tab, 1, &s1));
    assert_ok(rp_lmtab_find(&tab, 2, &s2));
    const double e0 = hypot((double)(start.M[0] - M_true[0]), (double)(start.M[1] - M_true[1]));
    const double e1 = hypot((double)(tab.pt[s1].M[0] - M_true[0]),
                            (double)(tab.pt[s1].M[1] - M_true[1]));
    assert_true(e1 < 0.5 * e0);                                  /* pulled onto the ray */
    assert_memory_equal(&tab.pt[s2], &start, sizeof(start));     /* not used: unchanged */
    const rp_real bad[6] = {(rp_real)NAN, 0, 0, 0, 0, 0};
    assert_true(rp_lmtab_refine(&tab, &rig, bad, NULL, NULL, o, oid, NULL, 2, RP_C(0.5), RP_C(0.0)) !=
                RP_OK);
}

static void test_bad_input_is_refused(void **state)
{
    (void)state;
    const rp_point3_t p = point(RP_C(0.0), RP_C(0.0), RP_C(1.0));
    uint16_t s;
    uint32_t n;
    const uint8_t cam_bad = RP_MAX_CAMS;
    assert_status(rp_lmtab_clear(NULL), RP_E_ARG);
    assert_status(rp_lmtab_insert(NULL, 1, 0, &p, &s), RP_E_ARG);
    assert_status(rp_lmtab_insert(&tab, 1, 0, NULL, &s), RP_E_ARG);
    assert_status(rp_lmtab_insert(&tab, RP_IDMAP_EMPTY, 0, &p, &s), RP_E_ARG);
    assert_status(rp_lmtab_find(NULL, 1, &s), RP_E_ARG);
    assert_status(rp_lmtab_slot(&tab, RP_IDMAP_MAX_SLOTS, NULL, NULL, NULL), RP_E_ARG);
    assert_status(rp_lmtab_gather(&tab, NULL, &cam_bad, 1, 0, obs, ids, 1, &n), RP_E_ARG);
    assert_status(rp_lmtab_gather(&tab, &fs, &cam_bad, 1, 0, obs, ids, 1, &n), RP_E_ARG);
    assert_status(rp_lmtab_mark_ids(&tab, NULL, NULL, 1), RP_E_ARG);
    assert_status(rp_lmtab_drop_unmarked(NULL, 0, NULL), RP_E_ARG);
    assert_status(rp_lmtab_refine(&tab, NULL, NULL, NULL, NULL, obs, ids, NULL, 0, RP_C(0.5), RP_C(0.0)),
                  RP_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_insert_find_and_slot),
        cmocka_unit_test(test_gather_follows_camera_order_and_groups),
        cmocka_unit_test(test_marks_and_drops),
        cmocka_unit_test(test_refine_moves_only_used_points),
        cmocka_unit_test(test_bad_input_is_refused),
    };
    return cmocka_run_group_tests_name("lmtab", tests, NULL, NULL);
}
