/* The real generation pipeline plugged into the ensemble runner, and the
 * scenario parameters recorded in ensemble.json. */
#include <inttypes.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "ensemble/ensemble_internal.h"
#include "karst/generate.h"
#include "karst/metrics.h"
#include "karst/readers.h"
#include "karst/vtk.h"

static karst_error_t pipe_realise(karst_ctx_t *ctx, void *user, uint64_t member_seed,
                                  karst_int_t index, karst_network_t *net) {
  const karst_ensemble_pipeline_t *p = user;
  (void)index; /* the member seed already encodes (base seed, index) */
  return karst_generate(ctx, p->sc, member_seed, 0, net, NULL, NULL);
}

static karst_error_t pipe_write(karst_ctx_t *ctx, void *user, const char *dir,
                                const karst_network_t *net) {
  (void)user;
  karst_error_t err = KARST_SUCCESS;
  char *vtp = karst_i_path_join(dir, "network.vtp");
  char *prefix = karst_i_path_join(dir, "network");
  if (!vtp || !prefix) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  err = karst_vtk_write_network(ctx, vtp, net);
  if (err) goto cleanup;
  err = karst_write_karstnet(ctx, prefix, net);
cleanup:
  free(vtp);
  free(prefix);
  return err;
}

static karst_error_t pipe_measure(karst_ctx_t *ctx, void *user, const karst_network_t *net,
                                  double *values) {
  (void)user;
  karst_metrics_options_t mo;
  karst_metrics_t m;
  int nf = 0;
  karst_metrics_options_init(&mo);
  karst_error_t err = karst_metrics_compute(ctx, net, &mo, &m);
  if (err) return err;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  for (int k = 0; k < nf && k < KARST_ENSEMBLE_MAX_METRICS; k++)
    values[k] = karst_metric_value(&m, &f[k]);
  return KARST_SUCCESS;
}

static karst_error_t pipe_collection(karst_ctx_t *ctx, void *user, const char *path, int n,
                                     const char *const *files) {
  (void)user;
  return karst_vtk_write_pvd(ctx, path, n, files);
}

/**
 * Fill @p hooks with the real pipeline (see ensemble.h); the metric column
 * names are those of karst_metric_fields, kept in @p storage.
 * @return KARST_ERANGE when there are more than KARST_ENSEMBLE_MAX_METRICS metrics.
 * Time complexity: O(number of metrics).
 */
karst_error_t karst_ensemble_hooks_pipeline(karst_ctx_t *ctx, karst_ensemble_hooks_t *hooks,
                                            karst_ensemble_pipeline_t *storage,
                                            const karst_scenario_t *sc) {
  int nf = 0;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  memset(hooks, 0, sizeof *hooks);
  memset(storage, 0, sizeof *storage);
  if (nf > KARST_ENSEMBLE_MAX_METRICS)
    return karst_set_error(ctx, KARST_ERANGE, "%d metrics, at most %d are supported", nf,
                           KARST_ENSEMBLE_MAX_METRICS);
  storage->sc = sc;
  for (int k = 0; k < nf; k++)
    storage->names[k] = f[k].key;
  hooks->realise = pipe_realise;
  hooks->write = pipe_write;
  hooks->measure = pipe_measure;
  hooks->write_collection = pipe_collection;
  hooks->n_metrics = nf;
  hooks->metric_names = storage->names;
  hooks->user = storage;
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Parameters as flat JSON lines                                            */
/* ------------------------------------------------------------------------ */
typedef struct {
  char *s;
  size_t len, cap;
  int first, failed;
} sbuf_t;

static void sb_add(sbuf_t *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_add(sbuf_t *b, const char *fmt, ...) {
  if (b->failed) return;
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (n < 0) {
    b->failed = 1;
    return;
  }
  if (b->len + (size_t)n + 1 > b->cap) {
    size_t cap = (b->cap ? 2 * b->cap : 1024) + (size_t)n;
    char *s = realloc(b->s, cap);
    if (!s) {
      b->failed = 1;
      return;
    }
    b->s = s;
    b->cap = cap;
  }
  va_start(ap, fmt);
  vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
  va_end(ap);
  b->len += (size_t)n;
}

/* One `"key": value` line; the comma goes before every line but the first. */
static void key(sbuf_t *b, const char *k) {
  sb_add(b, "%s    \"%s\": ", b->first ? "" : ",\n", k);
  b->first = 0;
}
static void num(sbuf_t *b, const char *k, double v) {
  key(b, k);
  sb_add(b, "%.17g", v);
}
static void str(sbuf_t *b, const char *k, const char *v) {
  key(b, k);
  if (!v) {
    sb_add(b, "null");
    return;
  }
  sb_add(b, "\"");
  for (const unsigned char *p = (const unsigned char *)v; *p; p++) {
    if (*p == '"' || *p == '\\')
      sb_add(b, "\\%c", *p);
    else if (*p < 0x20)
      sb_add(b, "\\u%04x", *p);
    else
      sb_add(b, "%c", *p);
  }
  sb_add(b, "\"");
}
static void vec3(sbuf_t *b, const char *k, const double v[3]) {
  key(b, k);
  sb_add(b, "[%.17g, %.17g, %.17g]", v[0], v[1], v[2]);
}

/**
 * The effective parameters of @p sc as flat `"key": value` lines (see
 * ensemble.h); every value written with %.17g so it round-trips.
 * @return malloc'ed text, or NULL when out of memory.
 * Time complexity: O(key points + tunnel types).
 */
char *karst_ensemble_parameters_json(const karst_scenario_t *sc) {
  sbuf_t b = {NULL, 0, 0, 1, 0};
  int counts[3] = {0, 0, 0};
  for (int k = 0; k < sc->n_key_points; k++)
    if ((int)sc->key_points[k].type >= 0 && (int)sc->key_points[k].type < 3)
      counts[sc->key_points[k].type]++;
  str(&b, "name", sc->name);
  vec3(&b, "domain.min", sc->domain_min);
  vec3(&b, "domain.max", sc->domain_max);
  if (sc->terrain.is_grid)
    str(&b, "terrain.heightfield", sc->terrain.path);
  else
    num(&b, "terrain.elevation", sc->terrain.elevation);
  num(&b, "water_table", sc->water_table);
  num(&b, "key_points.sinks", counts[KARST_KEYPOINT_SINK]);
  num(&b, "key_points.springs", counts[KARST_KEYPOINT_SPRING]);
  num(&b, "key_points.waypoints", counts[KARST_KEYPOINT_WAYPOINT]);
  num(&b, "horizons", sc->n_horizons);
  num(&b, "fractures", sc->n_fractures);
  num(&b, "prescribed_paths", sc->n_prescribed);
  num(&b, "permeability.background", sc->permeability.background);
  num(&b, "cost.w0", sc->cost.w0);
  num(&b, "cost.horizon", sc->cost.horizon);
  num(&b, "cost.fracture", sc->cost.fracture);
  num(&b, "cost.permeability", sc->cost.permeability);
  num(&b, "cost.prescribed", sc->cost.prescribed);
  num(&b, "sampling.fill_radius", sc->sampling.fill_radius);
  num(&b, "sampling.feature_radius", sc->sampling.feature_radius);
  num(&b, "sampling.permeable_threshold", sc->sampling.permeable_threshold);
  num(&b, "sampling.feature_band", sc->sampling.feature_band);
  num(&b, "sampling.k", sc->sampling.k);
  num(&b, "sampling.max_samples", (double)sc->sampling.max_samples);
  num(&b, "skeleton.gamma", sc->gamma);
  num(&b, "amplification.steps", sc->amplification.steps);
  num(&b, "amplification.points", sc->amplification.points);
  num(&b, "amplification.dead_end_fraction", sc->amplification.dead_end_fraction);
  num(&b, "tortuosity", sc->tortuosity);
  num(&b, "classification.vertical_angle", sc->classification.vertical_angle);
  num(&b, "classification.water_table_band", sc->classification.water_table_band);
  num(&b, "classification.epikarst_depth", sc->classification.epikarst_depth);
  num(&b, "classification.chamber_resistance", sc->classification.chamber_resistance);
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    char k[64];
    snprintf(k, sizeof k, "classification.radius.%s", karst_tunnel_type_name(t));
    key(&b, k);
    sb_add(&b, "[%.17g, %.17g]", sc->classification.radius[t].min,
           sc->classification.radius[t].max);
  }
  sb_add(&b, "\n");
  if (b.failed) {
    free(b.s);
    return NULL;
  }
  return b.s;
}
