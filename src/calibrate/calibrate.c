/* karst calibrate (include/karst/calibrate.h, docs/calibration.md): ABC-SMC of scenario
 * parameters against the metrics of a survey, every simulation a member of an ensemble.
 *
 * Why it is built this way:
 *  - The APMC engine (abc.c) works on a box of latent coordinates with a uniform prior: a
 *    uniform parameter is its own latent value, a log-uniform one its logarithm, and an
 *    integer key k in [lo, hi] the floor of a latent value in [lo, hi + 1) (or of its
 *    exponential), so each integer gets the prior mass of its unit cell and the kernel stays
 *    a continuous Gaussian.
 *  - Generation t is the ensemble DIR/generations/TTT: member i simulates proposal i with the
 *    member seed of karst_ensemble_run. Proposals depend only on the base seed and the
 *    metrics of earlier generations, which are read back from the ensembles' metrics.csv
 *    (%.17g round-trips every double). A re-run therefore recomputes every proposal
 *    bit for bit, finds the finished members on disk and simulates only the missing ones:
 *    a killed run loses nothing, and a resumed, a threaded and an MPI run write the same bytes.
 *  - Every particle's scenario is read through karst_scenario_load_with_overrides, so a
 *    proposed value is validated exactly like a value of the file.
 *  - Under MPI every rank computes the same proposals; only rank 0 writes the calibration's
 *    own files, and every step that can fail on one rank is agreed by all. */
#include "karst/calibrate.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "calibrate/calibrate_internal.h"
#include "ensemble/ensemble_internal.h"
#include "karst/compare.h"
#include "karst/ensemble.h"
#include "karst/generate.h"
#include "karst/io.h"
#include "karst/json.h"
#include "karst/metrics.h"
#include "karst/scenario.h"
#include "karst/version.h"
#include "scenario/scenario_internal.h"

/** Random streams of a calibration with base seed S: the proposals of generation t come from
 *  karst_rng stream (S, KARST_I_STREAM_PROPOSE + t), the base seed of its ensemble is the first
 *  output of stream (S, KARST_I_STREAM_SIMULATE + t). */
#define KARST_I_STREAM_PROPOSE (1ULL << 40)
#define KARST_I_STREAM_SIMULATE (2ULL << 40)
/** Bounds combinations checked by karst_calibrate_check_params: every corner of the prior box
 *  up to this many parameters (2^10 = 1024 loads), else the two extreme corners. */
#define KARST_I_CHECK_ALL_CORNERS_UP_TO 10
/** The lock of a calibration directory, held while a run works in it. */
#define KARST_I_CALIBRATE_LOCK ".calibrate.lock"

static const char *const collon_metrics[] = {
    "mean_length", "cv_length", "length_entropy", "tortuosity", "orientation_entropy",
    "aspl",        "cpd",       "mean_degree",    "cv_degree",  "correlation_vertex_degree"};

const char *const *karst_calibrate_default_metrics(int *n) {
  *n = (int)(sizeof collon_metrics / sizeof collon_metrics[0]);
  return collon_metrics;
}

void karst_calibrate_options_init(karst_calibrate_options_t *opt) {
  memset(opt, 0, sizeof *opt);
  opt->particles = KARST_CALIBRATE_DEFAULT_PARTICLES;
  opt->alpha = KARST_CALIBRATE_DEFAULT_ALPHA;
  opt->generations = KARST_CALIBRATE_DEFAULT_GENERATIONS;
  opt->min_acceptance = KARST_CALIBRATE_DEFAULT_MIN_ACCEPTANCE;
  opt->best_members = KARST_CALIBRATE_DEFAULT_BEST_MEMBERS;
  opt->seed = 1;
  opt->nthreads = 1;
  opt->use_mpi = 1;
}

/* ------------------------------------------------------------------------ */
/* Parameters                                                               */
/* ------------------------------------------------------------------------ */

static int parse_bound(const char *s, size_t len, double *out) {
  char buf[64];
  if (len == 0 || len >= sizeof buf) return -1;
  memcpy(buf, s, len);
  buf[len] = '\0';
  char *end;
  errno = 0;
  double v = strtod(buf, &end);
  if (end == buf || *end || errno == ERANGE || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

/**
 * Parse a --vary specification (calibrate.h): "KEY=LO:HI", "KEY=LO:HI:log",
 * "KEY=LO:HI:uniform". Messages quote the specification.
 * Time complexity: O(length).
 */
karst_error_t karst_calibrate_param_parse(karst_ctx_t *ctx, const char *spec,
                                          karst_calibrate_param_t *p) {
  memset(p, 0, sizeof *p);
  if (!spec) return karst_set_error(ctx, KARST_EINVAL, "no parameter given");
  snprintf(p->spec, sizeof p->spec, "%s", spec);
  const char *eq = strchr(spec, '=');
  if (!eq || !strchr(eq, ':'))
    return karst_set_error(ctx, KARST_EINVAL,
                           "'%s' needs KEY=LO:HI (uniform prior) or KEY=LO:HI:log (log-uniform), "
                           "e.g. skeleton.gamma=0.5:3",
                           p->spec);
  if (eq == spec) return karst_set_error(ctx, KARST_EINVAL, "'%s': no key before '='", p->spec);
  if ((size_t)(eq - spec) >= sizeof p->key)
    return karst_set_error(ctx, KARST_EINVAL, "'%s': the key is longer than %zu characters",
                           p->spec, sizeof p->key - 1);
  memcpy(p->key, spec, (size_t)(eq - spec));
  p->key[eq - spec] = '\0';
  const char *lo = eq + 1, *c1 = strchr(lo, ':');
  const char *hi = c1 + 1, *c2 = strchr(hi, ':');
  size_t hlen = c2 ? (size_t)(c2 - hi) : strlen(hi);
  if (parse_bound(lo, (size_t)(c1 - lo), &p->lo))
    return karst_set_error(ctx, KARST_EINVAL, "'%s': LO must be a finite number, got '%.*s'",
                           p->spec, (int)(c1 - lo), lo);
  if (parse_bound(hi, hlen, &p->hi))
    return karst_set_error(ctx, KARST_EINVAL, "'%s': HI must be a finite number, got '%.*s'",
                           p->spec, (int)hlen, hi);
  p->prior = KARST_PRIOR_UNIFORM;
  if (c2) {
    if (!strcmp(c2 + 1, "log"))
      p->prior = KARST_PRIOR_LOG_UNIFORM;
    else if (strcmp(c2 + 1, "uniform") != 0)
      return karst_set_error(ctx, KARST_EINVAL,
                             "'%s': the prior must be 'uniform' or 'log' (KEY=LO:HI:log), got '%s'",
                             p->spec, c2 + 1);
  }
  if (!(p->lo < p->hi))
    return karst_set_error(ctx, KARST_ERANGE, "'%s': LO must be below HI, got %g and %g", p->spec,
                           p->lo, p->hi);
  if (p->prior == KARST_PRIOR_LOG_UNIFORM && !(p->lo > 0))
    return karst_set_error(ctx, KARST_ERANGE, "'%s': a log-uniform prior needs LO > 0, got %g",
                           p->spec, p->lo);
  return KARST_SUCCESS;
}

/* The text of a value for the scenario parser: integers in digits, reals with 17 digits (the
 * parser reads back the same double). */
static void value_text(const karst_calibrate_param_t *p, double v, char *out, size_t size) {
  if (p->is_integer)
    snprintf(out, size, "%lld", (long long)v);
  else
    snprintf(out, size, "%.17g", v);
}

/* The latent prior box of a parameter (see the file comment). */
static void latent_box(const karst_calibrate_param_t *p, double *a, double *b) {
  double hi = p->is_integer ? p->hi + 1 : p->hi;
  if (p->prior == KARST_PRIOR_LOG_UNIFORM) {
    *a = log(p->lo);
    *b = log(hi);
  } else {
    *a = p->lo;
    *b = hi;
  }
}

/* The parameter value of latent @p u: exp for log priors, floor for integers, kept in
 * [lo, hi] against rounding at the ends. */
static double latent_value(const karst_calibrate_param_t *p, double u) {
  double v = p->prior == KARST_PRIOR_LOG_UNIFORM ? exp(u) : u;
  if (p->is_integer) v = floor(v);
  if (v < p->lo) v = p->lo;
  if (v > p->hi) v = p->hi;
  return v;
}

/* Load @p path with the parameters at @p values (origin: the --vary specification). */
static karst_error_t load_at(karst_ctx_t *ctx, const char *path, int n,
                             const karst_calibrate_param_t *params, const double *values,
                             karst_override_type_t *types, karst_scenario_t *sc) {
  karst_scenario_override_t ov[KARST_CALIBRATE_MAX_PARAMS];
  char text[KARST_CALIBRATE_MAX_PARAMS][40];
  for (int k = 0; k < n; k++) {
    value_text(&params[k], values[k], text[k], sizeof text[k]);
    ov[k] = (karst_scenario_override_t){params[k].key, text[k], params[k].spec, 1};
  }
  return karst_scenario_load_with_overrides(ctx, path, ov, n, types, sc);
}

/**
 * Check the parameters against the scenario (calibrate.h): each key through the scenario
 * parser at its bounds (the bounds as written, so an integer key given 0.5 is refused by the
 * parser itself), then every corner of the prior box.
 * Time complexity: O(2^n) scenario loads for n <= KARST_I_CHECK_ALL_CORNERS_UP_TO, else O(n).
 */
karst_error_t karst_calibrate_check_params(karst_ctx_t *ctx, const char *scenario_path, int n,
                                           karst_calibrate_param_t *params) {
  karst_error_t err = KARST_SUCCESS;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  if (n < 1 || n > KARST_CALIBRATE_MAX_PARAMS)
    return karst_set_error(ctx, KARST_ERANGE, "between 1 and %d parameters can be varied, got %d",
                           KARST_CALIBRATE_MAX_PARAMS, n);
  for (int k = 0; k < n; k++) {
    for (int j = 0; j < k; j++)
      if (!strcmp(params[j].key, params[k].key))
        return karst_set_error(ctx, KARST_EINVAL, "'%s': %s is varied twice (also '%s')",
                               params[k].spec, params[k].key, params[j].spec);
    if (!strncmp(params[k].key, "random.", 7) && strcmp(params[k].key, "random.seed") != 0)
      return karst_set_error(ctx, KARST_EINVAL,
                             "'%s': %s is not a model parameter (the calibration sets the seeds "
                             "and the number of simulations)",
                             params[k].spec, params[k].key);
  }
  /* Each key alone, at each bound, as the user wrote it: the parser says what is wrong. */
  for (int k = 0; k < n; k++) {
    for (int b = 0; b < 2; b++) {
      char text[64];
      snprintf(text, sizeof text, "%.17g", b ? params[k].hi : params[k].lo);
      karst_scenario_override_t ov = {params[k].key, text, params[k].spec, 1};
      karst_override_type_t type = KARST_OVERRIDE_UNREAD;
      err = karst_scenario_load_with_overrides(ctx, scenario_path, &ov, 1, &type, &sc);
      if (err == KARST_EINVAL && type == KARST_OVERRIDE_INTEGER &&
          (params[k].lo != floor(params[k].lo) || params[k].hi != floor(params[k].hi))) {
        err = karst_set_error(ctx, KARST_EINVAL,
                              "'%s': %s is an integer key: LO and HI must be whole numbers, got "
                              "%g and %g",
                              params[k].spec, params[k].key, params[k].lo, params[k].hi);
      }
      if (err) goto cleanup;
      params[k].is_integer = type == KARST_OVERRIDE_INTEGER;
    }
  }
  /* Every corner (cross-field rules such as feature_radius <= fill_radius). */
  int all = n <= KARST_I_CHECK_ALL_CORNERS_UP_TO;
  long corners = all ? 1L << n : 2;
  for (long c = 0; c < corners; c++) {
    double v[KARST_CALIBRATE_MAX_PARAMS];
    for (int k = 0; k < n; k++) {
      int high = all ? (int)((c >> k) & 1) : (int)c;
      v[k] = high ? params[k].hi : params[k].lo;
    }
    err = load_at(ctx, scenario_path, n, params, v, NULL, &sc);
    if (err) {
      char msg[KARST_ERRMSG_MAX];
      snprintf(msg, sizeof msg, "%s", ctx->errmsg);
      err = karst_set_error(ctx, err, "the prior bounds do not combine: %s", msg);
      goto cleanup;
    }
  }
cleanup:
  karst_scenario_destroy(&sc);
  return err;
}

/* ------------------------------------------------------------------------ */
/* The members of one generation                                            */
/* ------------------------------------------------------------------------ */

typedef struct gen_hooks {
  const char *scenario_path;
  int d, generation;
  const karst_calibrate_param_t *params;
  const double *values; /* m × d parameter values */
  karst_ensemble_hooks_t pipeline;
  karst_ensemble_pipeline_t pipe_storage;
} gen_hooks_t;

/* Member @p index simulates proposal @p index. A network whose key points cannot all be
 * connected (KARST_EUNREACHABLE) is an empty network: every metric undefined, distance +∞,
 * never accepted; every other failure stops the run. */
static karst_error_t gen_realise(karst_ctx_t *ctx, void *user, uint64_t member_seed,
                                 karst_int_t index, karst_network_t *net) {
  const gen_hooks_t *g = user;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_error_t err =
      load_at(ctx, g->scenario_path, g->d, g->params, &g->values[index * g->d], NULL, &sc);
  if (!err) err = karst_generate(ctx, &sc, member_seed, 0, net, NULL, NULL);
  if (err == KARST_EUNREACHABLE) {
    karst_log(ctx, KARST_LOG_INFO, "generation %d, particle %" PRId64 ": %s (distance +inf)",
              g->generation, index, ctx->errmsg);
    karst_network_destroy(net);
    karst_network_init(net);
    err = KARST_SUCCESS;
  }
  karst_scenario_destroy(&sc);
  return err;
}

/* Particles keep only their metrics (networks can be regenerated from posterior.csv). */
static karst_error_t gen_write(karst_ctx_t *ctx, void *user, const char *dir,
                               const karst_network_t *net) {
  (void)ctx;
  (void)user;
  (void)dir;
  (void)net;
  return KARST_SUCCESS;
}

static karst_error_t gen_measure(karst_ctx_t *ctx, void *user, const karst_network_t *net,
                                 double *values) {
  gen_hooks_t *g = user;
  return g->pipeline.measure(ctx, g->pipeline.user, net, values);
}

/* Progress of the members of a generation as "generation T". */
typedef struct gen_progress {
  const karst_ctx_t *parent;
  char stage[48];
} gen_progress_t;

static void gen_progress(void *user, const char *stage, double done, double total) {
  gen_progress_t *p = user;
  (void)stage;
  karst_progress(p->parent, p->stage, done, total);
}

/* ------------------------------------------------------------------------ */
/* Run state                                                                */
/* ------------------------------------------------------------------------ */

typedef struct run {
  const karst_calibrate_options_t *opt;
  const char *dir;
  int d, ranks, rank;
  karst_calibrate_param_t params[KARST_CALIBRATE_MAX_PARAMS];
  /* metrics: every column of karst_metric_fields; the distance uses sel[] */
  int n_fields;
  const karst_metric_field_t *fields;
  double survey[KARST_METRIC_FIELDS_MAX];
  int n_sel;
  int sel[KARST_CALIBRATE_MAX_METRICS];      /* field index of each selected metric */
  double scale[KARST_CALIBRATE_MAX_METRICS]; /* spread under the prior (NAN: not used) */
  int scale_is_mad[KARST_CALIBRATE_MAX_METRICS];
  char scenario_hash[17], survey_hash[17];
  karst_scenario_t base; /* the scenario as its file gives it (for the pipeline hooks) */
  char file_value[KARST_CALIBRATE_MAX_PARAMS][64]; /* the file's text of each key ("": default) */
  karst_i_abc_t abc;
  karst_i_calib_history_t hist;
  karst_int_t simulations, computed;
} run_t;

/* The directory of generation @p g, malloc'ed. */
static char *gen_dir(const char *dir, int g) {
  char rel[64];
  snprintf(rel, sizeof rel, "generations/%03d", g);
  return karst_i_path_join(dir, rel);
}

static karst_error_t no_memory(karst_ctx_t *ctx) {
  return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
}

/* The key of a calibration: what must not change between a run and its continuation. */
static char *key_text(const run_t *r) {
  char *text = NULL;
  size_t len = 0;
  FILE *fp = open_memstream(&text, &len);
  if (!fp) return NULL;
  const karst_calibrate_options_t *o = r->opt;
  fprintf(fp,
          "karst calibration key 1\nscenario_hash %s\nsurvey_hash %s\nseed %" PRIu64
          "\nparticles %" PRId64 "\nalpha %.17g\nmetrics",
          r->scenario_hash, r->survey_hash, o->seed, o->particles, o->alpha);
  for (int k = 0; k < r->n_sel; k++)
    fprintf(fp, "%c%s", k ? ',' : ' ', r->fields[r->sel[k]].key);
  fputc('\n', fp);
  for (int k = 0; k < r->d; k++)
    fprintf(fp, "vary %s %s %.17g %.17g\n", r->params[k].key,
            r->params[k].prior == KARST_PRIOR_LOG_UNIFORM ? "log" : "uniform", r->params[k].lo,
            r->params[k].hi);
  if (fclose(fp) != 0) {
    free(text);
    return NULL;
  }
  return text;
}

static karst_error_t check_or_write_key(karst_ctx_t *ctx, const run_t *r) {
  char *want = key_text(r), *path = karst_i_path_join(r->dir, "calibration.key");
  karst_error_t err = !want || !path
                          ? no_memory(ctx)
                          : karst_i_key_file(ctx, path, want,
                                             "a calibration of another scenario, survey, "
                                             "seed, particle count, alpha, metric set or "
                                             "prior",
                                             "the same settings to continue it");
  free(want);
  free(path);
  return err;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The median of the finite values of @p x (@p n entries) into *med, their count into *count;
 * @p tmp is scratch of n entries. */
static void median_of(const double *x, karst_int_t n, double *tmp, double *med,
                      karst_int_t *count) {
  karst_int_t m = 0;
  for (karst_int_t i = 0; i < n; i++)
    if (isfinite(x[i])) tmp[m++] = x[i];
  *count = m;
  *med = NAN;
  if (m == 0) return;
  qsort(tmp, (size_t)m, sizeof *tmp, cmp_double);
  *med = m % 2 ? tmp[m / 2] : 0.5 * (tmp[m / 2 - 1] + tmp[m / 2]);
}

/* ------------------------------------------------------------------------ */
/* Setup                                                                    */
/* ------------------------------------------------------------------------ */

static karst_error_t check_options(karst_ctx_t *ctx, const char *dir,
                                   const karst_calibrate_options_t *o) {
  if (!dir || !*dir) return karst_set_error(ctx, KARST_EINVAL, "no output directory given");
  if (!o->scenario_path || !o->survey_path)
    return karst_set_error(ctx, KARST_EINVAL, "a calibration needs a scenario and a survey");
  if (o->particles < 4 || o->particles > KARST_CALIBRATE_MAX_PARTICLES)
    return karst_set_error(ctx, KARST_ERANGE,
                           "the number of particles must be within [4, %d], got %" PRId64,
                           KARST_CALIBRATE_MAX_PARTICLES, o->particles);
  if (!(o->alpha > 0 && o->alpha < 1))
    return karst_set_error(ctx, KARST_ERANGE, "alpha must be within (0, 1), got %g", o->alpha);
  karst_int_t keep = (karst_int_t)floor(o->alpha * (double)o->particles);
  if (keep < 2 || keep >= o->particles)
    return karst_set_error(ctx, KARST_ERANGE,
                           "alpha %g keeps %" PRId64 " of %" PRId64
                           " particles: it must keep at least 2 and fewer than all",
                           o->alpha, keep, o->particles);
  if (o->generations < 0 || o->generations > KARST_CALIBRATE_MAX_GENERATIONS)
    return karst_set_error(ctx, KARST_ERANGE, "the generations must be within [0, %d], got %d",
                           KARST_CALIBRATE_MAX_GENERATIONS, o->generations);
  if (!(o->min_acceptance >= 0 && o->min_acceptance <= 1))
    return karst_set_error(ctx, KARST_ERANGE,
                           "the minimum acceptance must be within [0, 1], got %g",
                           o->min_acceptance);
  if (o->best_members < 0 || o->best_members > KARST_ENSEMBLE_MAX_MEMBERS)
    return karst_set_error(ctx, KARST_ERANGE, "the members of the best fit must be within [0, %d]",
                           KARST_ENSEMBLE_MAX_MEMBERS);
  if (o->nthreads < 1 || o->nthreads > KARST_ENSEMBLE_MAX_THREADS)
    return karst_set_error(ctx, KARST_ERANGE,
                           "the number of threads must be within [1, %d], got %d",
                           KARST_ENSEMBLE_MAX_THREADS, o->nthreads);
  if (o->n_params < 1 || o->n_params > KARST_CALIBRATE_MAX_PARAMS || !o->params)
    return karst_set_error(ctx, KARST_ERANGE, "between 1 and %d parameters can be varied, got %d",
                           KARST_CALIBRATE_MAX_PARAMS, o->n_params);
  if (o->n_metrics < 0 || o->n_metrics > KARST_CALIBRATE_MAX_METRICS ||
      (o->n_metrics > 0 && !o->metrics))
    return karst_set_error(ctx, KARST_ERANGE, "between 1 and %d metrics can be used, got %d",
                           KARST_CALIBRATE_MAX_METRICS, o->n_metrics);
  return KARST_SUCCESS;
}

/* The field index of metric @p name, or -1. */
static int field_index(const karst_metric_field_t *fields, int n_fields, const char *name) {
  for (int f = 0; f < n_fields; f++)
    if (!strcmp(fields[f].key, name)) return f;
  return -1;
}

/**
 * Check metric names (calibrate.h).
 * Time complexity: O(n × fields × name length²) (the suggestion's edit distances).
 */
karst_error_t karst_calibrate_check_metrics(karst_ctx_t *ctx, int n, const char *const *names) {
  int n_fields = 0;
  const karst_metric_field_t *fields = karst_metric_fields(&n_fields);
  const char *keys[KARST_METRIC_FIELDS_MAX];
  for (int f = 0; f < n_fields; f++)
    keys[f] = fields[f].key;
  if (n < 1 || n > KARST_CALIBRATE_MAX_METRICS)
    return karst_set_error(ctx, KARST_ERANGE, "between 1 and %d metrics can be used, got %d",
                           KARST_CALIBRATE_MAX_METRICS, n);
  for (int k = 0; k < n; k++) {
    if (field_index(fields, n_fields, names[k]) < 0) {
      const char *hint = karst_i_suggest(names[k], keys, n_fields);
      return karst_set_error(ctx, KARST_EINVAL,
                             "unknown metric '%s'%s%s%s (the metrics of karst "
                             "metrics: mean_length, cv_length, ..., see docs/metrics.md)",
                             names[k], hint ? " (did you mean '" : "", hint ? hint : "",
                             hint ? "'?)" : "");
    }
    for (int j = 0; j < k; j++)
      if (!strcmp(names[j], names[k]))
        return karst_set_error(ctx, KARST_EINVAL, "the metric %s is given twice", names[k]);
  }
  return KARST_SUCCESS;
}

/* The selected metrics and the survey's values of them. */
static karst_error_t select_metrics(karst_ctx_t *ctx, run_t *r) {
  const karst_calibrate_options_t *o = r->opt;
  int n_default = 0;
  const char *const *names =
      o->n_metrics > 0 ? o->metrics : karst_calibrate_default_metrics(&n_default);
  int n = o->n_metrics > 0 ? o->n_metrics : n_default;
  karst_error_t err = karst_calibrate_check_metrics(ctx, n, names);
  if (err) return err;
  r->n_sel = 0;
  for (int k = 0; k < n; k++) {
    int f = field_index(r->fields, r->n_fields, names[k]);
    if (!isfinite(r->survey[f])) {
      if (o->n_metrics > 0)
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: the survey's %s is undefined (docs/metrics.md); leave it out "
                               "of the metrics",
                               o->survey_path, names[k]);
      karst_log(ctx, KARST_LOG_WARNING, "%s: the survey's %s is undefined; it is left out",
                o->survey_path, names[k]);
      continue;
    }
    r->sel[r->n_sel++] = f;
  }
  if (r->n_sel == 0)
    return karst_set_error(ctx, KARST_EINVAL, "%s: none of the metrics is defined for the survey",
                           o->survey_path);
  return KARST_SUCCESS;
}

static karst_error_t setup(karst_ctx_t *ctx, run_t *r) {
  const karst_calibrate_options_t *o = r->opt;
  karst_error_t err = check_options(ctx, r->dir, o);
  if (err) return err;
  err = karst_scenario_load(ctx, o->scenario_path, &r->base);
  if (err) return err;
  r->d = o->n_params;
  memcpy(r->params, o->params, (size_t)r->d * sizeof *r->params);
  err = karst_calibrate_check_params(ctx, o->scenario_path, r->d, r->params);
  if (err) return err;
  for (int k = 0; k < r->d; k++) {
    karst_ctx_t quiet = *ctx;
    if (karst_scenario_value_text(&quiet, o->scenario_path, r->params[k].key, r->file_value[k],
                                  sizeof r->file_value[k]) != KARST_SUCCESS)
      r->file_value[k][0] = '\0';
  }
  r->fields = karst_metric_fields(&r->n_fields);
  const char *names[KARST_METRIC_FIELDS_MAX];
  int got = 0;
  err = karst_compare_survey_metrics(ctx, o->survey_path, KARST_METRIC_FIELDS_MAX, names, r->survey,
                                     &got);
  if (err) return err;
  err = select_metrics(ctx, r);
  if (err) return err;
  err = karst_file_hash(ctx, o->scenario_path, r->scenario_hash);
  if (!err) err = karst_file_hash(ctx, o->survey_path, r->survey_hash);
  if (err) return err;
  double lo[KARST_CALIBRATE_MAX_PARAMS], hi[KARST_CALIBRATE_MAX_PARAMS];
  for (int k = 0; k < r->d; k++)
    latent_box(&r->params[k], &lo[k], &hi[k]);
  karst_int_t keep = (karst_int_t)floor(o->alpha * (double)o->particles);
  return karst_i_abc_init(ctx, &r->abc, r->d, lo, hi, o->particles, keep);
}

/* ------------------------------------------------------------------------ */
/* History                                                                  */
/* ------------------------------------------------------------------------ */

static void history_destroy(karst_i_calib_history_t *h) {
  free(h->gen);
  free(h->values);
  free(h->weights);
  free(h->dist);
  free(h->born);
  free(h->member);
  free(h->seed);
  memset(h, 0, sizeof *h);
}

#define GROW(ptr, count)                                                                           \
  do {                                                                                             \
    void *p_ = realloc((ptr), (size_t)(count) * sizeof *(ptr));                                    \
    if (!p_) return no_memory(ctx);                                                                \
    (ptr) = p_;                                                                                    \
  } while (0)

/* Append the population after generation @p g; @p seeds[t] are the member seeds of
 * generation t. */
static karst_error_t history_push(karst_ctx_t *ctx, run_t *r, const karst_calibrate_generation_t *g,
                                  uint64_t *const *seeds) {
  karst_i_calib_history_t *h = &r->hist;
  karst_int_t nk = r->abc.n_keep;
  int d = r->d;
  if (h->n_gen == h->cap) {
    int cap = h->cap ? 2 * h->cap : 8;
    GROW(h->gen, cap);
    GROW(h->values, (karst_int_t)cap * nk * d);
    GROW(h->weights, (karst_int_t)cap * nk);
    GROW(h->dist, (karst_int_t)cap * nk);
    GROW(h->born, (karst_int_t)cap * nk);
    GROW(h->member, (karst_int_t)cap * nk);
    GROW(h->seed, (karst_int_t)cap * nk);
    h->cap = cap;
  }
  h->d = d;
  h->n_keep = nk;
  karst_int_t base = (karst_int_t)h->n_gen * nk;
  h->gen[h->n_gen] = *g;
  karst_i_abc_weights(&r->abc, &h->weights[base]);
  for (karst_int_t j = 0; j < nk; j++) {
    for (int k = 0; k < d; k++)
      h->values[(base + j) * d + k] = latent_value(&r->params[k], r->abc.u[j * d + k]);
    h->dist[base + j] = r->abc.rho[j];
    h->born[base + j] = r->abc.born[j];
    h->member[base + j] = r->abc.member[j];
    h->seed[base + j] = seeds[r->abc.born[j]][r->abc.member[j]];
  }
  h->n_gen++;
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* One generation                                                           */
/* ------------------------------------------------------------------------ */

static void csv_value(FILE *fp, const karst_calibrate_param_t *p, double v) {
  char t[40];
  value_text(p, v, t, sizeof t);
  fputs(t, fp);
}

static karst_error_t write_particles(karst_ctx_t *ctx, const run_t *r, const char *path,
                                     karst_int_t m, const double *values) {
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  fputs("index", f.fp);
  for (int k = 0; k < r->d; k++)
    fprintf(f.fp, ",%s", r->params[k].key);
  fputc('\n', f.fp);
  for (karst_int_t i = 0; i < m; i++) {
    fprintf(f.fp, "%" PRId64, i);
    for (int k = 0; k < r->d; k++) {
      fputc(',', f.fp);
      csv_value(f.fp, &r->params[k], values[i * r->d + k]);
    }
    fputc('\n', f.fp);
  }
  return karst_atomic_commit(ctx, &f);
}

/* The distance scales from the members of generation 0 (the prior predictive): the median
 * absolute deviation × KARST_CALIBRATE_MAD_TO_SD, else the standard deviation when the MAD is
 * 0 (a metric that is constant for most members); a metric that does not vary at all is left
 * out of the distance (it cannot tell particles apart). */
static karst_error_t prior_scales(karst_ctx_t *ctx, run_t *r, const karst_ensemble_table_t *t,
                                  const int *col) {
  karst_int_t n = t->n_rows;
  double *x = malloc((size_t)n * sizeof *x), *tmp = malloc((size_t)n * sizeof *tmp);
  if (!x || !tmp) {
    free(x);
    free(tmp);
    return no_memory(ctx);
  }
  int used = 0;
  for (int k = 0; k < r->n_sel; k++) {
    karst_int_t cnt = 0;
    double med, mad;
    for (karst_int_t i = 0; i < n; i++)
      x[i] = t->values[i * t->n_cols + col[k]];
    median_of(x, n, tmp, &med, &cnt);
    for (karst_int_t i = 0; i < n; i++)
      x[i] = fabs(x[i] - med);
    median_of(x, n, tmp, &mad, &cnt);
    r->scale[k] = NAN;
    r->scale_is_mad[k] = 0;
    if (cnt >= 2 && mad > 0) {
      r->scale[k] = KARST_CALIBRATE_MAD_TO_SD * mad;
      r->scale_is_mad[k] = 1;
    } else if (cnt >= 2) {
      double mean = 0, ss = 0;
      karst_int_t c = 0;
      for (karst_int_t i = 0; i < n; i++) {
        double v = t->values[i * t->n_cols + col[k]];
        if (isfinite(v)) mean += v, c++;
      }
      mean /= (double)c;
      for (karst_int_t i = 0; i < n; i++) {
        double v = t->values[i * t->n_cols + col[k]];
        if (isfinite(v)) ss += (v - mean) * (v - mean);
      }
      double sd = sqrt(ss / (double)(c - 1));
      if (sd > 0) r->scale[k] = sd;
    }
    if (isnan(r->scale[k]))
      karst_log(ctx, KARST_LOG_WARNING,
                "%s does not vary over the prior sample: it is left out of the distance",
                r->fields[r->sel[k]].key);
    else
      used++;
  }
  free(x);
  free(tmp);
  if (!used)
    return karst_set_error(ctx, KARST_EINVAL,
                           "none of the metrics varies over the %" PRId64
                           " prior simulations: the distance cannot tell the particles apart",
                           n);
  return KARST_SUCCESS;
}

/* Standardised Euclidean distance of member @p i to the survey; +∞ when a metric used is
 * undefined for the member. */
static double distance(const run_t *r, const karst_ensemble_table_t *t, const int *col,
                       karst_int_t i) {
  double s = 0;
  for (int k = 0; k < r->n_sel; k++) {
    if (isnan(r->scale[k])) continue;
    double x = t->values[i * t->n_cols + col[k]];
    if (!isfinite(x)) return INFINITY;
    double z = (x - r->survey[r->sel[k]]) / r->scale[k];
    s += z * z;
  }
  return sqrt(s);
}

/* Run generation @p g; its member seeds into *seeds_out (malloc'ed). */
static karst_error_t run_generation(karst_ctx_t *ctx, run_t *r, int g,
                                    karst_calibrate_generation_t *info, uint64_t **seeds_out,
                                    karst_ensemble_table_t *prior_table) {
  karst_error_t err = KARST_SUCCESS;
  const karst_calibrate_options_t *o = r->opt;
  int d = r->d;
  karst_int_t m = karst_i_abc_batch(&r->abc);
  double *u = malloc((size_t)m * (size_t)d * sizeof *u);
  double *values = malloc((size_t)m * (size_t)d * sizeof *values);
  double *logw = malloc((size_t)m * sizeof *logw), *rho = malloc((size_t)m * sizeof *rho);
  uint64_t *seeds = malloc((size_t)m * sizeof *seeds);
  char *dir = gen_dir(r->dir, g), *ppath = NULL, *mpath = NULL;
  karst_ensemble_table_t table;
  karst_ensemble_table_init(&table);
  gen_hooks_t gh;
  memset(&gh, 0, sizeof gh);
  memset(info, 0, sizeof *info);
  if (!u || !values || !logw || !rho || !seeds || !dir) {
    err = no_memory(ctx);
    goto cleanup;
  }
  ppath = karst_i_path_join(dir, "particles.csv");
  mpath = karst_i_path_join(dir, "metrics.csv");
  if (!ppath || !mpath) {
    err = no_memory(ctx);
    goto cleanup;
  }
  karst_rng_t rng;
  karst_rng_init(&rng, o->seed, KARST_I_STREAM_PROPOSE + (uint64_t)g);
  err = karst_i_abc_propose(ctx, &r->abc, &rng, u, logw);
  if (err) goto cleanup;
  for (karst_int_t i = 0; i < m; i++)
    for (int k = 0; k < d; k++)
      values[i * d + k] = latent_value(&r->params[k], u[i * d + k]);

  /* The proposals, on disk before any member runs (rank 0 writes, all agree). */
  if (r->rank == 0) {
    err = karst_mkdir_p(ctx, dir);
    if (!err) err = write_particles(ctx, r, ppath, m, values);
  }
  {
    karst_error_t all = karst_i_ensemble_agree(r->ranks, err);
    if (all && !err)
      err = karst_set_error(ctx, all, "rank 0 could not write %s: %s", ppath, karst_strerror(all));
    if (err) goto cleanup;
  }
  char hash[17];
  err = karst_file_hash(ctx, ppath, hash);
  if (err) goto cleanup;

  gh.scenario_path = o->scenario_path;
  gh.d = d;
  gh.generation = g;
  gh.params = r->params;
  gh.values = values;
  err = karst_ensemble_hooks_pipeline(ctx, &gh.pipeline, &gh.pipe_storage, &r->base);
  if (err) goto cleanup;
  karst_ensemble_hooks_t hooks = gh.pipeline;
  hooks.realise = gen_realise;
  hooks.write = gen_write;
  hooks.measure = gen_measure;
  hooks.write_collection = NULL;
  hooks.user = &gh;

  karst_rng_t srng;
  karst_rng_init(&srng, o->seed, KARST_I_STREAM_SIMULATE + (uint64_t)g);
  karst_ensemble_options_t eo;
  karst_ensemble_options_init(&eo);
  eo.n = m;
  eo.seed = karst_rng_u64(&srng);
  eo.nthreads = o->nthreads;
  eo.use_mpi = o->use_mpi;
  eo.scenario_path = ppath;
  eo.scenario_hash = hash;
  karst_ctx_t ectx = *ctx;
  gen_progress_t gp = {ctx, ""};
  snprintf(gp.stage, sizeof gp.stage, "generation %d", g);
  if (ctx->progress) {
    ectx.progress = gen_progress;
    ectx.progress_user = &gp;
  }
  karst_ensemble_summary_t es;
  err = karst_ensemble_run(&ectx, dir, &eo, &hooks, &es);
  if (err) {
    ctx->errcode = ectx.errcode;
    snprintf(ctx->errmsg, sizeof ctx->errmsg, "generation %d: %.2000s", g, ectx.errmsg);
    goto cleanup;
  }
  err = karst_ensemble_table_read(ctx, mpath, &table);
  if (err) goto cleanup;
  int col[KARST_CALIBRATE_MAX_METRICS];
  for (int k = 0; k < r->n_sel; k++) {
    col[k] = karst_ensemble_table_column(&table, r->fields[r->sel[k]].key);
    if (col[k] < 0) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s: no column %s", mpath, r->fields[r->sel[k]].key);
      goto cleanup;
    }
  }
  if (table.n_rows != m) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s: %" PRId64 " rows, expected %" PRId64, mpath,
                          table.n_rows, m);
    goto cleanup;
  }
  if (g == 0) {
    err = prior_scales(ctx, r, &table, col);
    if (err) goto cleanup;
  }
  karst_int_t undefined = 0;
  for (karst_int_t i = 0; i < m; i++) {
    rho[i] = distance(r, &table, col, i);
    undefined += isinf(rho[i]);
    seeds[i] = table.seed[i];
  }
  karst_int_t accepted = 0;
  err = karst_i_abc_update(ctx, &r->abc, u, logw, rho, &accepted);
  if (err) goto cleanup;
  info->generation = g;
  info->simulations = m;
  info->computed = es.complete - es.reused;
  info->accepted = accepted;
  info->acceptance = g == 0 ? NAN : (double)accepted / (double)m;
  info->undefined = undefined;
  info->tolerance = r->abc.tolerance;
  info->ess = karst_i_abc_ess(&r->abc);
  info->generations_max = o->generations;
  r->simulations += m;
  r->computed += es.computed;
  *seeds_out = seeds;
  seeds = NULL;
  if (g == 0) {
    *prior_table = table;
    karst_ensemble_table_init(&table);
  }
cleanup:
  karst_ensemble_table_destroy(&table);
  free(u);
  free(values);
  free(logw);
  free(rho);
  free(seeds);
  free(dir);
  free(ppath);
  free(mpath);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Outputs                                                                  */
/* ------------------------------------------------------------------------ */

static void csv_number(FILE *fp, double v) {
  if (isnan(v))
    return;
  else if (isinf(v))
    fputs(v > 0 ? "inf" : "-inf", fp);
  else
    fprintf(fp, "%.17g", v);
}

static karst_error_t write_posterior(karst_ctx_t *ctx, const run_t *r, const char *path) {
  const karst_i_calib_history_t *h = &r->hist;
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  fputs("generation,particle", f.fp);
  for (int k = 0; k < r->d; k++)
    fprintf(f.fp, ",%s", r->params[k].key);
  fputs(",weight,distance,simulated_in,member,seed\n", f.fp);
  for (int g = 0; g < h->n_gen; g++)
    for (karst_int_t j = 0; j < h->n_keep; j++) {
      karst_int_t at = (karst_int_t)g * h->n_keep + j;
      fprintf(f.fp, "%d,%" PRId64, g, j);
      for (int k = 0; k < r->d; k++) {
        fputc(',', f.fp);
        csv_value(f.fp, &r->params[k], h->values[at * r->d + k]);
      }
      fputc(',', f.fp);
      csv_number(f.fp, h->weights[at]);
      fputc(',', f.fp);
      csv_number(f.fp, h->dist[at]);
      fprintf(f.fp, ",%d,%" PRId64 ",%" PRIu64 "\n", h->born[at], h->member[at], h->seed[at]);
    }
  return karst_atomic_commit(ctx, &f);
}

static karst_error_t write_generations(karst_ctx_t *ctx, const run_t *r, const char *path) {
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  fputs("generation,simulations,accepted,acceptance,undefined,tolerance,ess\n", f.fp);
  for (int g = 0; g < r->hist.n_gen; g++) {
    const karst_calibrate_generation_t *x = &r->hist.gen[g];
    fprintf(f.fp, "%d,%" PRId64 ",", x->generation, x->simulations);
    if (g > 0) fprintf(f.fp, "%" PRId64, x->accepted);
    fputc(',', f.fp);
    csv_number(f.fp, x->acceptance);
    fprintf(f.fp, ",%" PRId64 ",", x->undefined);
    csv_number(f.fp, x->tolerance);
    fputc(',', f.fp);
    csv_number(f.fp, x->ess);
    fputc('\n', f.fp);
  }
  return karst_atomic_commit(ctx, &f);
}

static void json_number(FILE *fp, double v) {
  if (isfinite(v))
    fprintf(fp, "%.17g", v);
  else
    fputs("null", fp);
}

static const char *const stop_names[] = {"generations", "acceptance"};

static karst_error_t write_summary(karst_ctx_t *ctx, const run_t *r, const char *path,
                                   const karst_calibrate_summary_t *s) {
  const karst_calibrate_options_t *o = r->opt;
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  FILE *fp = f.fp;
  fputs("{\n  \"karst_version\": ", fp);
  karst_json_string(fp, karst_version());
  char *versions = karst_versions_json(); /* the libraries, as in ensemble.json and run.json */
  fprintf(fp, ",\n  \"versions\": %s", versions ? versions : "{}");
  free(versions);
  fputs(",\n  \"method\": \"ABC-SMC: adaptive population Monte Carlo ABC of Lenormand, Jabot & "
        "Deffuant 2013 (Algorithm 4) with the weights and truncated Gaussian kernel of Beaumont "
        "et al. 2009\",\n  \"scenario\": ",
        fp);
  karst_json_string(fp, o->scenario_path);
  fprintf(fp, ",\n  \"scenario_hash\": \"%s\",\n  \"survey\": ", r->scenario_hash);
  karst_json_string(fp, o->survey_path);
  fprintf(fp,
          ",\n  \"survey_hash\": \"%s\",\n  \"seed\": %" PRIu64 ",\n  \"particles\": %" PRId64
          ",\n  \"alpha\": %.17g,\n  \"population\": %" PRId64
          ",\n  \"generations_max\": %d,\n  \"min_acceptance\": %.17g,\n  \"best_members\": %d,\n",
          r->survey_hash, o->seed, o->particles, o->alpha, r->abc.n_keep, o->generations,
          o->min_acceptance, o->best_members);
  fputs("  \"parameters\": [\n", fp);
  for (int k = 0; k < r->d; k++) {
    const karst_calibrate_param_t *p = &r->params[k];
    fputs("    {\"key\": ", fp);
    karst_json_string(fp, p->key);
    fprintf(fp, ", \"prior\": \"%s\", \"low\": %.17g, \"high\": %.17g, \"integer\": %s",
            p->prior == KARST_PRIOR_LOG_UNIFORM ? "log-uniform" : "uniform", p->lo, p->hi,
            p->is_integer ? "true" : "false");
    fputs(", \"scenario_value\": ", fp);
    if (r->file_value[k][0])
      karst_json_string(fp, r->file_value[k]);
    else
      fputs("null", fp);
    fputs(", \"median\": ", fp);
    json_number(fp, s->median[k]);
    fputs(", \"q05\": ", fp);
    json_number(fp, s->low[k]);
    fputs(", \"q95\": ", fp);
    json_number(fp, s->high[k]);
    fprintf(fp, "}%s\n", k + 1 < r->d ? "," : "");
  }
  fputs("  ],\n  \"metrics\": [\n", fp);
  for (int k = 0; k < r->n_sel; k++) {
    fputs("    {\"name\": ", fp);
    karst_json_string(fp, r->fields[r->sel[k]].key);
    fputs(", \"survey\": ", fp);
    json_number(fp, r->survey[r->sel[k]]);
    fputs(", \"scale\": ", fp);
    json_number(fp, r->scale[k]);
    fprintf(fp, ", \"scale_kind\": \"%s\", \"used\": %s}%s\n",
            isnan(r->scale[k])   ? "none"
            : r->scale_is_mad[k] ? "mad"
                                 : "sd",
            isnan(r->scale[k]) ? "false" : "true", k + 1 < r->n_sel ? "," : "");
  }
  fputs("  ],\n  \"generations\": [\n", fp);
  for (int g = 0; g < r->hist.n_gen; g++) {
    const karst_calibrate_generation_t *x = &r->hist.gen[g];
    fprintf(fp, "    {\"generation\": %d, \"simulations\": %" PRId64 ", \"accepted\": %" PRId64,
            x->generation, x->simulations, x->accepted);
    fputs(", \"acceptance\": ", fp);
    json_number(fp, x->acceptance);
    fprintf(fp, ", \"undefined\": %" PRId64 ", \"tolerance\": ", x->undefined);
    json_number(fp, x->tolerance);
    fputs(", \"ess\": ", fp);
    json_number(fp, x->ess);
    fprintf(fp, "}%s\n", g + 1 < r->hist.n_gen ? "," : "");
  }
  fprintf(fp, "  ],\n  \"stop\": \"%s\",\n  \"best\": \"best.yaml\",\n", stop_names[s->stop]);
  fprintf(fp,
          "  \"timings\": {\"wall_seconds\": %.3f, \"simulations\": %" PRId64
          ", \"computed\": %" PRId64 ", \"threads\": %d, \"ranks\": %d}\n}\n",
          s->wall_seconds, s->simulations, s->computed, o->nthreads, s->ranks);
  return karst_atomic_commit(ctx, &f);
}

/* best.yaml: the scenario at the posterior median. It is written beside DIR/best.yaml first;
 * when it differs from the one there, the ensemble of the old one (DIR/best) is removed before
 * the new file replaces it, so DIR/best always belongs to DIR/best.yaml. */
static karst_error_t write_best(karst_ctx_t *ctx, const run_t *r, const double *best,
                                const karst_calibrate_summary_t *s, const char *path,
                                const char *best_dir) {
  /* The temporary is hidden and named like karst_temp_name's, so a killed run's leftover is
   * removed by the next run (karst_i_remove_stale_temporaries). */
  static const char next_name[] = ".best.yaml.tmp.next";
  karst_error_t err = KARST_SUCCESS;
  karst_scenario_override_t ov[KARST_CALIBRATE_MAX_PARAMS];
  char text[KARST_CALIBRATE_MAX_PARAMS][40];
  char *header = NULL, *next = NULL;
  size_t hlen = 0;
  FILE *hp = open_memstream(&header, &hlen);
  if (!hp) return no_memory(ctx);
  fprintf(hp,
          "# karst calibrate: %s at the weighted posterior median, fitted to the survey %s\n"
          "# by ABC-SMC (Lenormand et al. 2013), seed %" PRIu64 ", %" PRId64
          " particles per generation,\n# %d generations after the prior sample; see "
          "posterior.csv and report.html beside this file.\n",
          r->opt->scenario_path, r->opt->survey_path, r->opt->seed, r->opt->particles,
          s->generations);
  for (int k = 0; k < r->d; k++) {
    value_text(&r->params[k], best[k], text[k], sizeof text[k]);
    ov[k] = (karst_scenario_override_t){r->params[k].key, text[k], r->params[k].spec, 1};
    fprintf(hp, "#   %s = %s (was %s; 90 %% credible interval %.6g to %.6g; prior %s %g to %g)\n",
            r->params[k].key, text[k], r->file_value[k][0] ? r->file_value[k] : "the default",
            s->low[k], s->high[k],
            r->params[k].prior == KARST_PRIOR_LOG_UNIFORM ? "log-uniform" : "uniform",
            r->params[k].lo, r->params[k].hi);
  }
  if (fclose(hp) != 0) {
    free(header);
    return no_memory(ctx);
  }
  next = karst_i_path_join(r->dir, next_name);
  if (!next) {
    err = no_memory(ctx);
    goto cleanup;
  }
  err = karst_scenario_write_with_overrides(ctx, r->opt->scenario_path, ov, r->d, header, next);
  if (err) goto cleanup;
  char h_new[17], h_old[17];
  karst_ctx_t quiet = *ctx;
  int same = karst_file_hash(ctx, next, h_new) == KARST_SUCCESS &&
             karst_file_hash(&quiet, path, h_old) == KARST_SUCCESS && !strcmp(h_new, h_old);
  if (!same && karst_i_remove_tree(best_dir) != 0) {
    err = karst_set_error(ctx, KARST_EIO,
                          "%s: cannot remove the ensemble of the previous best fit: %s", best_dir,
                          strerror(errno));
    goto cleanup;
  }
  err = karst_rename_into_place(ctx, next, path);
cleanup:
  if (err && next) unlink(next);
  free(next);
  free(header);
  return err;
}

/* The ensemble of best.yaml in DIR/best, with the calibration's base seed: the same as
 * `karst ensemble DIR/best.yaml -n M --seed S -o DIR/best`. */
static karst_error_t run_best(karst_ctx_t *ctx, const run_t *r, const char *best_yaml,
                              const char *best_dir, karst_ensemble_table_t *table) {
  karst_error_t err = KARST_SUCCESS;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  char hash[17];
  char *params = NULL, *mpath = karst_i_path_join(best_dir, "metrics.csv");
  if (!mpath) return no_memory(ctx);
  err = karst_scenario_load(ctx, best_yaml, &sc);
  if (!err) err = karst_file_hash(ctx, best_yaml, hash);
  if (err) goto cleanup;
  params = karst_ensemble_parameters_json(&sc);
  if (!params) {
    err = no_memory(ctx);
    goto cleanup;
  }
  karst_ensemble_hooks_t hooks;
  karst_ensemble_pipeline_t pipe;
  err = karst_ensemble_hooks_pipeline(ctx, &hooks, &pipe, &sc);
  if (err) goto cleanup;
  karst_ensemble_options_t eo;
  karst_ensemble_options_init(&eo);
  eo.n = r->opt->best_members;
  eo.seed = r->opt->seed;
  eo.nthreads = r->opt->nthreads;
  eo.use_mpi = r->opt->use_mpi;
  eo.scenario_path = best_yaml;
  eo.scenario_hash = hash;
  eo.parameters_json = params;
  karst_ctx_t ectx = *ctx;
  gen_progress_t gp = {ctx, "best fit"};
  if (ctx->progress) {
    ectx.progress = gen_progress;
    ectx.progress_user = &gp;
  }
  err = karst_ensemble_run(&ectx, best_dir, &eo, &hooks, NULL);
  if (err) {
    ctx->errcode = ectx.errcode;
    snprintf(ctx->errmsg, sizeof ctx->errmsg, "the best-fit ensemble: %.2000s", ectx.errmsg);
    goto cleanup;
  }
  err = karst_ensemble_table_read(ctx, mpath, table);
cleanup:
  free(params);
  free(mpath);
  karst_scenario_destroy(&sc);
  return err;
}

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/**
 * Run, or complete, a calibration in @p dir (calibrate.h, docs/calibration.md).
 *
 * @param ctx      context; ctx->interrupt stops cleanly (finished members are kept),
 *                 ctx->progress receives ("generation T", members done, members to do)
 * @param dir      output directory (created)
 * @param opt      scenario, survey, parameters, metrics, N, α, generations, seed ...
 * @param summary  what happened (may be NULL)
 * @return KARST_SUCCESS with every output written; KARST_EINTERRUPTED after an interrupt
 *         (run again to continue); KARST_EBUSY when another run holds DIR; the parser's
 *         code for a parameter that is not a numeric key of the scenario; the error of a
 *         failing member ("generation T: realisation I: ...").
 * Time complexity: (N + G (N − N_α)) realisations of the scenario / (threads × ranks),
 * plus O(G N N_α d) for the weights.
 */
karst_error_t karst_calibrate_run(karst_ctx_t *ctx, const char *dir,
                                  const karst_calibrate_options_t *opt,
                                  karst_calibrate_summary_t *summary) {
  karst_error_t err = KARST_SUCCESS;
  double t0 = now_seconds();
  run_t *r = calloc(1, sizeof *r);
  uint64_t **seeds = NULL;
  int n_seeds = 0, lock_fd = -1;
  char *lock_path = NULL, *p_post = NULL, *p_gen = NULL, *p_best = NULL, *p_bdir = NULL;
  char *p_report = NULL, *p_json = NULL;
  karst_ensemble_table_t prior, best_table;
  karst_ensemble_table_init(&prior);
  karst_ensemble_table_init(&best_table);
  karst_calibrate_summary_t s;
  memset(&s, 0, sizeof s);
  if (!r) return no_memory(ctx);
  karst_scenario_init(&r->base);
  r->opt = opt;
  r->dir = dir;
  /* Every rank checks the settings; they agree before anything else (a rank that stopped
   * here alone would leave the others waiting in a collective call). */
  r->ranks = karst_i_ensemble_world(opt->use_mpi, &r->rank);
  err = setup(ctx, r);
  {
    karst_error_t all = karst_i_ensemble_agree(r->ranks, err);
    if (all && !err)
      err = karst_set_error(ctx, all, "another rank could not set up the calibration (%s)",
                            karst_strerror(all));
    if (err) goto cleanup;
  }
  s.ranks = r->ranks;
  s.rank = r->rank;
  s.n_params = r->d;
  seeds = calloc((size_t)opt->generations + 1, sizeof *seeds);
  p_post = karst_i_path_join(dir, "posterior.csv");
  p_gen = karst_i_path_join(dir, "generations.csv");
  p_best = karst_i_path_join(dir, "best.yaml");
  p_bdir = karst_i_path_join(dir, "best");
  p_report = karst_i_path_join(dir, "report.html");
  p_json = karst_i_path_join(dir, "calibration.json");
  if (!seeds || !p_post || !p_gen || !p_best || !p_bdir || !p_report || !p_json) {
    err = no_memory(ctx);
    goto cleanup;
  }

  /* Rank 0 locks and checks the directory before anything in it is touched. */
  if (r->rank == 0) {
    err = karst_mkdir_p(ctx, dir);
    if (!err)
      err = karst_i_ensemble_lock(ctx, dir, KARST_I_CALIBRATE_LOCK, "calibration", &lock_fd,
                                  &lock_path);
    if (!err) err = karst_i_remove_stale_temporaries(ctx, dir);
    if (!err) err = check_or_write_key(ctx, r);
  }
  {
    karst_error_t all = karst_i_ensemble_agree(r->ranks, err);
    if (all && !err)
      err = karst_set_error(ctx, all, "rank 0 could not prepare %s: %s", dir, karst_strerror(all));
    if (err) goto cleanup;
  }

  s.stop = KARST_CALIBRATE_STOP_GENERATIONS;
  for (int g = 0; g <= opt->generations; g++) {
    karst_calibrate_generation_t info;
    err = run_generation(ctx, r, g, &info, &seeds[g], &prior);
    if (!err) {
      n_seeds = g + 1;
      err = history_push(ctx, r, &info, seeds);
    }
    karst_error_t all = karst_i_ensemble_agree(r->ranks, err);
    if (all && !err)
      err = karst_set_error(ctx, all, "another rank failed in generation %d (%s)", g,
                            karst_strerror(all));
    if (err) goto cleanup;
    if (r->rank == 0 && opt->on_generation) opt->on_generation(opt->on_generation_user, &info);
    s.generations = g;
    if (g > 0 && info.acceptance <= opt->min_acceptance) {
      s.stop = KARST_CALIBRATE_STOP_ACCEPTANCE;
      break;
    }
  }

  /* The posterior: the weighted population of the last generation. */
  const karst_i_calib_history_t *h = &r->hist;
  karst_int_t base = (karst_int_t)(h->n_gen - 1) * h->n_keep;
  double *x = malloc((size_t)h->n_keep * sizeof *x);
  if (!x) {
    err = no_memory(ctx);
    goto cleanup;
  }
  for (int k = 0; k < r->d && !err; k++) {
    for (karst_int_t j = 0; j < h->n_keep; j++)
      x[j] = h->values[(base + j) * r->d + k];
    err = karst_i_weighted_quantile(ctx, x, &h->weights[base], h->n_keep, 0.5, &s.median[k]);
    if (!err)
      err = karst_i_weighted_quantile(ctx, x, &h->weights[base], h->n_keep, KARST_CALIBRATE_CI_LOW,
                                      &s.low[k]);
    if (!err)
      err = karst_i_weighted_quantile(ctx, x, &h->weights[base], h->n_keep, KARST_CALIBRATE_CI_HIGH,
                                      &s.high[k]);
  }
  free(x);
  if (err) goto cleanup;
  s.tolerance = r->abc.tolerance;
  s.simulations = r->simulations;

  if (r->rank == 0) err = write_best(ctx, r, s.median, &s, p_best, p_bdir);
  {
    karst_error_t all = karst_i_ensemble_agree(r->ranks, err);
    if (all && !err) err = karst_set_error(ctx, all, "rank 0 could not write %s", p_best);
    if (err) goto cleanup;
  }
  if (opt->best_members > 0) {
    err = run_best(ctx, r, p_best, p_bdir, &best_table);
    if (err) goto cleanup;
  }
  s.computed = r->computed;
  s.wall_seconds = now_seconds() - t0;
  if (r->rank == 0) {
    karst_i_calib_view_t v;
    memset(&v, 0, sizeof v);
    v.opt = opt;
    v.dir = dir;
    v.d = r->d;
    v.params = r->params;
    v.file_value = r->file_value;
    v.n_sel = r->n_sel;
    for (int k = 0; k < r->n_sel; k++) {
      v.metric[k] = r->fields[r->sel[k]].key;
      v.survey[k] = r->survey[r->sel[k]];
      v.scale[k] = r->scale[k];
      v.scale_is_mad[k] = r->scale_is_mad[k];
    }
    v.hist = &r->hist;
    v.median = s.median;
    v.low = s.low;
    v.high = s.high;
    v.prior = &prior;
    v.best = opt->best_members > 0 ? &best_table : NULL;
    v.stop = s.stop;
    err = write_posterior(ctx, r, p_post);
    if (!err) err = write_generations(ctx, r, p_gen);
    if (!err) err = karst_i_calibrate_report(ctx, p_report, &v);
    if (!err) err = write_summary(ctx, r, p_json, &s);
  }
  {
    karst_error_t all = karst_i_ensemble_agree(r->ranks, err);
    if (all && !err) err = karst_set_error(ctx, all, "rank 0 could not write the outputs");
  }
cleanup:
  karst_i_ensemble_unlock(lock_fd, lock_path);
  s.wall_seconds = now_seconds() - t0;
  if (r) {
    s.computed = r->computed;
    s.simulations = r->simulations;
  }
  if (summary) *summary = s;
  for (int g = 0; seeds && g < n_seeds; g++)
    free(seeds[g]);
  free(seeds);
  karst_ensemble_table_destroy(&prior);
  karst_ensemble_table_destroy(&best_table);
  if (r) {
    history_destroy(&r->hist);
    karst_i_abc_destroy(&r->abc);
    karst_scenario_destroy(&r->base);
  }
  free(r);
  free(p_post);
  free(p_gen);
  free(p_best);
  free(p_bdir);
  free(p_report);
  free(p_json);
  return err;
}
