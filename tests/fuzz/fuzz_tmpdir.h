/*
 * fuzz_tmpdir.h - a private folder per fuzzing process for the targets that go through files
 * (the replay source reads frames.csv, truth.csv and images by path): made once, removed at exit.
 */
#ifndef FUZZ_TMPDIR_H
#define FUZZ_TMPDIR_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_fuzz_dir[64];

static void fuzz_dir_remove(void)
{
    static const char *const names[] = {"frames.csv", "truth.csv", "a.pgm", "b.png", "img", NULL};
    char p[128];
    for (int i = 0; names[i] != NULL; i++) {
        snprintf(p, sizeof p, "%s/%s", g_fuzz_dir, names[i]);
        unlink(p);
    }
    rmdir(g_fuzz_dir);
}

/* The folder (made on the first call). */
static const char *fuzz_dir(void)
{
    if (g_fuzz_dir[0] == '\0') {
        const char *tmp = getenv("TMPDIR");
        snprintf(g_fuzz_dir, sizeof g_fuzz_dir, "%s/rp_fuzz_XXXXXX",
                 tmp != NULL && strlen(tmp) < 32 ? tmp : "/tmp");
        if (mkdtemp(g_fuzz_dir) == NULL) {
            perror("fuzz: mkdtemp");
            abort();
        }
        atexit(fuzz_dir_remove);
    }
    return g_fuzz_dir;
}

/* Writes n bytes into the folder's file `name`. */
static void fuzz_write(const char *name, const void *data, size_t n)
{
    char p[128];
    snprintf(p, sizeof p, "%s/%s", fuzz_dir(), name);
    FILE *f = fopen(p, "wb");
    if (f == NULL || (n > 0 && fwrite(data, 1, n, f) != n) || fclose(f) != 0) {
        perror("fuzz: write");
        abort();
    }
}

#endif /* FUZZ_TMPDIR_H */
