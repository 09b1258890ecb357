/*
 * The ensemble runner, tested with a fake generator (a tiny random network
 * drawn from the member's seed) so the orchestration is checked on its own:
 * byte-identical files whatever the thread count and the MPI process count,
 * resuming after deletions, leftovers, SIGTERM and SIGKILL, the key guard,
 * failures, argument checks, and reading metrics.csv back.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "ensemble/ensemble_internal.h"
#include "karst.h"
#include "test_util.h"

/* ------------------------------------------------------------------------ */
/* The fake generator                                                       */
/* ------------------------------------------------------------------------ */
typedef struct fake {
  int slow_ms;         /* sleep per member, in steps that watch the interrupt flag */
  karst_int_t fail_at; /* member index whose realise fails (-1: none) */
  int empty_at;        /* member index that is an empty network (-1: none) */
} fake_t;

static const char *const fake_names[] = {"nodes", "edges", "total_length", "undefined"};

static karst_error_t fake_realise(karst_ctx_t *ctx, void *user, uint64_t seed, karst_int_t index,
                                  karst_network_t *net) {
  fake_t *f = user;
  for (int t = 0; t < f->slow_ms; t += 5) {
    if (karst_interrupted(ctx)) return karst_set_error(ctx, KARST_EINTERRUPTED, "stopped");
    usleep(5000);
  }
  if (index == f->fail_at)
    return karst_set_error(ctx, KARST_EUNREACHABLE, "key point 'sink3' cannot be connected");
  if (index == f->empty_at) return KARST_SUCCESS;
  karst_rng_t r;
  karst_rng_init(&r, seed, 0);
  int n = 3 + (int)karst_rng_below(&r, 8);
  for (int i = 0; i < n; i++) {
    karst_error_t err = karst_network_add_node(net, karst_rng_uniform_range(&r, 0, 100),
                                               karst_rng_uniform_range(&r, 0, 100),
                                               karst_rng_uniform_range(&r, 0, 20), NULL);
    if (err) return err;
  }
  for (int i = 1; i < n; i++)
    karst_network_add_edge(net, i - 1, i, NULL);
  karst_network_add_edge(net, 0, (karst_int_t)karst_rng_below(&r, (uint64_t)n - 1) + 1, NULL);
  double *type = NULL;
  karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &type);
  for (karst_int_t e = 0; e < net->n_edges; e++)
    type[e] = (double)karst_rng_below(&r, KARST_TUNNEL_TYPE_COUNT);
  return KARST_SUCCESS;
}

/* A plain-text stand-in for network.vtp: enough to compare bytes and read back. */
static karst_error_t fake_write(karst_ctx_t *ctx, void *user, const char *dir,
                                const karst_network_t *net) {
  (void)user;
  char path[1024];
  snprintf(path, sizeof path, "%s/network.vtp", dir);
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  karst_attr_t *type = karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
  fprintf(f.fp, "%" PRId64 " %" PRId64 "\n", net->n_nodes, net->n_edges);
  for (karst_int_t i = 0; i < net->n_nodes; i++)
    fprintf(f.fp, "%.17g %.17g %.17g\n", net->xyz[3 * i], net->xyz[3 * i + 1], net->xyz[3 * i + 2]);
  for (karst_int_t e = 0; e < net->n_edges; e++)
    fprintf(f.fp, "%" PRId64 " %" PRId64 " %d\n", net->edges[2 * e], net->edges[2 * e + 1],
            type ? (int)type->data[e] : -1);
  return karst_atomic_commit(ctx, &f);
}

static karst_error_t fake_measure(karst_ctx_t *ctx, void *user, const karst_network_t *net,
                                  double *v) {
  (void)ctx, (void)user;
  double len = 0;
  for (karst_int_t e = 0; e < net->n_edges; e++)
    len += karst_network_edge_length(net, e);
  v[0] = (double)net->n_nodes;
  v[1] = (double)net->n_edges;
  v[2] = net->n_edges ? len : NAN;
  v[3] = NAN;
  return KARST_SUCCESS;
}

static karst_error_t fake_collection(karst_ctx_t *ctx, void *user, const char *path, int n,
                                     const char *const *files) {
  (void)user;
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  for (int i = 0; i < n; i++)
    fprintf(f.fp, "%d %s\n", i, files[i]);
  return karst_atomic_commit(ctx, &f);
}

static void fake_hooks(karst_ensemble_hooks_t *h, fake_t *f) {
  memset(h, 0, sizeof *h);
  h->realise = fake_realise;
  h->write = fake_write;
  h->measure = fake_measure;
  h->write_collection = fake_collection;
  h->n_metrics = 4;
  h->metric_names = fake_names;
  h->user = f;
}

static fake_t fake_default(void) {
  fake_t f = {0, -1, -1};
  return f;
}

/* ------------------------------------------------------------------------ */
/* Files                                                                    */
/* ------------------------------------------------------------------------ */
static char *read_all(const char *path, size_t *len) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  size_t got = fread(s, 1, (size_t)n, fp);
  s[got] = '\0';
  fclose(fp);
  if (len) *len = got;
  return s;
}

/* Every regular file below @p dir, relative paths sorted, one per line. */
static void list_files(const char *root, const char *rel, char *out, size_t size) {
  char path[2048];
  snprintf(path, sizeof path, "%s%s%s", root, *rel ? "/" : "", rel);
  struct dirent **ents = NULL;
  int n = scandir(path, &ents, NULL, alphasort);
  for (int i = 0; i < n; i++) {
    const char *nm = ents[i]->d_name;
    if (strcmp(nm, ".") && strcmp(nm, "..")) {
      char sub[2048], full[4096];
      snprintf(sub, sizeof sub, "%s%s%s", rel, *rel ? "/" : "", nm);
      snprintf(full, sizeof full, "%s/%s", root, sub);
      struct stat st;
      if (stat(full, &st) == 0 && S_ISDIR(st.st_mode))
        list_files(root, sub, out, size);
      else
        snprintf(out + strlen(out), size - strlen(out), "%s\n", sub);
    }
    free(ents[i]);
  }
  free(ents);
}

/* Both trees hold the same files with the same bytes, the run log ensemble_log.json (wall time,
 * members computed and reused) aside: ensemble.json included, byte for byte. */
static void assert_same_tree(const char *a, const char *b) {
  static char la[1 << 16], lb[1 << 16];
  la[0] = lb[0] = '\0';
  list_files(a, "", la, sizeof la);
  list_files(b, "", lb, sizeof lb);
  assert_string_equal(la, lb);
  char *save = NULL;
  for (char *f = strtok_r(la, "\n", &save); f; f = strtok_r(NULL, "\n", &save)) {
    char pa[4096], pb[4096];
    snprintf(pa, sizeof pa, "%s/%s", a, f);
    snprintf(pb, sizeof pb, "%s/%s", b, f);
    size_t na = 0, nb = 0;
    char *sa, *sb;
    if (strcmp(f, KARST_ENSEMBLE_LOG_NAME) == 0) continue;
    sa = read_all(pa, &na);
    sb = read_all(pb, &nb);
    assert_non_null(sa);
    assert_non_null(sb);
    if (na != nb || memcmp(sa, sb, na) != 0) {
      print_error("%s differs between %s and %s\n", f, a, b);
      fail();
    }
    free(sa);
    free(sb);
  }
}

/* Entries whose name contains @p containing, or the visible entries when NULL. */
static int count_entries(const char *dir, const char *containing) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d))) {
    if (containing)
      n += strstr(e->d_name, containing) != NULL;
    else
      n += e->d_name[0] != '.';
  }
  closedir(d);
  return n;
}

static char *make_tmpdir(void) {
  char tmpl[] = "/tmp/karst_test_ensemble_XXXXXX";
  char *d = mkdtemp(tmpl);
  assert_non_null(d);
  return strdup(d);
}

static void rm_rf(const char *dir) {
  char cmd[1200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  assert_int_equal(system(cmd), 0);
}

static karst_error_t run_fake(const char *dir, karst_int_t n, uint64_t seed, int threads, fake_t *f,
                              karst_ensemble_summary_t *sum, karst_ctx_t *ctx_out) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  opt.n = n;
  opt.seed = seed;
  opt.nthreads = threads;
  opt.scenario_path = "fake.yaml";
  opt.scenario_hash = "0123456789abcdef";
  opt.parameters_json = "    \"name\": \"fake\",\n    \"skeleton.gamma\": 2\n";
  karst_ensemble_hooks_t h;
  fake_hooks(&h, f);
  karst_error_t err = karst_ensemble_run(&ctx, dir, &opt, &h, sum);
  if (ctx_out) *ctx_out = ctx;
  return err;
}

/* ------------------------------------------------------------------------ */
/* Tests                                                                    */
/* ------------------------------------------------------------------------ */
static void test_member_seed(void **state) {
  (void)state;
  /* A pure function of (seed, index): equal inputs agree, neighbours differ. */
  assert_true(karst_ensemble_member_seed(7, 3) == karst_ensemble_member_seed(7, 3));
  assert_true(karst_ensemble_member_seed(7, 3) != karst_ensemble_member_seed(7, 4));
  assert_true(karst_ensemble_member_seed(7, 3) != karst_ensemble_member_seed(8, 3));
  /* Definition: the first output of the karst_rng stream (seed, index). */
  karst_rng_t r;
  karst_rng_init(&r, 7, 3);
  assert_true(karst_ensemble_member_seed(7, 3) == karst_rng_u64(&r));
}

/* Same bytes with 1 and 4 threads; metrics.csv rows in index order with the member seeds. */
static void test_threads_byte_identical(void **state) {
  (void)state;
  char *a = make_tmpdir(), *b = make_tmpdir();
  fake_t f = fake_default();
  f.empty_at = 4; /* an empty member: its metrics are empty cells */
  karst_ensemble_summary_t s1, s4;
  assert_int_equal(run_fake(a, 13, 42, 1, &f, &s1, NULL), KARST_SUCCESS);
  assert_int_equal(run_fake(b, 13, 42, 4, &f, &s4, NULL), KARST_SUCCESS);
  assert_int_equal(s1.computed, 13);
  assert_int_equal(s4.computed, 13);
  assert_int_equal(s4.reused, 0);
  assert_same_tree(a, b);

  char p[1200];
  snprintf(p, sizeof p, "%s/metrics.csv", a);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_table_t t;
  karst_ensemble_table_init(&t);
  assert_int_equal(karst_ensemble_table_read(&ctx, p, &t), KARST_SUCCESS);
  assert_int_equal(t.n_rows, 13);
  assert_int_equal(t.n_cols, 4);
  assert_string_equal(t.names[2], "total_length");
  for (karst_int_t i = 0; i < 13; i++) {
    assert_int_equal(t.index[i], i);
    assert_true(t.seed[i] == karst_ensemble_member_seed(42, i));
    assert_true(isnan(t.values[i * 4 + 3])); /* "undefined" is an empty cell */
    if (i == 4) {
      assert_close(t.values[i * 4 + 0], 0, 0);
      assert_true(isnan(t.values[i * 4 + 2]));
    } else {
      /* The fake draws 3..10 nodes and adds one chord: edges = nodes. */
      assert_true(t.values[i * 4 + 0] >= 3 && t.values[i * 4 + 0] <= 10);
      assert_close(t.values[i * 4 + 1], t.values[i * 4 + 0], 0);
    }
  }
  karst_ensemble_table_destroy(&t);

  /* The member row is copied verbatim: the same bytes as the member's own file. */
  char *all = read_all(p, NULL);
  snprintf(p, sizeof p, "%s/realisations/0007/metrics.csv", a);
  char *one = read_all(p, NULL);
  assert_non_null(strstr(all, strchr(one, '\n') + 1));
  free(all);
  free(one);
  /* ensemble.json records scenario, hash, seed, N and the parameters. */
  snprintf(p, sizeof p, "%s/ensemble.json", a);
  char *js = read_all(p, NULL);
  assert_non_null(strstr(js, "\"scenario_hash\": \"0123456789abcdef\""));
  assert_non_null(strstr(js, "\"seed\": 42,"));
  assert_non_null(strstr(js, "\"realisations\": 13,"));
  assert_non_null(strstr(js, "\"skeleton.gamma\": 2"));
  assert_null(strstr(js, "wall_seconds")); /* the run log is its own file */
  free(js);
  char logp[1300];
  snprintf(logp, sizeof logp, "%s/" KARST_ENSEMBLE_LOG_NAME, a);
  js = read_all(logp, NULL);
  assert_non_null(js);
  assert_non_null(strstr(js, "\"wall_seconds\": "));
  assert_non_null(strstr(js, "\"computed\": 13,"));
  free(js);
  /* Independent check that ensemble.json is valid JSON. */
  char cmd[1400];
  snprintf(cmd, sizeof cmd,
           "/usr/bin/python3 -c \"import json,sys; d=json.load(open('%s')); "
           "sys.exit(0 if d['realisations']==13 and len(d['metrics'])==4 else 1)\"",
           p);
  assert_int_equal(system(cmd), 0);
  rm_rf(a);
  rm_rf(b);
  free(a);
  free(b);
}

/* Deleted members and a leftover temporary: the re-run computes only what is missing. */
static void test_resume_after_deletion(void **state) {
  (void)state;
  char *ref = make_tmpdir(), *d = make_tmpdir();
  fake_t f = fake_default();
  karst_ensemble_summary_t s;
  assert_int_equal(run_fake(ref, 12, 5, 2, &f, &s, NULL), KARST_SUCCESS);
  assert_int_equal(run_fake(d, 12, 5, 2, &f, &s, NULL), KARST_SUCCESS);
  char p[1200];
  snprintf(p, sizeof p, "rm -rf '%s/realisations/0003' '%s/realisations/0007' '%s/metrics.csv'", d,
           d, d);
  assert_int_equal(system(p), 0);
  /* What a SIGKILL can leave: a hidden member temporary and a collection temporary. */
  snprintf(p, sizeof p, "%s/realisations/.0003.tmp.99999", d);
  assert_int_equal(mkdir(p, 0777), 0);
  snprintf(p, sizeof p, "%s/realisations/.0003.tmp.99999/network.vtp", d);
  FILE *fp = fopen(p, "w");
  fputs("half a fi", fp);
  fclose(fp);
  snprintf(p, sizeof p, "%s/.metrics.csv.tmp.99999.0", d);
  fp = fopen(p, "w");
  fputs("index,se", fp);
  fclose(fp);

  assert_int_equal(run_fake(d, 12, 5, 3, &f, &s, NULL), KARST_SUCCESS);
  assert_int_equal(s.computed, 2);
  assert_int_equal(s.reused, 10);
  assert_int_equal(s.complete, 12);
  assert_same_tree(ref, d);
  /* A complete ensemble re-run computes nothing and writes the same files. */
  assert_int_equal(run_fake(d, 12, 5, 1, &f, &s, NULL), KARST_SUCCESS);
  assert_int_equal(s.computed, 0);
  assert_same_tree(ref, d);
  rm_rf(ref);
  rm_rf(d);
  free(ref);
  free(d);
}

static volatile int child_stop;
static void on_term(int sig) {
  (void)sig;
  child_stop = 1;
}

/* Start a slow ensemble in a child, signal it once a few members are done, return its status. */
static int interrupted_child(const char *dir, int sig, karst_int_t n) {
  pid_t pid = fork();
  assert_true(pid >= 0);
  if (pid == 0) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    ctx.interrupt = &child_stop;
    ctx.nthreads = 2;
    fake_t f = fake_default();
    f.slow_ms = 40;
    karst_ensemble_options_t opt;
    karst_ensemble_options_init(&opt);
    opt.n = n;
    opt.seed = 9;
    opt.nthreads = 2;
    opt.scenario_path = "fake.yaml";
    opt.scenario_hash = "0123456789abcdef";
    opt.parameters_json = "    \"name\": \"fake\",\n    \"skeleton.gamma\": 2\n";
    karst_ensemble_hooks_t h;
    fake_hooks(&h, &f);
    karst_error_t err = karst_ensemble_run(&ctx, dir, &opt, &h, NULL);
    _exit((int)err);
  }
  char real[1200];
  snprintf(real, sizeof real, "%s/realisations", dir);
  for (int tries = 0; tries < 2000 && count_entries(real, NULL) < 5; tries++)
    usleep(5000);
  kill(pid, sig);
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

/* SIGTERM mid-run: finished members kept, nothing half-written, re-run gives the same bytes. */
static void test_interrupt_and_resume(void **state) {
  (void)state;
  char *ref = make_tmpdir(), *d = make_tmpdir();
  fake_t f = fake_default();
  karst_ensemble_summary_t s;
  assert_int_equal(run_fake(ref, 60, 9, 2, &f, &s, NULL), KARST_SUCCESS);

  int status = interrupted_child(d, SIGTERM, 60);
  assert_true(WIFEXITED(status));
  assert_int_equal(WEXITSTATUS(status), KARST_EINTERRUPTED);
  char real[1200], p[1300];
  snprintf(real, sizeof real, "%s/realisations", d);
  assert_int_equal(count_entries(real, ".tmp."), 0); /* no temporary left */
  assert_int_equal(count_entries(d, ".tmp."), 0);
  snprintf(p, sizeof p, "%s/metrics.csv", d);
  assert_int_not_equal(access(p, F_OK), 0);    /* collection files only when complete */
  int members = count_entries(real, NULL) - 1; /* minus ensemble.key */
  assert_true(members >= 3 && members < 60);
  /* Every member directory present is complete. */
  for (int i = 0; i < 60; i++) {
    snprintf(p, sizeof p, "%s/%04d", real, i);
    if (access(p, F_OK) != 0) continue;
    snprintf(p, sizeof p, "%s/%04d/metrics.csv", real, i);
    char *m = read_all(p, NULL);
    assert_non_null(m);
    int lines = 0;
    for (char *c = m; *c; c++)
      lines += *c == '\n';
    assert_int_equal(lines, 2);
    free(m);
  }
  assert_int_equal(run_fake(d, 60, 9, 2, &f, &s, NULL), KARST_SUCCESS);
  assert_int_equal(s.reused, members);
  assert_int_equal(s.computed, 60 - members);
  assert_same_tree(ref, d);
  rm_rf(d);

  /* SIGKILL: no clean-up at all; the re-run removes the leftovers and completes. */
  char *k = make_tmpdir();
  status = interrupted_child(k, SIGKILL, 60);
  assert_true(WIFSIGNALED(status));
  assert_int_equal(run_fake(k, 60, 9, 1, &f, &s, NULL), KARST_SUCCESS);
  snprintf(real, sizeof real, "%s/realisations", k);
  assert_int_equal(count_entries(real, ".tmp."), 0);
  assert_same_tree(ref, k);
  rm_rf(k);
  rm_rf(ref);
  free(k);
  free(d);
  free(ref);
}

/* A directory of another seed is refused instead of mixing two ensembles. */
static void test_key_guard(void **state) {
  (void)state;
  char *d = make_tmpdir();
  fake_t f = fake_default();
  karst_ensemble_summary_t s;
  karst_ctx_t ctx;
  assert_int_equal(run_fake(d, 3, 1, 1, &f, &s, NULL), KARST_SUCCESS);
  assert_int_equal(run_fake(d, 3, 2, 1, &f, &s, &ctx), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "another scenario or seed"));
  assert_non_null(strstr(ctx.errmsg, "ensemble.key"));
  /* More members of the same ensemble are fine: the first three are reused. */
  assert_int_equal(run_fake(d, 5, 1, 1, &f, &s, NULL), KARST_SUCCESS);
  assert_int_equal(s.reused, 3);
  rm_rf(d);
  free(d);
}

/* A failing member: the message names it, earlier members stay, nothing half-written. */
static void test_member_failure(void **state) {
  (void)state;
  char *d = make_tmpdir();
  fake_t f = fake_default();
  f.fail_at = 5;
  karst_ensemble_summary_t s;
  karst_ctx_t ctx;
  assert_int_equal(run_fake(d, 9, 3, 1, &f, &s, &ctx), KARST_EUNREACHABLE);
  assert_string_equal(ctx.errmsg, "realisation 5: key point 'sink3' cannot be connected");
  char p[1200];
  for (int i = 0; i < 5; i++) {
    snprintf(p, sizeof p, "%s/realisations/%04d/network.vtp", d, i);
    assert_int_equal(access(p, F_OK), 0);
  }
  snprintf(p, sizeof p, "%s/realisations/0005", d);
  assert_int_not_equal(access(p, F_OK), 0);
  snprintf(p, sizeof p, "%s/realisations", d);
  assert_int_equal(count_entries(p, ".tmp."), 0);
  snprintf(p, sizeof p, "%s/metrics.csv", d);
  assert_int_not_equal(access(p, F_OK), 0);
  rm_rf(d);
  free(d);
}

static void test_arguments(void **state) {
  (void)state;
  char *d = make_tmpdir();
  fake_t f = fake_default();
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  karst_ensemble_hooks_t h;
  fake_hooks(&h, &f);
  opt.n = 0;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "got 0"));
  opt.n = KARST_ENSEMBLE_MAX_MEMBERS + (karst_int_t)1;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "got 100000001"));
  opt.n = 2;
  opt.nthreads = 0;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_ERANGE);
  opt.nthreads = KARST_ENSEMBLE_MAX_THREADS + 1;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "got 1025"));
  assert_int_equal(count_entries(d, NULL), 0); /* refused before anything was created */
  opt.nthreads = 1;
  h.realise = NULL;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_EINVAL);
  fake_hooks(&h, &f);
  const char *bad[] = {"a", "b,c"};
  h.metric_names = bad;
  h.n_metrics = 2;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "b,c"));
  assert_int_equal(karst_ensemble_run(&ctx, "", &opt, &h, NULL), KARST_EINVAL);
  /* A single member, more threads than members. */
  fake_hooks(&h, &f);
  opt.n = 1;
  opt.nthreads = 8;
  karst_ensemble_summary_t s;
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, &s), KARST_SUCCESS);
  assert_int_equal(s.complete, 1);
  rm_rf(d);
  free(d);
}

/* A second run into a DIR whose lock is held is refused before it touches anything: here the
 * test holds the flock(2) itself, as a concurrent `karst ensemble` would. */
static void test_lock(void **state) {
  (void)state;
  char *d = make_tmpdir();
  char lock[1100], real[1100], tmp[1200];
  fake_t f = fake_default();
  karst_ctx_t ctx;
  snprintf(lock, sizeof lock, "%s/%s", d, KARST_ENSEMBLE_LOCK_NAME);
  snprintf(real, sizeof real, "%s/realisations", d);
  snprintf(tmp, sizeof tmp, "%s/.0001.tmp.999999", real);
  assert_int_equal(mkdir(real, 0777), 0);
  assert_int_equal(mkdir(tmp, 0777), 0); /* "the other run's" member in progress */
  int fd = open(lock, O_RDWR | O_CREAT, 0666);
  assert_true(fd >= 0);
  assert_int_equal(flock(fd, LOCK_EX | LOCK_NB), 0);
  assert_int_equal(pwrite(fd, "4242\n", 5, 0), 5);
  assert_int_equal(run_fake(d, 3, 7, 2, &f, NULL, &ctx), KARST_EBUSY);
  assert_non_null(strstr(ctx.errmsg, "in use by another karst ensemble (pid 4242"));
  struct stat st;
  assert_int_equal(stat(tmp, &st), 0);           /* not removed as a leftover */
  assert_int_equal(count_entries(real, NULL), 0); /* no member, no ensemble.key */
  assert_int_equal(stat(lock, &st), 0);          /* the holder's lock file is left alone */
  close(fd);                                     /* the holder ends (without unlinking) */
  assert_int_equal(run_fake(d, 3, 7, 2, &f, NULL, &ctx), KARST_SUCCESS);
  assert_int_not_equal(stat(tmp, &st), 0);     /* now a leftover, removed */
  assert_int_not_equal(stat(lock, &st), 0);    /* removed at the end of the run */
  assert_int_equal(count_entries(real, NULL), 4); /* 3 members + ensemble.key */
  rm_rf(d);
  free(d);
}

/* The launcher detection reads OMPI_COMM_WORLD_SIZE, else PMI_SIZE; a build without MPI refuses
 * a start as one of several processes, a build with MPI accepts it. Expected values are the
 * variables' contents (and 1 for absent or malformed ones). */
static void test_launcher_detection(void **state) {
  (void)state;
  char *saved_ompi = getenv("OMPI_COMM_WORLD_SIZE"), *saved_pmi = getenv("PMI_SIZE");
  saved_ompi = saved_ompi ? strdup(saved_ompi) : NULL;
  saved_pmi = saved_pmi ? strdup(saved_pmi) : NULL;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  int size = 0;
  unsetenv("OMPI_COMM_WORLD_SIZE");
  unsetenv("PMI_SIZE");
  assert_int_equal(karst_ensemble_launcher_size(), 1);
  assert_int_equal(karst_i_ensemble_launcher_check(&ctx, 0, &size), KARST_SUCCESS);
  assert_int_equal(size, 1);
  setenv("OMPI_COMM_WORLD_SIZE", "4", 1);
  assert_int_equal(karst_ensemble_launcher_size(), 4);
  assert_int_equal(karst_i_ensemble_launcher_check(&ctx, 0, &size), KARST_EUNSUPPORTED);
  assert_int_equal(size, 4);
  assert_non_null(strstr(ctx.errmsg, "one of 4 processes"));
  assert_non_null(strstr(ctx.errmsg, "built without MPI"));
  assert_int_equal(karst_i_ensemble_launcher_check(&ctx, 1, &size), KARST_SUCCESS);
  setenv("OMPI_COMM_WORLD_SIZE", "1", 1); /* mpirun -np 1: one process, nothing to race */
  assert_int_equal(karst_i_ensemble_launcher_check(&ctx, 0, &size), KARST_SUCCESS);
  const char *malformed[] = {"", "x", "-2", "0", "3x", " 3"};
  for (size_t k = 0; k < sizeof malformed / sizeof *malformed; k++) {
    setenv("OMPI_COMM_WORLD_SIZE", malformed[k], 1);
    assert_int_equal(karst_ensemble_launcher_size(), 1);
  }
  unsetenv("OMPI_COMM_WORLD_SIZE");
  setenv("PMI_SIZE", "3", 1); /* MPICH's Hydra, Slurm */
  assert_int_equal(karst_ensemble_launcher_size(), 3);
  assert_int_equal(karst_i_ensemble_launcher_check(&ctx, 0, &size), KARST_EUNSUPPORTED);
  setenv("OMPI_COMM_WORLD_SIZE", "2", 1); /* Open MPI's variable comes first */
  assert_int_equal(karst_ensemble_launcher_size(), 2);
#if !KARST_HAVE_MPI
  /* This build has no MPI: karst_ensemble_mpi_start itself refuses. */
  int ranks = 0, rank = -1, init = -1;
  assert_int_equal(karst_ensemble_mpi_start(&ctx, &ranks, &rank, &init), KARST_EUNSUPPORTED);
  assert_int_equal(init, 0);
#endif
  unsetenv("OMPI_COMM_WORLD_SIZE");
  unsetenv("PMI_SIZE");
  if (saved_ompi) setenv("OMPI_COMM_WORLD_SIZE", saved_ompi, 1);
  if (saved_pmi) setenv("PMI_SIZE", saved_pmi, 1);
  free(saved_ompi);
  free(saved_pmi);
}

static int progress_calls;
static double progress_last_done, progress_last_total;
static void count_progress(void *user, const char *stage, double done, double total) {
  (void)user;
  assert_string_equal(stage, "ensemble");
  assert_true(done >= progress_last_done); /* never goes backwards */
  progress_calls++;
  progress_last_done = done;
  progress_last_total = total;
}

static void test_progress(void **state) {
  (void)state;
  char *d = make_tmpdir();
  fake_t f = fake_default();
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.progress = count_progress;
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  opt.n = 6;
  opt.nthreads = 2;
  karst_ensemble_hooks_t h;
  fake_hooks(&h, &f);
  assert_int_equal(karst_ensemble_run(&ctx, d, &opt, &h, NULL), KARST_SUCCESS);
  /* At least the start (0 of 6) and the end (6 of 6); intermediate reports may coalesce. */
  assert_true(progress_calls >= 2);
  assert_close(progress_last_done, 6, 0);
  assert_close(progress_last_total, 6, 0);
  rm_rf(d);
  free(d);
}

static void write_text(const char *path, const char *text) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
}

/* Malformed metrics tables: each error names FILE:LINE and the offending cell. */
static void test_table_errors(void **state) {
  (void)state;
  char *d = make_tmpdir();
  char p[1200];
  snprintf(p, sizeof p, "%s/m.csv", d);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_table_t t;
  karst_ensemble_table_init(&t);
  struct {
    const char *text, *expect;
  } cases[] = {
      {"", "m.csv:1: empty file"},
      {"idx,seed,a\n", "m.csv:1: the header must start with \"index,seed\""},
      {"index,seed,a\n0,1,2\n1,2\n", "m.csv:3: 2 cells, expected 3"},
      {"index,seed,a\n0,1,x2\n", "m.csv:2: column 'a' must be a number or empty, got \"x2\""},
      {"index,seed,a\n-1,1,2\n", "m.csv:2: index must be a non-negative integer"},
      {"index,seed,a\n0,-1,2\n", "m.csv:2: seed must be an unsigned integer"},
      {"index,seed,a\n0,1,nan\n", "m.csv:2: column 'a'"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    write_text(p, cases[i].text);
    assert_int_equal(karst_ensemble_table_read(&ctx, p, &t), KARST_EPARSE);
    if (!strstr(ctx.errmsg, cases[i].expect)) {
      print_error("case %zu: '%s' lacks '%s'\n", i, ctx.errmsg, cases[i].expect);
      fail();
    }
    assert_int_equal(t.n_rows, 0);
  }
  /* Header only: zero rows, names kept. */
  write_text(p, "index,seed,a,b\n");
  assert_int_equal(karst_ensemble_table_read(&ctx, p, &t), KARST_SUCCESS);
  assert_int_equal(t.n_rows, 0);
  assert_int_equal(t.n_cols, 2);
  assert_int_equal(karst_ensemble_table_column(&t, "b"), 1);
  assert_int_equal(karst_ensemble_table_column(&t, "c"), -1);
  karst_ensemble_table_destroy(&t);
  snprintf(p, sizeof p, "%s/missing.csv", d);
  assert_int_equal(karst_ensemble_table_read(&ctx, p, &t), KARST_EIO);
  rm_rf(d);
  free(d);
}

/* The parameters block of ensemble.json is valid JSON for a default scenario, with the
 * same members as run.json (the defaults of karst_scenario_init, docs/scenario.md). */
static void test_parameters_json(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  char *s = karst_ensemble_parameters_json(&sc);
  assert_non_null(s);
  assert_non_null(strstr(s, "    \"gamma\": 2,\n"));
  assert_non_null(strstr(s, "\"epikarst\": [0.5, 0.5]"));
  char *d = make_tmpdir(), p[1200], cmd[1500];
  snprintf(p, sizeof p, "%s/p.json", d);
  FILE *fp = fopen(p, "w");
  fprintf(fp, "{\n%s}\n", s);
  fclose(fp);
  snprintf(cmd, sizeof cmd,
           "/usr/bin/python3 -c \"import json; d=json.load(open('%s')); "
           "assert d['sampling']['k']==40 and d['reuse']==0.5 and "
           "d['cost']['fracture_combine']=='sum'\"",
           p);
  assert_int_equal(system(cmd), 0);
  free(s);
  karst_scenario_destroy(&sc);
  rm_rf(d);
  free(d);
}

/* The real writers and metrics (VTK .vtp, Karstnet pair, karst_metrics_compute, .pvd) behind
 * a fake realisation: same bytes for 1 and 2 threads, and the files read back. */
static karst_error_t seed_only_realise(karst_ctx_t *ctx, void *user, uint64_t seed,
                                       karst_int_t index, karst_network_t *net) {
  (void)user;
  fake_t f = fake_default();
  return fake_realise(ctx, &f, seed, index, net);
}

static void test_pipeline_writers(void **state) {
  (void)state;
  char *a = make_tmpdir(), *b = make_tmpdir();
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_hooks_t h;
  karst_ensemble_pipeline_t pipe;
  assert_int_equal(karst_ensemble_hooks_pipeline(&ctx, &h, &pipe, &sc), KARST_SUCCESS);
  int nf = 0;
  karst_metric_fields(&nf);
  assert_int_equal(h.n_metrics, nf);
  h.realise = seed_only_realise;
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  opt.n = 5;
  opt.seed = 3;
  opt.nthreads = 1;
  karst_ensemble_summary_t s;
  assert_int_equal(karst_ensemble_run(&ctx, a, &opt, &h, &s), KARST_SUCCESS);
  opt.nthreads = 2;
  assert_int_equal(karst_ensemble_run(&ctx, b, &opt, &h, &s), KARST_SUCCESS);
  assert_same_tree(a, b);
  char p[1200];
  const char *files[] = {"ensemble.pvd", "realisations/0004/network.vtp",
                         "realisations/0004/network_nodes.dat",
                         "realisations/0004/network_links.dat"};
  for (int i = 0; i < 4; i++) {
    snprintf(p, sizeof p, "%s/%s", a, files[i]);
    assert_int_equal(access(p, F_OK), 0);
  }
  /* The member reads back (VTK reader) with the node count its metrics row records. */
  snprintf(p, sizeof p, "%s/realisations/0004/network.vtp", a);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_read_network(&ctx, p, KARST_FORMAT_AUTO, &net), KARST_SUCCESS);
  snprintf(p, sizeof p, "%s/metrics.csv", a);
  karst_ensemble_table_t t;
  karst_ensemble_table_init(&t);
  assert_int_equal(karst_ensemble_table_read(&ctx, p, &t), KARST_SUCCESS);
  int cn = karst_ensemble_table_column(&t, "nodes"), ce = karst_ensemble_table_column(&t, "edges");
  assert_true(cn >= 0 && ce >= 0);
  assert_close(t.values[4 * t.n_cols + cn], (double)net.n_nodes, 0);
  assert_close(t.values[4 * t.n_cols + ce], (double)net.n_edges, 0);
  karst_ensemble_table_destroy(&t);
  karst_network_destroy(&net);
  /* The collection lists the members in order (Python's XML parser). */
  char cmd[1600];
  snprintf(cmd, sizeof cmd,
           "/usr/bin/python3 -c \"import xml.etree.ElementTree as E; "
           "d=[x.get('file') for x in E.parse('%s/ensemble.pvd').getroot().iter('DataSet')]; "
           "assert d==['realisations/%%04d/network.vtp'%%i for i in range(5)], d\"",
           a);
  assert_int_equal(system(cmd), 0);
  karst_scenario_destroy(&sc);
  rm_rf(a);
  rm_rf(b);
  free(a);
  free(b);
}

/* MPI: the test program re-runs itself under mpirun as 3 ranks (--mpi-child DIR). */
static int mpi_child(const char *dir) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  int ranks = 1, rank = 0, init = 0;
  if (karst_ensemble_mpi_start(&ctx, &ranks, &rank, &init) != KARST_SUCCESS) return 1;
  if (ranks != 3) { /* library built without MPI: every process would be rank 0 */
    karst_ensemble_mpi_finish(init);
    return 77;
  }
  fake_t f = fake_default();
  karst_ensemble_summary_t s;
  karst_error_t err = run_fake(dir, 11, 77, 2, &f, &s, &ctx);
  if (err) fprintf(stderr, "rank %d: %s\n", rank, ctx.errmsg);
  /* Rank r computed exactly the members i with i mod 3 = r. */
  int want = (11 - rank + 2) / 3;
  if (!err && s.computed != want) {
    fprintf(stderr, "rank %d computed %d members, expected %d\n", rank, (int)s.computed, want);
    err = KARST_EINVAL;
  }
  karst_ensemble_mpi_finish(init);
  return (int)err;
}

#if KARST_HAVE_MPI
static void test_mpi_three_ranks(void **state) {
  (void)state;
  /* Registered only in MPI builds (see main); scripts/install-deps installs Open MPI. */
  if (system("command -v mpirun >/dev/null 2>&1") != 0) {
    print_error("mpirun not found: run scripts/install-deps\n");
    fail();
  }
  char *ref = make_tmpdir(), *d = make_tmpdir();
  fake_t f = fake_default();
  karst_ensemble_summary_t s;
  assert_int_equal(run_fake(ref, 11, 77, 1, &f, &s, NULL), KARST_SUCCESS);
  char self[1024];
  ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  assert_true(n > 0);
  self[n] = '\0';
  char cmd[3000];
  snprintf(cmd, sizeof cmd,
           "mpirun --allow-run-as-root --oversubscribe -np 3 -x ASAN_OPTIONS=detect_leaks=0 "
           "'%s' --mpi-child '%s' > '%s.log' 2>&1",
           self, d, d);
  int rc = system(cmd);
  if (rc != 0) {
    snprintf(cmd, sizeof cmd, "cat '%s.log'", d);
    (void)system(cmd);
  }
  assert_int_equal(rc, 0);
  assert_same_tree(ref, d);
  snprintf(cmd, sizeof cmd, "%s/" KARST_ENSEMBLE_LOG_NAME, d);
  char *js = read_all(cmd, NULL);
  assert_non_null(strstr(js, "\"ranks\": 3"));
  free(js);
  snprintf(cmd, sizeof cmd, "rm -f '%s.log'", d);
  (void)system(cmd);
  rm_rf(ref);
  rm_rf(d);
  free(ref);
  free(d);
}
#endif

int main(int argc, char **argv) {
  if (argc == 3 && strcmp(argv[1], "--mpi-child") == 0) return mpi_child(argv[2]);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_member_seed),
      cmocka_unit_test(test_threads_byte_identical),
      cmocka_unit_test(test_resume_after_deletion),
      cmocka_unit_test(test_interrupt_and_resume),
      cmocka_unit_test(test_key_guard),
      cmocka_unit_test(test_member_failure),
      cmocka_unit_test(test_arguments),
      cmocka_unit_test(test_lock),
      cmocka_unit_test(test_launcher_detection),
      cmocka_unit_test(test_progress),
      cmocka_unit_test(test_table_errors),
      cmocka_unit_test(test_parameters_json),
      cmocka_unit_test(test_pipeline_writers),
#if KARST_HAVE_MPI
      cmocka_unit_test(test_mpi_three_ranks),
#endif
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
