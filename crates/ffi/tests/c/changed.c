/*
 * A C host whose model's store changes on disk while the model is open,
 * run by crates/ffi/tests/changed.rs:
 *
 *     changed MODEL STORE SCRATCH_DIR
 *
 * The host installs a SIGBUS handler of its own first (it leaves by
 * siglongjmp). Then: the store truncated and rewritten shorter between
 * open and reconstruct, rewritten at the same size, and truncated while
 * threads reconstruct in a loop. Every call must give OK with the right
 * table or BAD_FILE naming the store, the process must keep running, and
 * the host's handler must still get the faults of the host's own maps
 * (and only those). Prints "all checks passed" and exits 0, or lists each
 * failure and exits 1.
 */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <setjmp.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "brdf_atlas.h"

static int failures = 0;

#define CHECK(cond, ...)                                                       \
    do {                                                                       \
        if (!(cond)) {                                                         \
            failures++;                                                        \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);               \
            fprintf(stderr, __VA_ARGS__);                                      \
            fputc('\n', stderr);                                               \
        }                                                                      \
    } while (0)

static const char *store_path = NULL;

/* The call failed with BAD_FILE, and its message names the store and the change. */
static void expect_changed(BrdfAtlasStatus s, const char *what) {
    const char *m = brdf_atlas_last_error_message();
    CHECK(s == BRDF_ATLAS_STATUS_BAD_FILE, "%s -> %d (%s), want BAD_FILE; message: %s", what,
          (int)s, brdf_atlas_status_message(s), m);
    CHECK(strstr(m, store_path) != NULL, "%s: message lacks the store's path: %s", what, m);
    CHECK(strstr(m, "changed on disk while open") != NULL, "%s: message: %s", what, m);
    CHECK(strchr(m, '\n') == NULL, "%s: message of more than one line", what);
}

/* ---- the host's own SIGBUS handler ---- */

static sigjmp_buf host_jump;
static volatile sig_atomic_t host_faults = 0;

static void host_handler(int sig, siginfo_t *info, void *context) {
    (void)sig;
    (void)info;
    (void)context;
    host_faults++;
    siglongjmp(host_jump, 1);
}

static void install_host_handler(void) {
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_sigaction = host_handler;
    action.sa_flags = SA_SIGINFO;
    sigemptyset(&action.sa_mask);
    if (sigaction(SIGBUS, &action, NULL) != 0) {
        perror("sigaction");
        exit(2);
    }
}

/* Map a file of the host's, truncate it, touch it: the host's handler must
 * be called (once) and jump back here. */
static void host_fault(const char *dir) {
    char path[4096];
    long page = sysconf(_SC_PAGESIZE);
    int fd, before = host_faults;
    volatile unsigned char *p;

    snprintf(path, sizeof path, "%s/host-own.bin", dir);
    fd = open(path, O_RDWR | O_CREAT | O_TRUNC, 0600);
    if (fd < 0 || ftruncate(fd, 4 * page) != 0) {
        perror(path);
        exit(2);
    }
    p = mmap(NULL, 4 * page, PROT_READ, MAP_SHARED, fd, 0);
    if (p == MAP_FAILED) {
        perror("mmap");
        exit(2);
    }
    CHECK(p[3 * page] == 0, "a fresh page reads 0");
    if (ftruncate(fd, 0) != 0) {
        perror("ftruncate");
        exit(2);
    }
    if (sigsetjmp(host_jump, 1) == 0) {
        unsigned char v = p[3 * page];
        CHECK(0, "touching the host's truncated map did not fault (read %u)", v);
    }
    CHECK(host_faults == before + 1, "the host's handler ran %d times, want %d",
          (int)host_faults, before + 1);
    munmap((void *)p, 4 * page);
    close(fd);
}

/* ---- files ---- */

static unsigned char *slurp(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    unsigned char *data;
    long n;
    if (f == NULL || fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0) {
        perror(path);
        exit(2);
    }
    rewind(f);
    data = malloc((size_t)n + 1);
    if (data == NULL || fread(data, 1, (size_t)n, f) != (size_t)n) {
        perror(path);
        exit(2);
    }
    fclose(f);
    *len = (size_t)n;
    return data;
}

/* Rewrite `path` in place, as `cp` or `head -c N > path` does: the same
 * inode truncated, then `len` bytes written. */
static void rewrite(const char *path, const unsigned char *data, size_t len) {
    FILE *f = fopen(path, "wb");
    if (f == NULL || fwrite(data, 1, len, f) != len || fclose(f) != 0) {
        perror(path);
        exit(2);
    }
}

/* Date `path` an hour back, so that the next write moves its mtime
 * whatever the file system's timestamp granularity. */
static void backdate(const char *path) {
    struct timespec times[2];
    clock_gettime(CLOCK_REALTIME, &times[0]);
    times[0].tv_sec -= 3600;
    times[1] = times[0];
    if (utimensat(AT_FDCWD, path, times, 0) != 0) {
        perror("utimensat");
        exit(2);
    }
}

static BrdfAtlasModel *open_model(const char *path) {
    BrdfAtlasModel *m = NULL;
    BrdfAtlasStatus s = brdf_atlas_model_open(path, &m);
    if (s != BRDF_ATLAS_STATUS_OK) {
        fprintf(stderr, "open %s: %s\n", path, brdf_atlas_last_error_message());
        exit(2);
    }
    return m;
}

/* ---- reconstructions on threads while the store is truncated ---- */

#define THREADS 3
static BrdfAtlasModel *shared = NULL;
static const double *reference = NULL;
static size_t table_len = 0;
static atomic_int started = 0;
static atomic_int truncated = 0;

struct outcome {
    int ok, changed, garbage, other, ok_after;
};

static void *work(void *arg) {
    struct outcome *o = arg;
    double *t = malloc(table_len * sizeof *t);
    int counted = 0;
    for (;;) {
        int after = atomic_load(&truncated);
        BrdfAtlasStatus s = brdf_atlas_model_reconstruct(shared, 0.3, -0.2, t, table_len, NULL);
        if (s == BRDF_ATLAS_STATUS_OK) {
            o->ok++;
            o->ok_after += after;
            if (memcmp(t, reference, table_len * sizeof *t) != 0) {
                o->garbage++;
            }
        } else if (s == BRDF_ATLAS_STATUS_BAD_FILE &&
                   strstr(brdf_atlas_last_error_message(), "changed on disk while open")) {
            o->changed++;
            break;
        } else {
            o->other++;
            break;
        }
        if (!counted) {
            atomic_fetch_add(&started, 1);
            counted = 1;
        }
    }
    free(t);
    return NULL;
}

int main(int argc, char **argv) {
    const char *model_path, *dir;
    unsigned char *original, *changed;
    size_t store_len, i;
    double *first, *t, rgb[3] = {7, 7, 7}, w[64];
    const double wi[3] = {0, 0, 1}, wo[3] = {0.3, 0, 1};
    float map[4 * 4 * 3];
    BrdfAtlasModel *m;
    pthread_t threads[THREADS];
    struct outcome outcomes[THREADS];

    if (argc != 4) {
        fprintf(stderr, "usage: %s MODEL STORE SCRATCH_DIR\n", argv[0]);
        return 2;
    }
    model_path = argv[1];
    store_path = argv[2];
    dir = argv[3];
    original = slurp(store_path, &store_len);

    install_host_handler();
    host_fault(dir);

    /* 1. Truncated and rewritten shorter between open and reconstruct. */
    m = open_model(model_path);
    brdf_atlas_model_table_len(m, &table_len);
    first = malloc(table_len * sizeof *first);
    t = malloc(table_len * sizeof *t);
    CHECK(brdf_atlas_model_reconstruct(m, 0.3, -0.2, first, table_len, NULL) ==
              BRDF_ATLAS_STATUS_OK,
          "first reconstruct: %s", brdf_atlas_last_error_message());
    rewrite(store_path, original, store_len / 3);
    for (i = 0; i < table_len; i++) {
        t[i] = -7.0;
    }
    expect_changed(brdf_atlas_model_reconstruct(m, 0.3, -0.2, t, table_len, NULL),
                   "reconstruct after truncation");
    CHECK(t[0] == -7.0 && t[table_len - 1] == -7.0, "a failed reconstruct wrote the buffer");
    /* The handle refuses every later call, cleanly. */
    expect_changed(brdf_atlas_model_reconstruct(m, 0.3, -0.2, t, table_len, NULL),
                   "second reconstruct");
    expect_changed(brdf_atlas_model_eval(m, 0.3, -0.2, wi, wo, rgb), "eval");
    CHECK(rgb[0] == 7, "a failed eval wrote rgb");
    expect_changed(brdf_atlas_model_weights(m, 0.3, -0.2, w, 64), "weights");
    expect_changed(brdf_atlas_model_albedo_map(m, 4, 4, NULL, 4, map, 4 * 4 * 3), "albedo map");
    /* The host's own faults still reach the host's handler. */
    host_fault(dir);
    brdf_atlas_model_free(m);

    /* 2. The same size, other bytes, rewritten in place. */
    rewrite(store_path, original, store_len);
    backdate(store_path);
    m = open_model(model_path);
    CHECK(brdf_atlas_model_reconstruct(m, 0.3, -0.2, t, table_len, NULL) ==
                  BRDF_ATLAS_STATUS_OK &&
              memcmp(t, first, table_len * sizeof *t) == 0,
          "reopened: %s", brdf_atlas_last_error_message());
    changed = malloc(store_len);
    memcpy(changed, original, store_len);
    changed[store_len - 1] ^= 0x40;
    rewrite(store_path, changed, store_len);
    expect_changed(brdf_atlas_model_reconstruct(m, 0.3, -0.2, t, table_len, NULL),
                   "reconstruct after a same-size rewrite");
    expect_changed(brdf_atlas_model_eval(m, 0.3, -0.2, wi, wo, rgb), "eval after rewrite");
    brdf_atlas_model_free(m);

    /* 3. Truncated while threads reconstruct in a loop. */
    rewrite(store_path, original, store_len);
    shared = open_model(model_path);
    reference = first;
    memset(outcomes, 0, sizeof outcomes);
    for (i = 0; i < THREADS; i++) {
        pthread_create(&threads[i], NULL, work, &outcomes[i]);
    }
    while (atomic_load(&started) < THREADS) {
        sched_yield();
    }
    rewrite(store_path, original, 4096);
    atomic_store(&truncated, 1);
    for (i = 0; i < THREADS; i++) {
        pthread_join(threads[i], NULL);
        CHECK(outcomes[i].garbage == 0, "thread %zu: %d tables differ from the reference", i,
              outcomes[i].garbage);
        CHECK(outcomes[i].changed == 1 && outcomes[i].other == 0,
              "thread %zu ended on %d BAD_FILE, %d other errors: %s", i, outcomes[i].changed,
              outcomes[i].other, brdf_atlas_last_error_message());
        CHECK(outcomes[i].ok >= 1 && outcomes[i].ok_after == 0,
              "thread %zu: %d successes, %d after the truncation", i, outcomes[i].ok,
              outcomes[i].ok_after);
    }
    brdf_atlas_model_free(shared);
    host_fault(dir);

    /* The store restored, the model opens and answers again. */
    rewrite(store_path, original, store_len);
    m = open_model(model_path);
    CHECK(brdf_atlas_model_reconstruct(m, 0.3, -0.2, t, table_len, NULL) ==
                  BRDF_ATLAS_STATUS_OK &&
              memcmp(t, first, table_len * sizeof *t) == 0,
          "restored: %s", brdf_atlas_last_error_message());
    brdf_atlas_model_free(m);
    CHECK(host_faults == 3, "the host's handler ran %d times, want 3", (int)host_faults);

    free(original);
    free(changed);
    free(first);
    free(t);
    if (failures) {
        fprintf(stderr, "%d failures\n", failures);
        return 1;
    }
    printf("all checks passed\n");
    return 0;
}
