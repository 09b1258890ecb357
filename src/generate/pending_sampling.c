/* TEMPORARY weak placeholders for the sampling / graph / cost stages and the
 * scenario file hash (branches `sampling` and `scenario`); the real, strong
 * definitions replace them when those branches land. Remove this file then. */
#include "generate/pending_sampling.h"

__attribute__((weak)) karst_error_t karst_sampling_run(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                                       karst_rng_t *rng, karst_samples_t *out) {
  (void)sc, (void)rng, (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "sampling is not available yet");
}

__attribute__((weak)) karst_error_t karst_graph_build(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                                      const karst_samples_t *samples,
                                                      karst_graph_t *out) {
  (void)sc, (void)samples, (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "the sample graph is not available yet");
}

__attribute__((weak)) double karst_cost_lower_bound_per_metre(const karst_scenario_t *sc) {
  return sc->cost.w0 * (sc->n_prescribed > 0 ? sc->cost.prescribed : 1.0);
}

/* The scenario branch defines karst_file_hash (FNV-1a 64 of the file's bytes); this weak copy
 * lets run.json be written meanwhile. */
#include <stdio.h>
__attribute__((weak)) karst_error_t karst_file_hash(karst_ctx_t *ctx, const char *path,
                                                    char out[17]) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return karst_set_error(ctx, KARST_EIO, "%s: cannot open to hash it", path);
  uint64_t h = 0xcbf29ce484222325ULL;
  int c;
  while ((c = fgetc(fp)) != EOF)
    h = (h ^ (uint64_t)(unsigned char)c) * 0x100000001b3ULL;
  fclose(fp);
  snprintf(out, 17, "%016llx", (unsigned long long)h);
  return KARST_SUCCESS;
}
