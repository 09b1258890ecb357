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
#include "karst/view.h"
#include "karst/vtk.h"

static karst_error_t pipe_realise(karst_ctx_t *ctx, void *user, uint64_t member_seed,
                                  karst_int_t index, karst_network_t *net) {
  const karst_ensemble_pipeline_t *p = user;
  (void)index; /* the member seed already encodes (base seed, index) */
  return karst_generate(ctx, p->sc, member_seed, 0, net, NULL, NULL);
}

/* The ParaView script beside @p file (view.h), showing it in @p role. */
static karst_error_t write_script(karst_ctx_t *ctx, const char *file, karst_view_role_t role) {
  char *script = karst_view_script_path(file);
  if (!script) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  karst_view_item_t item = {file, role, NULL};
  karst_error_t err = karst_view_write_script(ctx, script, script, &item, 1);
  free(script);
  return err;
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
  if (err) goto cleanup;
  err = write_script(ctx, vtp, KARST_VIEW_NETWORK);
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
  karst_error_t err = karst_vtk_write_pvd(ctx, path, n, files);
  return err ? err : write_script(ctx, path, KARST_VIEW_COLLECTION);
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
/* Parameters: the same members as run.json                                */
/* ------------------------------------------------------------------------ */
/**
 * The effective parameters of @p sc as the members of ensemble.json's
 * "parameters" object: exactly those of run.json (karst_generate_write_parameters),
 * so one realisation and an ensemble record a scenario the same way.
 * @return malloc'ed text, or NULL when out of memory.
 * Time complexity: O(size of the scenario).
 */
char *karst_ensemble_parameters_json(const karst_scenario_t *sc) {
  char *text = NULL;
  size_t len = 0;
  FILE *fp = open_memstream(&text, &len);
  if (!fp) return NULL;
  karst_generate_write_parameters(fp, sc);
  if (ferror(fp)) {
    fclose(fp);
    free(text);
    return NULL;
  }
  fclose(fp);
  return text;
}
