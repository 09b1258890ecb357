/* Unit tests build scenarios in code and change them between calls; these wrappers build the
 * geology of the scenario as it is at the moment of the call (karst_geology_create with seed 0,
 * realisation 0), ask it, and free it. */
#ifndef KARST_TEST_GEOLOGY_FIXTURE_H
#define KARST_TEST_GEOLOGY_FIXTURE_H
#include <stdio.h>
#include <stdlib.h>

#include "karst/cost.h"
#include "karst/geology.h"
#include "karst/graph.h"
#include "karst/sampling.h"

/* The geology of @p sc now; aborts the test run (with the message) if it cannot be built. */
static inline karst_geology_t *geo_make(const karst_scenario_t *sc) {
  karst_ctx_t c;
  karst_ctx_init(&c);
  karst_geology_t *g = NULL;
  if (karst_geology_create(&c, sc, 0, 0, &g) != KARST_SUCCESS) {
    fprintf(stderr, "geology of the test scenario: %s\n", c.errmsg);
    abort();
  }
  return g;
}

static inline double T_cost_edge(const karst_scenario_t *sc, const double a[3], const double b[3]) {
  karst_geology_t *g = geo_make(sc);
  double c = karst_cost_edge(g, a, b);
  karst_geology_free(g);
  return c;
}

static inline double T_cost_point(const karst_scenario_t *sc, const double p[3],
                                  const double d[3]) {
  karst_geology_t *g = geo_make(sc);
  double c = karst_cost_point(g, p, d);
  karst_geology_free(g);
  return c;
}

static inline double T_fracture_term(const karst_scenario_t *sc, const double d[3]) {
  karst_geology_t *g = geo_make(sc);
  double c = karst_cost_fracture_term(g, d);
  karst_geology_free(g);
  return c;
}

static inline int T_in_bedrock(const karst_scenario_t *sc, const double p[3]) {
  karst_geology_t *g = geo_make(sc);
  int r = karst_geology_in_bedrock(g, p);
  karst_geology_free(g);
  return r;
}

static inline int T_segment_in_bedrock(const karst_scenario_t *sc, const double a[3],
                                       const double b[3]) {
  karst_geology_t *g = geo_make(sc);
  int r = karst_geology_segment_in_bedrock(g, a, b);
  karst_geology_free(g);
  return r;
}

static inline karst_error_t T_graph_build(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                          const karst_samples_t *s, karst_graph_t *g) {
  karst_geology_t *geo = geo_make(sc);
  karst_error_t err = karst_graph_build(ctx, geo, s, g);
  karst_geology_free(geo);
  return err;
}

static inline karst_error_t T_sampling_run(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                           karst_rng_t *rng, karst_samples_t *s) {
  karst_geology_t *geo = geo_make(sc);
  karst_error_t err = karst_sampling_run(ctx, geo, rng, s);
  karst_geology_free(geo);
  return err;
}

/* The scenario's default water table: the horizontal plane at @p z. */
static inline void T_set_water_table(karst_scenario_t *sc, double z) {
  sc->water_table.given = 1;
  sc->water_table.elevation = z;
  sc->water_table.dip = sc->water_table.dip_direction = 0;
  sc->water_table.origin[0] = sc->water_table.origin[1] = 0;
}
#endif
