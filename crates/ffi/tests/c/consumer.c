/*
 * A C consumer of brdf_atlas.h, run by crates/ffi/tests/consumers.rs:
 *
 *     consumer-c EXPECTED.txt
 *
 * EXPECTED.txt holds the model's path, the files for the bad calls, and the
 * Rust library's answers, one "key values... [path]" line each. Every
 * answer must match bit for bit; every bad call must give its documented
 * status and message and leave the outputs untouched. Prints
 * "all checks passed" and exits 0, or lists each failure and exits 1.
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* A call must give `want`; on a failure the message must mention `needle`. */
#define EXPECT(call, want, needle)                                             \
    do {                                                                       \
        BrdfAtlasStatus s_ = (call);                                           \
        const char *m_ = brdf_atlas_last_error_message();                      \
        CHECK(s_ == (want), "%s -> %d (%s), want %d; message: %s", #call,      \
              (int)s_, brdf_atlas_status_message(s_), (int)(want), m_);        \
        if ((want) == BRDF_ATLAS_STATUS_OK) {                                  \
            CHECK(m_[0] == '\0', "%s: message after success: %s", #call, m_);  \
        } else {                                                               \
            CHECK(strstr(m_, (needle)) != NULL, "%s: message %s lacks %s",     \
                  #call, m_, (needle));                                        \
        }                                                                      \
    } while (0)

#define OK BRDF_ATLAS_STATUS_OK

/* ---- expected.txt ---- */

#define MAX_LINES 512
static char *lines[MAX_LINES];
static int line_count = 0;

static unsigned char *slurp(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    unsigned char *data = NULL;
    long n;
    if (f == NULL) {
        fprintf(stderr, "cannot open %s\n", path);
        exit(2);
    }
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    data = malloc((size_t)n + 1);
    if (data == NULL || fread(data, 1, (size_t)n, f) != (size_t)n) {
        fprintf(stderr, "cannot read %s\n", path);
        exit(2);
    }
    data[n] = '\0';
    fclose(f);
    *len = (size_t)n;
    return data;
}

static char *expected_text = NULL;

static void load(const char *path) {
    size_t len;
    char *p;
    expected_text = (char *)slurp(path, &len);
    for (p = strtok(expected_text, "\n"); p != NULL && line_count < MAX_LINES;
         p = strtok(NULL, "\n")) {
        lines[line_count++] = p;
    }
}

/* The rest of the `nth` line whose first word is `key`, or NULL. */
static const char *find(const char *key, int nth) {
    size_t k = strlen(key);
    int i;
    for (i = 0; i < line_count; i++) {
        if (strncmp(lines[i], key, k) == 0 && lines[i][k] == ' ' && nth-- == 0) {
            return lines[i] + k + 1;
        }
    }
    return NULL;
}

static const char *need(const char *key, int nth) {
    const char *r = find(key, nth);
    if (r == NULL) {
        fprintf(stderr, "expected.txt has no line %d for %s\n", nth, key);
        exit(2);
    }
    return r;
}

/* Read a number and advance. */
static double num(const char **p) {
    char *end;
    double v = strtod(*p, &end);
    if (end == *p) {
        fprintf(stderr, "expected a number at: %s\n", *p);
        exit(2);
    }
    *p = end;
    return v;
}

/* What is left of a line: a path or a name. */
static const char *rest(const char *p) {
    while (*p == ' ') {
        p++;
    }
    return p;
}

static int same(double a, double b) {
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

/* ---- the checks ---- */

static BrdfAtlasModel *model = NULL;
static size_t table_len = 0;

static void check_open(void) {
    BrdfAtlasModel *sentinel = (BrdfAtlasModel *)&failures; /* never a real handle */
    BrdfAtlasModel *out = sentinel;
    const char *corrupt = rest(need("corrupt", 0));
    const char *missing = rest(need("missing", 0));
    const char *changed = rest(need("changed", 0));

    EXPECT(brdf_atlas_model_open(corrupt, &out), BRDF_ATLAS_STATUS_BAD_FILE, corrupt);
    CHECK(strstr(brdf_atlas_last_error_message(), "brdf_atlas_model_open: ") ==
              brdf_atlas_last_error_message(),
          "the message names the function: %s", brdf_atlas_last_error_message());
    EXPECT(brdf_atlas_model_open(missing, &out), BRDF_ATLAS_STATUS_IO, missing);
    EXPECT(brdf_atlas_model_open(changed, &out), BRDF_ATLAS_STATUS_BAD_FILE, "checksum");
    EXPECT(brdf_atlas_model_open(NULL, &out), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "path");
    EXPECT(brdf_atlas_model_open("", &out), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "empty");
    EXPECT(brdf_atlas_model_open("bad-\xff\xfe.model", &out),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "UTF-8");
    CHECK(out == sentinel, "a failed open wrote *out");
    EXPECT(brdf_atlas_model_open(rest(need("model", 0)), NULL),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "out");
    EXPECT(brdf_atlas_model_open(rest(need("model", 0)), &model), OK, "");
    CHECK(model != NULL, "open gave no handle");
    brdf_atlas_model_free(NULL);
}

/*
 * The generated corpus of broken files (crates/hostile), one line each:
 * "KEY STATUS<TAB>PATH<TAB>NAME<TAB>WANT". Opening the model (hostile_open)
 * or locating the MERL file (hostile_locate) must give STATUS, a one-line
 * message containing the file name NAME and the words WANT, and leave the
 * out-parameter untouched.
 */
static void check_hostile(const char *key, int locate) {
    const char *line;
    int i;
    for (i = 0; (line = find(key, i)) != NULL; i++) {
        char buf[8192];
        char *end, *path, *name, *want;
        long status;
        BrdfAtlasModel *sentinel = (BrdfAtlasModel *)&failures; /* never a real handle */
        BrdfAtlasModel *out = sentinel;
        BrdfAtlasLocation loc, untouched;
        BrdfAtlasStatus s;
        const char *m;

        snprintf(buf, sizeof buf, "%s", line);
        status = strtol(buf, &end, 10);
        path = strchr(end, '\t');
        name = path ? strchr(path + 1, '\t') : NULL;
        want = name ? strchr(name + 1, '\t') : NULL;
        if (want == NULL) {
            fprintf(stderr, "malformed %s line: %s\n", key, line);
            exit(2);
        }
        *path++ = '\0';
        *name++ = '\0';
        *want++ = '\0';
        memset(&loc, 0x5a, sizeof loc);
        memcpy(&untouched, &loc, sizeof loc);
        s = locate ? brdf_atlas_model_locate(model, path, &loc) : brdf_atlas_model_open(path, &out);
        m = brdf_atlas_last_error_message();
        CHECK((long)s == status, "%s %s -> %d (%s), want %ld; message: %s", key, path, (int)s,
              brdf_atlas_status_message(s), status, m);
        CHECK(strstr(m, name) != NULL, "%s: message lacks the file name %s: %s", path, name, m);
        CHECK(strstr(m, want) != NULL, "%s: message lacks \"%s\": %s", path, want, m);
        CHECK(strchr(m, '\n') == NULL, "%s: message of more than one line: %s", path, m);
        CHECK(out == sentinel, "%s: a failed open wrote *out", path);
        CHECK(memcmp(&loc, &untouched, sizeof loc) == 0, "%s: a failed locate wrote *location",
              path);
    }
    CHECK(i >= 15, "only %d %s lines in expected.txt", i, key);
}

static void check_facts(void) {
    size_t q = 0, n = 0, len = 0, expected_n = (size_t)atoi(need("count", 0));
    const char *p;
    BrdfAtlasDims dims;
    BrdfAtlasView view;
    char name[256];
    double one[3];
    size_t i;

    CHECK(strcmp(brdf_atlas_version(), need("version", 0)) == 0, "version %s",
          brdf_atlas_version());
    CHECK(strcmp(brdf_atlas_version(), BRDF_ATLAS_VERSION) == 0, "header version %s, library %s",
          BRDF_ATLAS_VERSION, brdf_atlas_version());
    EXPECT(brdf_atlas_model_latent_dim(model, &q), OK, "");
    CHECK(q == (size_t)atoi(need("q", 0)), "q = %zu", q);
    EXPECT(brdf_atlas_model_material_count(model, &n), OK, "");
    CHECK(n == expected_n, "count = %zu", n);
    EXPECT(brdf_atlas_model_dims(model, &dims), OK, "");
    p = need("dims", 0);
    CHECK(dims.theta_h == (size_t)num(&p) && dims.theta_d == (size_t)num(&p) &&
              dims.phi_d == (size_t)num(&p),
          "dims %zux%zux%zu", dims.theta_h, dims.theta_d, dims.phi_d);
    EXPECT(brdf_atlas_model_table_len(model, &table_len), OK, "");
    CHECK(table_len == 3 * dims.theta_h * dims.theta_d * dims.phi_d, "table_len %zu",
          table_len);
    EXPECT(brdf_atlas_model_view(model, &view), OK, "");
    p = need("view", 0);
    CHECK(same(view.x0, num(&p)) && same(view.x1, num(&p)) && same(view.y0, num(&p)) &&
              same(view.y1, num(&p)),
          "view %g %g %g %g", view.x0, view.x1, view.y0, view.y1);

    for (i = 0; i < n; i++) {
        char key[32];
        double xy[3] = {7, 7, 7};
        const char *want;
        sprintf(key, "name %zu", i);
        want = rest(need(key, 0));
        EXPECT(brdf_atlas_model_material_name(model, i, NULL, 0, &len), OK, "");
        CHECK(len == strlen(want), "name %zu: length %zu", i, len);
        memset(name, 'x', sizeof name);
        EXPECT(brdf_atlas_model_material_name(model, i, name, len, &len),
               BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
        CHECK(name[0] == 'x', "a too-short name buffer was written");
        EXPECT(brdf_atlas_model_material_name(model, i, name, sizeof name, &len), OK, "");
        CHECK(strcmp(name, want) == 0, "name %zu: %s, want %s", i, name, want);
        sprintf(key, "latent %zu", i);
        p = need(key, 0);
        EXPECT(brdf_atlas_model_latent_point(model, i, xy, 1),
               BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
        CHECK(xy[0] == 7, "a too-short latent buffer was written");
        EXPECT(brdf_atlas_model_latent_point(model, i, xy, 3), OK, "");
        CHECK(same(xy[0], num(&p)) && same(xy[1], num(&p)) && xy[2] == 7,
              "latent %zu: %g %g", i, xy[0], xy[1]);
    }
    EXPECT(brdf_atlas_model_material_name(model, n, name, sizeof name, &len),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "does not exist");
    EXPECT(brdf_atlas_model_material_name(model, 0, NULL, 10, &len),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "buf");
    EXPECT(brdf_atlas_model_material_name(model, 0, name, sizeof name, NULL),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "name_len");
    EXPECT(brdf_atlas_model_latent_point(model, (size_t)-1, one, 3),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "does not exist");
    EXPECT(brdf_atlas_model_latent_point(model, 0, NULL, 3), BRDF_ATLAS_STATUS_NULL_ARGUMENT,
           "buf");

    /* A NULL handle is an error everywhere, never a crash. */
    EXPECT(brdf_atlas_model_latent_dim(NULL, &q), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    EXPECT(brdf_atlas_model_material_count(NULL, &n), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    EXPECT(brdf_atlas_model_dims(NULL, &dims), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    EXPECT(brdf_atlas_model_view(NULL, &view), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    EXPECT(brdf_atlas_model_table_len(NULL, &len), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    EXPECT(brdf_atlas_model_latent_dim(model, NULL), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "q");
    EXPECT(brdf_atlas_model_dims(model, NULL), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "dims");
    EXPECT(brdf_atlas_model_view(model, NULL), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "view");

    CHECK(strcmp(brdf_atlas_status_message(-1), "unknown status") == 0, "status -1");
    CHECK(strcmp(brdf_atlas_status_message(1000), "unknown status") == 0, "status 1000");
    CHECK(strcmp(brdf_atlas_status_message(BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL),
                 "buffer too small") == 0,
          "status message");
}

/* The table file's data: its bytes after the 12-byte header. */
static int table_matches(const double *table, const char *path) {
    size_t len;
    unsigned char *file = slurp(path, &len);
    int ok = len == 12 + table_len * sizeof(double) &&
             memcmp(file + 12, table, table_len * sizeof(double)) == 0;
    free(file);
    return ok;
}

static void check_reconstruct(void) {
    double *table = malloc(table_len * sizeof(double));
    size_t written = 0, k;
    const char *p = need("point", 0);
    double x = num(&p), y = num(&p);
    const char *expected_file = rest(p);
    char out_path[4096];
    size_t a, b;
    unsigned char *got, *want;

    EXPECT(brdf_atlas_model_reconstruct(model, x, y, table, table_len, &written), OK, "");
    CHECK(written == table_len, "written %zu", written);
    CHECK(table_matches(table, expected_file), "the table at (%g, %g) differs from Rust's", x,
          y);
    EXPECT(brdf_atlas_model_reconstruct(model, x, y, table, table_len, NULL), OK, "");

    /* Too short, NULL, NaN, infinite: errors, and the buffer untouched. */
    for (k = 0; k < table_len; k++) {
        table[k] = 12345.0;
    }
    EXPECT(brdf_atlas_model_reconstruct(model, x, y, table, table_len - 1, &written),
           BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
    EXPECT(brdf_atlas_model_reconstruct(model, NAN, y, table, table_len, &written),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT(brdf_atlas_model_reconstruct(model, x, INFINITY, table, table_len, &written),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT(brdf_atlas_model_reconstruct(model, x, -INFINITY, table, table_len, &written),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT(brdf_atlas_model_reconstruct(NULL, x, y, table, table_len, &written),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    for (k = 0; k < table_len; k++) {
        CHECK(table[k] == 12345.0, "a failed call wrote table[%zu]", k);
        if (table[k] != 12345.0) {
            break;
        }
    }
    EXPECT(brdf_atlas_model_reconstruct(model, x, y, NULL, table_len, &written),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "buf");
    EXPECT(brdf_atlas_model_reconstruct(model, x, y, table, 0, &written),
           BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
    EXPECT(brdf_atlas_model_table_len(model, NULL), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "len");

    /* Far outside the box: answered, and the same as Rust's. */
    p = need("far", 0);
    x = num(&p);
    y = num(&p);
    EXPECT(brdf_atlas_model_reconstruct(model, x, y, table, table_len, NULL), OK, "");
    CHECK(table_matches(table, rest(p)), "the table at (%g, %g) differs from Rust's", x, y);
    EXPECT(brdf_atlas_model_reconstruct(model, -1e308, 1e308, table, table_len, NULL), OK, "");

    /* To a file: the same bytes as the Rust library's file. */
    p = need("point", 0);
    x = num(&p);
    y = num(&p);
    sprintf(out_path, "%s/c.binary", rest(need("out_dir", 0)));
    EXPECT(brdf_atlas_model_reconstruct_to_file(model, x, y, out_path), OK, "");
    got = slurp(out_path, &a);
    want = slurp(rest(p), &b);
    CHECK(a == b && memcmp(got, want, a) == 0, "%s differs from %s", out_path, rest(p));
    free(got);
    free(want);
    sprintf(out_path, "%s/no/such/dir/c.binary", rest(need("out_dir", 0)));
    EXPECT(brdf_atlas_model_reconstruct_to_file(model, x, y, out_path), BRDF_ATLAS_STATUS_IO,
           "no/such/dir");
    EXPECT(brdf_atlas_model_reconstruct_to_file(model, x, y, NULL),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "path");
    EXPECT(brdf_atlas_model_reconstruct_to_file(model, NAN, y, out_path),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    free(table);
}

static void check_eval_and_weights(void) {
    const char *p = need("point", 0);
    double x = num(&p), y = num(&p);
    double wi[3 * 16], wo[3 * 16], want[3 * 16], rgb[3 * 16], w[64];
    size_t n = 0, i, c, count = (size_t)atoi(need("count", 0));

    while ((p = find("pair", (int)n)) != NULL && n < 16) {
        for (c = 0; c < 3; c++) wi[3 * n + c] = num(&p);
        for (c = 0; c < 3; c++) wo[3 * n + c] = num(&p);
        for (c = 0; c < 3; c++) want[3 * n + c] = num(&p);
        n++;
    }
    CHECK(n == 8, "%zu pairs in expected.txt", n);
    for (i = 0; i < n; i++) {
        EXPECT(brdf_atlas_model_eval(model, x, y, wi + 3 * i, wo + 3 * i, rgb), OK, "");
        for (c = 0; c < 3; c++) {
            CHECK(same(rgb[c], want[3 * i + c]), "pair %zu channel %zu: %.17g, want %.17g", i,
                  c, rgb[c], want[3 * i + c]);
        }
    }
    for (i = 0; i < 3 * n; i++) rgb[i] = -7;
    EXPECT(brdf_atlas_model_eval_batch(model, x, y, wi, wo, n, rgb, 3 * n - 1),
           BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "rgb");
    CHECK(rgb[0] == -7, "a too-short batch buffer was written");
    EXPECT(brdf_atlas_model_eval_batch(model, x, y, wi, wo, n, rgb, 3 * n), OK, "");
    for (i = 0; i < 3 * n; i++) {
        CHECK(same(rgb[i], want[i]), "batch value %zu: %.17g, want %.17g", i, rgb[i], want[i]);
    }
    EXPECT(brdf_atlas_model_eval_batch(model, x, y, NULL, NULL, 0, NULL, 0), OK, "");
    EXPECT(brdf_atlas_model_eval_batch(model, x, y, wi, wo, SIZE_MAX, rgb, 3 * n),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "overflows");
    EXPECT(brdf_atlas_model_eval_batch(model, x, y, NULL, wo, n, rgb, 3 * n),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "wi");
    EXPECT(brdf_atlas_model_eval_batch(model, NAN, y, wi, wo, n, rgb, 3 * n),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT(brdf_atlas_model_eval(model, x, y, NULL, wo, rgb), BRDF_ATLAS_STATUS_NULL_ARGUMENT,
           "wi");
    EXPECT(brdf_atlas_model_eval(model, x, y, wi, wo, NULL), BRDF_ATLAS_STATUS_NULL_ARGUMENT,
           "rgb");
    EXPECT(brdf_atlas_model_eval(NULL, x, y, wi, wo, rgb), BRDF_ATLAS_STATUS_NULL_ARGUMENT,
           "model");
    EXPECT(brdf_atlas_model_eval(model, x, NAN, wi, wo, rgb),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");

    p = need("weights", 0);
    w[count - 1] = -7;
    EXPECT(brdf_atlas_model_weights(model, x, y, w, count - 1),
           BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
    CHECK(w[count - 1] == -7, "a too-short weights buffer was written");
    EXPECT(brdf_atlas_model_weights(model, x, y, w, 64), OK, "");
    for (i = 0; i < count; i++) {
        double v = num(&p);
        CHECK(same(w[i], v), "weight %zu: %.17g, want %.17g", i, w[i], v);
    }
    EXPECT(brdf_atlas_model_weights(model, x, y, NULL, 64), BRDF_ATLAS_STATUS_NULL_ARGUMENT,
           "buf");
    EXPECT(brdf_atlas_model_weights(model, INFINITY, y, w, 64),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT(brdf_atlas_model_weights(model, 1e9, -1e9, w, 64), OK, "");
    CHECK(w[0] == 0, "weights far away: %g", w[0]);
}

static void check_map(void) {
    const char *p = need("map", 0);
    size_t width = (size_t)num(&p), height = (size_t)num(&p), samples = (size_t)num(&p);
    size_t len = width * height * 3, flen;
    float *map = malloc(len * sizeof(float));
    unsigned char *want = slurp(rest(p), &flen);
    BrdfAtlasView view, bad;

    CHECK(flen == len * sizeof(float), "map file of %zu bytes", flen);
    /* NULL view and 0 samples: the defaults. */
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, NULL, samples, map, len), OK, "");
    CHECK(memcmp(map, want, flen) == 0, "the default map differs from Rust's");
    /* The same, spelled out. */
    EXPECT(brdf_atlas_model_view(model, &view), OK, "");
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, &view, 256, map, len), OK, "");
    CHECK(memcmp(map, want, flen) == 0, "the map with the default view differs from Rust's");
    free(want);

    map[0] = -7;
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, NULL, 0, map, len - 1),
           BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
    EXPECT(brdf_atlas_model_albedo_map(model, 0, height, NULL, 0, map, len),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "map size");
    EXPECT(brdf_atlas_model_albedo_map(model, SIZE_MAX, SIZE_MAX, NULL, 0, map, len),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "map size");
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, NULL, (size_t)BRDF_ATLAS_MAX_SAMPLES + 1,
                                       map, len),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "samples");
    bad = view;
    bad.x0 = bad.x1;
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, &bad, 0, map, len),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "view");
    bad = view;
    bad.y1 = NAN;
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, &bad, 0, map, len),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "view");
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, NULL, 0, NULL, len),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "buf");
    EXPECT(brdf_atlas_model_albedo_map(NULL, width, height, NULL, 0, map, len),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
    CHECK(map[0] == -7, "a failed map call wrote the buffer");
    free(map);

    /* Another window and sample count. */
    p = need("map_view", 0);
    width = (size_t)num(&p);
    height = (size_t)num(&p);
    samples = (size_t)num(&p);
    view.x0 = num(&p);
    view.x1 = num(&p);
    view.y0 = num(&p);
    view.y1 = num(&p);
    len = width * height * 3;
    map = malloc(len * sizeof(float));
    want = slurp(rest(p), &flen);
    EXPECT(brdf_atlas_model_albedo_map(model, width, height, &view, samples, map, len), OK, "");
    CHECK(flen == len * sizeof(float) && memcmp(map, want, flen) == 0,
          "the map of another window differs from Rust's");
    free(want);
    free(map);
}

static void check_locate(void) {
    const char *p = need("locate", 0);
    size_t nearest = (size_t)num(&p);
    BrdfAtlasLocation got, untouched;
    char missing[4096];

    EXPECT(brdf_atlas_model_locate(model, rest(need("probe", 0)), &got), OK, "");
    CHECK(got.nearest == nearest, "nearest %zu, want %zu", got.nearest, nearest);
    CHECK(same(got.x, num(&p)) && same(got.y, num(&p)) && same(got.rmse, num(&p)) &&
              same(got.spread, num(&p)),
          "located at (%.17g, %.17g) rmse %.17g spread %.17g", got.x, got.y, got.rmse,
          got.spread);
    memset(&untouched, 0, sizeof untouched);
    untouched.x = 42;
    got = untouched;
    sprintf(missing, "%s/missing.binary", rest(need("out_dir", 0)));
    EXPECT(brdf_atlas_model_locate(model, missing, &got), BRDF_ATLAS_STATUS_IO,
           "missing.binary");
    EXPECT(brdf_atlas_model_locate(model, rest(need("bad_merl", 0)), &got),
           BRDF_ATLAS_STATUS_BAD_MERL, "bad.binary");
    EXPECT(brdf_atlas_model_locate(model, rest(need("wrong_dims", 0)), &got),
           BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "8x8x16");
    EXPECT(brdf_atlas_model_locate(model, NULL, &got), BRDF_ATLAS_STATUS_NULL_ARGUMENT,
           "merl_path");
    EXPECT(brdf_atlas_model_locate(model, rest(need("probe", 0)), NULL),
           BRDF_ATLAS_STATUS_NULL_ARGUMENT, "location");
    CHECK(got.x == 42, "a failed locate wrote its output");
}

/* ---- threads: one handle, concurrent reconstructions ---- */

#define THREADS 4
#define POINTS 4
#define ROUNDS 3

struct job {
    int index;
    double xy[POINTS][2];
    double *tables[POINTS]; /* the serial results */
    int mismatches;
    int message_ok;
};

static void *work(void *arg) {
    struct job *job = arg;
    double *table = malloc(table_len * sizeof(double));
    BrdfAtlasModel *none = NULL;
    int round, k;
    char needle[64];
    for (round = 0; round < ROUNDS; round++) {
        for (k = 0; k < POINTS; k++) {
            int j = (k + job->index) % POINTS; /* threads start at different points */
            if (brdf_atlas_model_reconstruct(model, job->xy[j][0], job->xy[j][1], table,
                                             table_len, NULL) != OK ||
                memcmp(table, job->tables[j], table_len * sizeof(double)) != 0) {
                job->mismatches++;
            }
        }
    }
    /* Each thread has its own last error. */
    sprintf(needle, "thread-%d.model", job->index);
    brdf_atlas_model_open(needle, &none);
    job->message_ok = none == NULL && strstr(brdf_atlas_last_error_message(), needle) != NULL;
    free(table);
    return NULL;
}

static void check_threads(void) {
    struct job jobs[THREADS];
    pthread_t threads[THREADS];
    double *tables[POINTS];
    double xy[POINTS][2];
    int t, k;

    for (k = 0; k < POINTS; k++) {
        const char *p = need("point", k);
        xy[k][0] = num(&p);
        xy[k][1] = num(&p);
        tables[k] = malloc(table_len * sizeof(double));
        EXPECT(brdf_atlas_model_reconstruct(model, xy[k][0], xy[k][1], tables[k], table_len,
                                            NULL),
               OK, "");
        CHECK(table_matches(tables[k], rest(p)), "point %d differs from Rust's", k);
    }
    for (t = 0; t < THREADS; t++) {
        jobs[t].index = t;
        memcpy(jobs[t].xy, xy, sizeof xy);
        memcpy(jobs[t].tables, tables, sizeof tables);
        jobs[t].mismatches = 0;
        jobs[t].message_ok = 0;
        CHECK(pthread_create(&threads[t], NULL, work, &jobs[t]) == 0, "pthread_create");
    }
    for (t = 0; t < THREADS; t++) {
        pthread_join(threads[t], NULL);
        CHECK(jobs[t].mismatches == 0, "thread %d: %d reconstructions differ from serial ones",
              t, jobs[t].mismatches);
        CHECK(jobs[t].message_ok, "thread %d did not see its own last error", t);
    }
    for (k = 0; k < POINTS; k++) {
        free(tables[k]);
    }
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s EXPECTED.txt\n", argv[0]);
        return 2;
    }
    load(argv[1]);
    check_open();
    if (model == NULL) {
        fprintf(stderr, "cannot go on without a model\n");
        return 1;
    }
    check_hostile("hostile_open", 0);
    check_hostile("hostile_locate", 1);
    check_facts();
    check_reconstruct();
    check_eval_and_weights();
    check_map();
    check_locate();
    check_threads();
    brdf_atlas_model_free(model);
    free(expected_text);
    if (failures != 0) {
        fprintf(stderr, "%d checks failed\n", failures);
        return 1;
    }
    printf("all checks passed\n");
    return 0;
}
