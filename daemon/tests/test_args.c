/*
 * test_args.c - the daemon's command line (daemon/rp_args.c):
 *   - the defaults, every option, --help;
 *   - each bad command line refused with a message naming the option and the value;
 *   - the overrides land in the configuration; too long a channel, a --sim-drop camera the rig
 *     does not have are refused; the sim source's run length follows --frames (else 300).
 */
#include <string.h>

#include "rp_args.h"
#include "rp_test.h"

static rp_config_t g_cfg;
static char g_err[1024];

/* Parse a NULL-terminated list of arguments; the messages land in g_err. */
static rp_args_status_t parse(rp_args_t *a, const char *const *argv)
{
    int argc = 0;
    while (argv[argc] != NULL) {
        ++argc;
    }
    memset(g_err, 0, sizeof g_err);
    FILE *err = fmemopen(g_err, sizeof g_err - 1, "w");
    assert_non_null(err);
    const rp_args_status_t st = rp_args_parse(argc, (char **)(uintptr_t)argv, a, err);
    fclose(err);
    return st;
}

static void test_defaults_and_every_option(void **state)
{
    (void)state;
    rp_args_t a;
    const char *const min[] = {"rigpose", "--config", "x.yaml", NULL};
    assert_int_equal(parse(&a, min), RP_ARGS_OK);
    assert_string_equal(a.config, "x.yaml");
    assert_int_equal(a.frames, 0);
    assert_int_equal(a.print_every, 1);
    assert_int_equal(a.drop_cam, -2);
    assert_null(a.lcm_url);
    assert_null(a.stats_json);
    assert_false(a.fast || a.quiet);
    assert_int_equal(a.threads, -1); /* the file's */

    const char *const all[] = {"rigpose", "--frames", "12", "--lcm-url", "memq://",
                               "--pose-channel", "P", "--status-channel", "S",
                               "--image-channel", "I", "--fast", "--sim-drop", "2:40",
                               "--print-every", "5", "--quiet", "--stats-json", "s.json",
                               "--threads", "3", "--config", "c.yaml", NULL};
    assert_int_equal(parse(&a, all), RP_ARGS_OK);
    assert_int_equal(a.frames, 12);
    assert_string_equal(a.lcm_url, "memq://");
    assert_string_equal(a.pose_channel, "P");
    assert_string_equal(a.status_channel, "S");
    assert_string_equal(a.image_channel, "I");
    assert_true(a.fast && a.quiet);
    assert_int_equal(a.drop_cam, 2);
    assert_int_equal(a.drop_from, 40);
    assert_int_equal(a.print_every, 5);
    assert_string_equal(a.stats_json, "s.json");
    assert_int_equal(a.threads, 3);
    assert_string_equal(a.config, "c.yaml");
    assert_string_equal(g_err, "");

    const char *const help[] = {"rigpose", "--frames", "1", "-h", NULL};
    assert_int_equal(parse(&a, help), RP_ARGS_HELP);
}

static void test_bad_command_lines_name_the_option(void **state)
{
    (void)state;
    static const struct { const char *argv[6]; const char *msg; } cases[] = {
        {{"rigpose", NULL}, "--config FILE is required"},
        {{"rigpose", "--frames", "1", NULL}, "--config FILE is required"},
        {{"rigpose", "--config", NULL}, "--config: unknown option or missing value"},
        {{"rigpose", "--config", "c", "--frames", "-1", NULL}, "--frames: '-1' is not a count"},
        {{"rigpose", "--config", "c", "--frames", "3x", NULL}, "--frames: '3x' is not a count"},
        {{"rigpose", "--config", "c", "--frames", "4294967296", NULL},
         "--frames: '4294967296' is not a count"},
        {{"rigpose", "--config", "c", "--print-every", "0", NULL},
         "--print-every: '0' is not a positive count"},
        {{"rigpose", "--config", "c", "--sim-drop", "6:1", NULL}, "--sim-drop: '6:1' is not"},
        {{"rigpose", "--config", "c", "--sim-drop", "1:2:3", NULL}, "--sim-drop: '1:2:3'"},
        {{"rigpose", "--config", "c", "--sim-drop", "1", NULL}, "--sim-drop: '1'"},
        {{"rigpose", "--config", "c", "--bogus", "1", NULL}, "--bogus: unknown option"},
        {{"rigpose", "--config", "c", "--threads", "17", NULL}, "--threads: '17' is not a count"},
        {{"rigpose", "--config", "c", "--threads", "-1", NULL}, "--threads: '-1' is not a count"},
        /* echoed words cannot move the terminal: control characters written \xNN */
        {{"rigpose", "--config", "c", "--frames", "1\033[2J\n", NULL},
         "--frames: '1\\x1b[2J\\x0a' is not a count"},
        {{"rigpose", "--config", "c", "--\033]0;x\007", "1", NULL},
         "--\\x1b]0;x\\x07: unknown option"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        rp_args_t a;
        assert_int_equal(parse(&a, cases[i].argv), RP_ARGS_E_USAGE);
        if (strstr(g_err, cases[i].msg) == NULL) {
            fail_msg("case %zu: wanted '%s' in '%s'", i, cases[i].msg, g_err);
        }
    }
    rp_args_t a;
    assert_int_equal(rp_args_parse(1, NULL, &a, stderr), RP_ARGS_E_USAGE);
    assert_int_equal(rp_args_parse(0, NULL, NULL, stderr), RP_ARGS_E_USAGE);
}

static rp_args_status_t apply(const rp_args_t *a)
{
    memset(g_err, 0, sizeof g_err);
    FILE *err = fmemopen(g_err, sizeof g_err - 1, "w");
    assert_non_null(err);
    const rp_args_status_t st = rp_args_apply(a, &g_cfg, err);
    fclose(err);
    return st;
}

static void load_default(void)
{
    char err[RP_CFG_ERR_MAX];
    if (rp_config_load("config/sim.yaml", &g_cfg, err, sizeof err) != RP_CFG_OK) {
        fail_msg("%s", err);
    }
}

static void test_overrides_land_in_the_configuration(void **state)
{
    (void)state;
    rp_args_t a;
    const char *const all[] = {"rigpose", "--config", "config/sim.yaml", "--lcm-url", "memq://",
                               "--pose-channel", "P", "--status-channel", "S", "--image-channel",
                               "I", "--fast", "--sim-drop", "5:7", "--frames", "40", "--threads",
                               "2", NULL};
    assert_int_equal(parse(&a, all), RP_ARGS_OK);
    load_default();
    g_cfg.hal.realtime = 1;
    g_cfg.hal.sim_frames = 0;
    assert_int_equal(apply(&a), RP_ARGS_OK);
    assert_string_equal(g_cfg.lcm_url, "memq://");
    assert_string_equal(g_cfg.pose_channel, "P");
    assert_string_equal(g_cfg.status_channel, "S");
    assert_string_equal(g_cfg.image_channel, "I");
    assert_int_equal(g_cfg.hal.realtime, 0);
    assert_int_equal(g_cfg.sim.drop_cam, 5);
    assert_int_equal(g_cfg.sim.drop_from, 7);
    assert_int_equal(g_cfg.hal.sim_frames, 40);
    assert_int_equal(g_cfg.threads, 2);

    /* The file's run length stays; with neither, 300. */
    const char *const min[] = {"rigpose", "--config", "config/sim.yaml", NULL};
    assert_int_equal(parse(&a, min), RP_ARGS_OK);
    load_default();
    const char *pose = "RIGPOSE_POSE";
    assert_string_equal(g_cfg.pose_channel, pose);
    g_cfg.hal.sim_frames = 0;
    assert_int_equal(apply(&a), RP_ARGS_OK);
    assert_int_equal(g_cfg.hal.sim_frames, 300);
    assert_string_equal(g_cfg.pose_channel, pose);
    g_cfg.hal.sim_frames = 77;
    assert_int_equal(apply(&a), RP_ARGS_OK);
    assert_int_equal(g_cfg.hal.sim_frames, 77);
}

static void test_overrides_that_do_not_fit_are_refused(void **state)
{
    (void)state;
    static char long_name[RP_CFG_CHANNEL_MAX + 1];
    memset(long_name, 'x', RP_CFG_CHANNEL_MAX);
    rp_args_t a;
    const char *const too_long[] = {"rigpose", "--config", "c", "--pose-channel", long_name, NULL};
    assert_int_equal(parse(&a, too_long), RP_ARGS_OK);
    load_default();
    assert_int_equal(apply(&a), RP_ARGS_E_USAGE);
    assert_non_null(strstr(g_err, "--pose-channel: 1..63 characters"));

    const char *const empty[] = {"rigpose", "--config", "c", "--lcm-url", "", NULL};
    assert_int_equal(parse(&a, empty), RP_ARGS_OK);
    assert_int_equal(apply(&a), RP_ARGS_E_USAGE);
    assert_non_null(strstr(g_err, "--lcm-url: 1.."));

    const char *const drop[] = {"rigpose", "--config", "c", "--sim-drop", "5:1", NULL};
    assert_int_equal(parse(&a, drop), RP_ARGS_OK);
    load_default();
    g_cfg.rig.n_cams = 4;
    assert_int_equal(apply(&a), RP_ARGS_E_USAGE);
    assert_non_null(strstr(g_err, "--sim-drop: the rig has 4 cameras"));
    assert_int_equal(rp_args_apply(NULL, &g_cfg, stderr), RP_ARGS_E_USAGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_and_every_option),
        cmocka_unit_test(test_bad_command_lines_name_the_option),
        cmocka_unit_test(test_overrides_land_in_the_configuration),
        cmocka_unit_test(test_overrides_that_do_not_fit_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
