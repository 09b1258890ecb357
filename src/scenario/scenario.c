/* Scenario lifecycle and defaults. The YAML reader is not written yet. */
#include <stdlib.h>
#include <string.h>

#include "karst/scenario.h"

void karst_scenario_init(karst_scenario_t *sc) {
  memset(sc, 0, sizeof *sc);
  sc->domain_max[0] = sc->domain_max[1] = sc->domain_max[2] = 100.0;
  sc->terrain.elevation = 100.0;
  sc->permeability.background = 1.0;
  sc->cost.w0 = 1.0;
  sc->cost.horizon = 1.0;
  sc->cost.fracture = 1.0;
  sc->cost.permeability = 1.0;
  sc->cost.prescribed = 0.1;
  sc->sampling.fill_radius = 10.0;
  sc->sampling.feature_radius = 3.0;
  sc->sampling.permeable_threshold = 0.3;
  sc->sampling.feature_band = 1.0;
  sc->sampling.k = 40;
  sc->sampling.max_samples = 5000000;
  sc->gamma = 2.0;
  sc->tortuosity = 0.1;
  sc->classification.vertical_angle = 60.0;
  sc->classification.water_table_band = 5.0;
  sc->classification.epikarst_depth = 10.0;
  sc->classification.chamber_resistance = 0.05;
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    sc->classification.radius[t].min = 0.5;
    sc->classification.radius[t].max = 4.0;
  }
  sc->classification.radius[KARST_TUNNEL_EPIKARST].max = 0.5;
  sc->seed = 1;
  sc->realisations = 1;
}

static void free_perm(karst_perm_node_t *n) {
  for (int i = 0; i < n->n_children; i++) free_perm(&n->children[i]);
  free(n->children);
}

void karst_scenario_destroy(karst_scenario_t *sc) {
  free(sc->path);
  free(sc->name);
  free(sc->terrain.path);
  free(sc->terrain.z);
  free(sc->horizons);
  free(sc->fractures);
  if (sc->permeability.root) {
    free_perm(sc->permeability.root);
    free(sc->permeability.root);
  }
  free(sc->key_points);
  free(sc->prescribed);
  memset(sc, 0, sizeof *sc);
}

karst_error_t karst_scenario_load(karst_ctx_t *ctx, const char *path, karst_scenario_t *sc) {
  (void)sc;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: the scenario reader is not available yet", path);
}
