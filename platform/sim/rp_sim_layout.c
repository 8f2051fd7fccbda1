/*
 * rp_sim_layout.c - placements of cam2 and cam4 for the layout study (see rp_sim_layout.h).
 */
#include "rp_sim_layout.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)
#define N_NUMBERS 8
#define MAX_OFFSET_M 10.0

rp_sim_layout_t rp_sim_layout_paper(void)
{
    rp_sim_layout_t l;
    memset(&l, 0, sizeof l);
    strcpy(l.name, "paper");
    l.cam2 = rp_sim_paper_place(1);
    l.cam4 = rp_sim_paper_place(0);
    l.is_paper = 1;
    return l;
}

static int near_place(const rp_sim_place_t *a, const rp_sim_place_t *b)
{
    for (int i = 0; i < 3; ++i) {
        if (fabs(a->D[i] - b->D[i]) > 1e-4) {
            return 0;
        }
    }
    return fabs(remainder(a->yaw - b->yaw, 360.0 * DEG)) <= 0.01 * DEG;
}

/* Snap a placement close to the paper's onto it exactly. */
static void snap_to_paper(rp_sim_layout_t *l)
{
    const rp_sim_layout_t p = rp_sim_layout_paper();
    l->is_paper = near_place(&l->cam2, &p.cam2) && near_place(&l->cam4, &p.cam4);
    if (l->is_paper) {
        l->cam2 = p.cam2;
        l->cam4 = p.cam4;
    }
}

int rp_sim_layout_parse_line(const char *line, rp_sim_layout_t *out, char *err, size_t err_len)
{
    char buf[1024];
    const size_t len = strcspn(line, "#\r\n");
    if (len >= sizeof buf) {
        snprintf(err, err_len, "line longer than %zu characters", sizeof buf - 1);
        return -1;
    }
    memcpy(buf, line, len);
    buf[len] = '\0';

    char *tok[N_NUMBERS + 2];
    int n = 0;
    for (char *p = strtok(buf, " \t"); p; p = strtok(NULL, " \t")) {
        if (n < N_NUMBERS + 2) {
            tok[n] = p;
        }
        ++n;
    }
    if (n == 0) {
        return 0;
    }
    if (n != N_NUMBERS + 1) {
        snprintf(err, err_len,
                 "expected a name and 8 numbers (cam2 x y z yaw, cam4 x y z yaw), got %d field%s",
                 n, n == 1 ? "" : "s");
        return -1;
    }
    if (strlen(tok[0]) >= RP_SIM_LAYOUT_NAME) {
        snprintf(err, err_len, "name '%s' longer than %d characters", tok[0],
                 RP_SIM_LAYOUT_NAME - 1);
        return -1;
    }
    double v[N_NUMBERS];
    for (int i = 0; i < N_NUMBERS; ++i) {
        char *end;
        errno = 0;
        v[i] = strtod(tok[i + 1], &end);
        if (errno || *end || end == tok[i + 1] || !isfinite(v[i])) {
            snprintf(err, err_len, "'%s' is not a finite number", tok[i + 1]);
            return -1;
        }
        const int is_yaw = (i % 4) == 3;
        if (is_yaw ? fabs(v[i]) > 360.0 : fabs(v[i]) > MAX_OFFSET_M) {
            snprintf(err, err_len, "%s %g out of range (|%s| <= %g)", is_yaw ? "yaw" : "offset",
                     v[i], is_yaw ? "yaw" : "offset", is_yaw ? 360.0 : MAX_OFFSET_M);
            return -1;
        }
    }
    memset(out, 0, sizeof *out);
    strcpy(out->name, tok[0]);
    rp_sim_place_t *cam[2] = {&out->cam2, &out->cam4};
    for (int c = 0; c < 2; ++c) {
        for (int i = 0; i < 3; ++i) {
            cam[c]->D[i] = v[4 * c + i];
        }
        cam[c]->yaw = v[4 * c + 3] * DEG;
    }
    snap_to_paper(out);
    return 1;
}

int rp_sim_layout_read(const char *path, rp_sim_layout_t *out, int max, char *err,
                       size_t err_len)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, err_len, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    char line[1100], why[200];
    int n = 0, lineno = 0, rc = 0;
    while (fgets(line, sizeof line, f)) {
        ++lineno;
        const size_t len = strlen(line);
        if (len == sizeof line - 1 && line[len - 1] != '\n' && !feof(f)) {
            snprintf(err, err_len, "%s:%d: line too long", path, lineno);
            rc = -1;
            break;
        }
        rp_sim_layout_t l;
        const int r = rp_sim_layout_parse_line(line, &l, why, sizeof why);
        if (r < 0) {
            snprintf(err, err_len, "%s:%d: %s", path, lineno, why);
            rc = -1;
            break;
        }
        if (r == 0) {
            continue;
        }
        int dup = 0;
        for (int i = 0; i < n; ++i) {
            dup |= strcmp(out[i].name, l.name) == 0;
        }
        if (dup) {
            snprintf(err, err_len, "%s:%d: placement '%s' given twice", path, lineno, l.name);
            rc = -1;
            break;
        }
        if (n == max) {
            snprintf(err, err_len, "%s:%d: more than %d placements", path, lineno, max);
            rc = -1;
            break;
        }
        out[n++] = l;
    }
    if (rc == 0 && ferror(f)) {
        snprintf(err, err_len, "%s: read error", path);
        rc = -1;
    }
    fclose(f);
    if (rc == 0 && n == 0) {
        snprintf(err, err_len, "%s: no placements", path);
        rc = -1;
    }
    return rc < 0 ? -1 : n;
}

int rp_sim_layout_grid(rp_sim_layout_t *out, int max)
{
    const double xs[3] = {0.05 * sqrt(3.0), 0.15, 0.25};
    const double zs[3] = {-0.05, 0.05, -0.15};
    const double yaws[3] = {90.0, 60.0, 120.0};
    int n = 0;
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            for (int c = 0; c < 3 && n < max; ++c) {
                rp_sim_layout_t *l = &out[n++];
                memset(l, 0, sizeof *l);
                snprintf(l->name, sizeof l->name, "x%.3f_z%+.2f_yaw%.0f", xs[a], zs[b], yaws[c]);
                l->cam2.D[0] = xs[a];
                l->cam2.D[2] = zs[b];
                l->cam2.yaw = yaws[c] * DEG;
                l->cam4.D[0] = -xs[a];
                l->cam4.D[2] = zs[b];
                l->cam4.yaw = -yaws[c] * DEG;
                snap_to_paper(l);
                if (l->is_paper) {
                    strcpy(l->name, "paper");
                }
            }
        }
    }
    return n;
}

void rp_sim_layout_apply(const rp_sim_layout_t *l, rp_sim_cfg_t *cfg)
{
    cfg->cam2 = l->cam2;
    cfg->cam4 = l->cam4;
}

/* a before b in the ranking: smaller key, NaN last, ties by index. */
static int ranks_before(const double *key, uint32_t a, uint32_t b)
{
    const int na = isnan(key[a]), nb = isnan(key[b]);
    if (na != nb) {
        return nb;
    }
    if (!na && key[a] != key[b]) {
        return key[a] < key[b];
    }
    return a < b;
}

void rp_sim_layout_rank(const double *key, uint32_t n, uint32_t *order)
{
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t j = i;
        while (j > 0 && ranks_before(key, i, order[j - 1])) {
            order[j] = order[j - 1];
            --j;
        }
        order[j] = i;
    }
}
