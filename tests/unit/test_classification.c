/* Classification (src/classification, Paris et al. 2021 §5.3, Fig. 11):
 * every cell of the decision table on hand-placed segments, the radius
 * ranges, the zone and vadose flags, the water-table distance, and the water
 * table of each edge's own spring. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "karst.h"
#include "test_util.h"

/* Terrain at 100 m, one spring at (1000, 0, 50) whose water table is the horizontal plane through
 * it (band ±5), epikarst 10 m, steep from 60°, a ghost-rock sphere of resistance 0 (radius 5) at
 * (500, 500, 30), background resistance 1. */
static void make_scenario(karst_scenario_t *sc, karst_perm_node_t *sphere) {
  karst_scenario_init(sc);
  sc->domain_max[0] = sc->domain_max[1] = 1000;
  sc->domain_max[2] = 100;
  sc->terrain.elevation = 100;
  sc->n_key_points = 1;
  sc->key_points = calloc(1, sizeof *sc->key_points);
  sc->key_points[0].type = KARST_KEYPOINT_SPRING;
  sc->key_points[0].p[0] = 1000, sc->key_points[0].p[2] = 50;
  memset(sphere, 0, sizeof *sphere);
  sphere->kind = KARST_PERM_SPHERE;
  sphere->resistance = 0;
  sphere->center[0] = 500, sphere->center[1] = 500, sphere->center[2] = 30;
  sphere->radius = 5;
  sc->permeability.root = sphere;
}

static karst_tunnel_type_t seg(const karst_scenario_t *sc, double x, double z, double dx,
                               double dz) {
  double a[3] = {x, 0, z}, b[3] = {x + dx, 0, z + dz};
  karst_geology_t *g = geo_make(sc);
  karst_tunnel_type_t t = karst_classification_type(g, 0, a, b);
  karst_geology_free(g);
  return t;
}

static karst_error_t run(karst_ctx_t *ctx, const karst_scenario_t *sc, karst_rng_t *r,
                         karst_network_t *net) {
  karst_geology_t *g = geo_make(sc);
  karst_error_t err = karst_classification_run(ctx, g, r, net);
  karst_geology_free(g);
  return err;
}

static void test_decision_table(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_perm_node_t sphere;
  make_scenario(&sc, &sphere);
  /* Each segment is 10 m long, centred at the stated elevation; tan 60° = 1.732. The water
   * table is at 50 m, the epiphreatic band 45-55 m. */
  assert_int_equal(seg(&sc, 0, 75, 10, 0), KARST_TUNNEL_CANYON);  /* vadose, horizontal */
  assert_int_equal(seg(&sc, 0, 70, 0, 10), KARST_TUNNEL_TUBE);    /* vadose, vertical (centre 75) */
  assert_int_equal(seg(&sc, 0, 53, 10, 0), KARST_TUNNEL_KEYHOLE); /* in the band, above W */
  assert_int_equal(seg(&sc, 0, 50, 10, 0), KARST_TUNNEL_PASSAGE); /* at W */
  assert_int_equal(seg(&sc, 0, 47, 10, 0), KARST_TUNNEL_PASSAGE); /* in the band, below W */
  assert_int_equal(seg(&sc, 0, 46, 0, 8), KARST_TUNNEL_TUBE);     /* in the band, vertical */
  assert_int_equal(seg(&sc, 0, 20, 10, 0), KARST_TUNNEL_TUBE);    /* phreatic, horizontal */
  assert_int_equal(seg(&sc, 0, 15, 0, 10), KARST_TUNNEL_TUBE);    /* phreatic, vertical */
  /* Epikarst: steep AND in the 10 m below the terrain (Paris et al. §5.3, "narrow vertical
   * conduits that start from the surface"). By hand: seg(x, z, dx, dz) runs from (x, 0, z) to
   * (x + dx, 0, z + dz), midpoint depth 100 − (z + dz / 2), angle atan(|dz| / |dx|). */
  assert_int_equal(seg(&sc, 0, 91, 0, 6), KARST_TUNNEL_EPIKARST); /* depth 6, 90° */
  assert_int_equal(seg(&sc, 0, 95, 10, 0), KARST_TUNNEL_CANYON);  /* depth 5, 0°: not epikarst */
  assert_int_equal(seg(&sc, 0, 97, 10, 1), KARST_TUNNEL_CANYON);  /* depth 2.5, 5.7° */
  assert_int_equal(seg(&sc, 0, 83, 0, 10), KARST_TUNNEL_TUBE);    /* depth 12, 90°: a shaft */
  assert_int_equal(seg(&sc, 0, 88, 10, 0), KARST_TUNNEL_CANYON);  /* depth 12, 0° */
  /* At the angle threshold near the surface: dz = tan 60° (+1e-12) over dx = 1, midpoint depth
   * 100 − (93 + 0.866) = 6.13, is epikarst; tan 59° over 1 m is gentle, a canyon. */
  assert_int_equal(seg(&sc, 0, 93, 1, tan(60.0 * M_PI / 180) + 1e-12), KARST_TUNNEL_EPIKARST);
  assert_int_equal(seg(&sc, 0, 93, 1, tan(59.0 * M_PI / 180)), KARST_TUNNEL_CANYON);
  double a[3] = {495, 500, 30}, b[3] = {505, 500, 30};
  karst_geology_t *g = geo_make(&sc);
  assert_int_equal(karst_classification_type(g, 0, a, b), KARST_TUNNEL_CHAMBER); /* ghost rock */
  karst_geology_free(g);
  /* Band edges: |z − W| ≤ 5 counts as the band; 5.5 m above is vadose, below phreatic. */
  assert_int_equal(seg(&sc, 0, 55, 10, 0), KARST_TUNNEL_KEYHOLE);
  assert_int_equal(seg(&sc, 0, 55.5, 10, 0), KARST_TUNNEL_CANYON);
  assert_int_equal(seg(&sc, 0, 44.5, 10, 0), KARST_TUNNEL_TUBE);
  /* A phreatic conduit within an inception horizon's radius is a soluble-bed conduit (bed). */
  sc.n_horizons = 1;
  sc.horizons = calloc(1, sizeof *sc.horizons);
  sc.horizons[0].elevation = 20, sc.horizons[0].radius = 5;
  assert_int_equal(seg(&sc, 0, 22, 10, 0), KARST_TUNNEL_BED);    /* 2 m from the horizon */
  assert_int_equal(seg(&sc, 0, 30, 10, 0), KARST_TUNNEL_TUBE);   /* 10 m from it */
  assert_int_equal(seg(&sc, 0, 75, 10, 0), KARST_TUNNEL_CANYON); /* vadose: no bed */
  /* Verticality threshold: 60° exactly is steep, 59° is not (dz/dx = tan θ). */
  assert_int_equal(seg(&sc, 0, 75, 1, tan(60.0 * M_PI / 180) + 1e-12), KARST_TUNNEL_TUBE);
  assert_int_equal(seg(&sc, 0, 75, 1, tan(59.0 * M_PI / 180)), KARST_TUNNEL_CANYON);
  /* Degenerate zero-length segment: gentle. */
  assert_int_equal(seg(&sc, 0, 20, 0, 0), KARST_TUNNEL_BED);
  assert_int_equal(seg(&sc, 0, 40, 0, 0), KARST_TUNNEL_TUBE);
  sc.permeability.root = NULL;
  karst_scenario_destroy(&sc);
}

/* Each edge is judged against the water table of its own spring (the "spring" edge attribute):
 * spring 0's table at 50 m, spring 1's dipping from 80 m at x = 0 by 45° to the east
 * (W = 80 − x). At x = 10 (W1 = 70) a horizontal segment at z = 60 is phreatic for spring 1
 * (a tube) and vadose for spring 0 (a canyon); the node distances follow each node's spring. */
static void test_own_water_table(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_perm_node_t sphere;
  make_scenario(&sc, &sphere);
  sc.n_key_points = 2;
  sc.key_points = realloc(sc.key_points, 2 * sizeof *sc.key_points);
  memset(&sc.key_points[1], 0, sizeof sc.key_points[1]);
  sc.key_points[1].type = KARST_KEYPOINT_SPRING;
  sc.key_points[1].p[0] = 70, sc.key_points[1].p[2] = 10;
  karst_surface_def_t *w = &sc.key_points[1].water_table;
  w->given = 1, w->elevation = 80, w->dip = 45, w->dip_direction = 90;
  w->origin[0] = 0, w->origin[1] = 0;
  karst_network_t net;
  karst_network_init(&net);
  karst_int_t a, b, c, d;
  karst_network_add_node(&net, 5, 0, 60, &a);
  karst_network_add_node(&net, 15, 0, 60, &b);
  karst_network_add_node(&net, 5, 1, 60, &c);
  karst_network_add_node(&net, 15, 1, 60, &d);
  karst_network_add_edge(&net, a, b, NULL);
  karst_network_add_edge(&net, c, d, NULL);
  double *es, *ns;
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_EDGE, "spring", 1, 1, &es), 0);
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_NODE, "spring", 1, 1, &ns), 0);
  es[0] = 1, es[1] = 0;
  ns[a] = ns[b] = 1, ns[c] = ns[d] = 0;
  karst_rng_t r;
  karst_rng_init(&r, 1, 6);
  assert_int_equal(run(&ctx, &sc, &r, &net), KARST_SUCCESS);
  const double *type = karst_network_attr_find(&net, KARST_ATTR_EDGE, "tunnel_type")->data;
  const double *zone = karst_network_attr_find(&net, KARST_ATTR_EDGE, "zone")->data;
  const double *wtd = karst_network_attr_find(&net, KARST_ATTR_NODE, "water_table_distance")->data;
  assert_int_equal((int)type[0], KARST_TUNNEL_TUBE);
  assert_int_equal((int)zone[0], KARST_ZONE_PHREATIC);
  assert_int_equal((int)type[1], KARST_TUNNEL_CANYON);
  assert_int_equal((int)zone[1], KARST_ZONE_VADOSE);
  assert_close(wtd[a], 60 - 75, 1e-9); /* W1(5) = 75 */
  assert_close(wtd[b], 60 - 65, 1e-9); /* W1(15) = 65 */
  assert_close(wtd[c], 10, 1e-12);     /* W0 = 50 */
  karst_network_destroy(&net);
  sc.permeability.root = NULL;
  karst_scenario_destroy(&sc);
}

static void test_run_radii(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_perm_node_t sphere;
  make_scenario(&sc, &sphere);
  karst_network_t net;
  karst_network_init(&net);
  /* 2000 horizontal phreatic segments (tubes) and one epikarst segment at the end. */
  const int n = 2000;
  for (int i = 0; i <= n; i++)
    karst_network_add_node(&net, i, 0, 20, NULL);
  for (int i = 0; i < n; i++)
    karst_network_add_edge(&net, i, i + 1, NULL);
  karst_int_t u, v;
  karst_network_add_node(&net, 0, 0, 92, &u);
  karst_network_add_node(&net, 0, 0, 98, &v);
  karst_network_add_edge(&net, u, v, NULL);
  karst_rng_t r;
  karst_rng_init(&r, 1, 6);
  sc.classification.radius_correlation = 0; /* independent draws, the paper's literal rule */
  assert_int_equal(run(&ctx, &sc, &r, &net), KARST_SUCCESS);
  const double *type = karst_network_attr_find(&net, KARST_ATTR_EDGE, "tunnel_type")->data;
  const double *rad = karst_network_attr_find(&net, KARST_ATTR_EDGE, "radius")->data;
  const double *vad = karst_network_attr_find(&net, KARST_ATTR_EDGE, "vadose")->data;
  const double *zone = karst_network_attr_find(&net, KARST_ATTR_EDGE, "zone")->data;
  const double *wtd = karst_network_attr_find(&net, KARST_ATTR_NODE, "water_table_distance")->data;
  double mean = 0, lo = INFINITY, hi = -INFINITY;
  for (int e = 0; e < n; e++) {
    assert_int_equal((int)type[e], KARST_TUNNEL_TUBE);
    assert_int_equal((int)vad[e], 0);
    assert_int_equal((int)zone[e], KARST_ZONE_PHREATIC);
    mean += rad[e] / n;
    lo = fmin(lo, rad[e]);
    hi = fmax(hi, rad[e]);
  }
  /* Uniform on [0.5, 4] (§5.3): mean 2.25, standard error 3.5/sqrt(12·2000) = 0.023; 0.1 is > 4 SE.
   */
  assert_close(mean, 2.25, 0.1);
  assert_true(lo >= 0.5 && hi <= 4.0);
  assert_true(lo < 0.6 && hi > 3.9);
  assert_int_equal((int)type[n], KARST_TUNNEL_EPIKARST);
  assert_close(rad[n], 0.5, 0); /* fixed 50 cm (§5.3) */
  assert_int_equal((int)vad[n], 1);
  assert_int_equal((int)zone[n], KARST_ZONE_VADOSE);
  assert_close(wtd[0], -30, 0);
  assert_close(wtd[v], 48, 0);
  /* Configurable ranges; a bad range is refused and named. */
  sc.classification.radius[KARST_TUNNEL_CANYON].min = 3;
  sc.classification.radius[KARST_TUNNEL_CANYON].max = 1;
  assert_int_equal(run(&ctx, &sc, &r, &net), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "canyon"));
  sc.classification.radius[KARST_TUNNEL_CANYON].max = 3;
  sc.classification.vertical_angle = 95;
  assert_int_equal(run(&ctx, &sc, &r, &net), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "95"));
  karst_network_destroy(&net);
  /* Empty network: nothing to do, no error. */
  sc.classification.vertical_angle = 60;
  karst_network_init(&net);
  assert_int_equal(run(&ctx, &sc, &r, &net), KARST_SUCCESS);
  karst_network_destroy(&net);
  sc.permeability.root = NULL;
  karst_scenario_destroy(&sc);
}

/* The correlated radius (classification.radius_correlation, after Frantz et al. 2021):
 * neighbouring segments have nearly equal radii, segments many correlation lengths apart are
 * unrelated, and the marginal stays uniform on [min, max]. Expected values from the field's
 * definition: Var(g(p) - g(p + h)) = 2 (1 - exp(-h^2 / (2 L^2))), 2e-4 for h = 2 m, L = 100 m,
 * so |Δu| <= φ(0) |Δg| < 0.4 × 5 × 0.014 and |Δr| < 0.1 m at 5 sigma (3.5 m range). */
static void test_run_radii_correlated(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_perm_node_t sphere;
  make_scenario(&sc, &sphere);
  sc.classification.radius_correlation = 100;
  karst_network_t net;
  karst_network_init(&net);
  /* a 4 km phreatic line of 2 m segments, then 3000 isolated segments 10 km apart */
  const int n = 2000, far = 3000;
  for (int i = 0; i <= n; i++)
    karst_network_add_node(&net, 2.0 * i, 0, 20, NULL);
  for (int i = 0; i < n; i++)
    karst_network_add_edge(&net, i, i + 1, NULL);
  for (int i = 0; i < far; i++) {
    karst_int_t u, v;
    double x = 1e4 * (i % 60), y = 1e4 * (1 + i / 60);
    karst_network_add_node(&net, x, y, 20, &u);
    karst_network_add_node(&net, x + 1, y, 20, &v);
    karst_network_add_edge(&net, u, v, NULL);
  }
  karst_rng_t r;
  karst_rng_init(&r, 3, 6);
  assert_int_equal(run(&ctx, &sc, &r, &net), KARST_SUCCESS);
  const double *rad = karst_network_attr_find(&net, KARST_ATTR_EDGE, "radius")->data;
  double maxstep = 0, lo = INFINITY, hi = -INFINITY;
  for (int e = 0; e + 1 < n; e++)
    maxstep = fmax(maxstep, fabs(rad[e + 1] - rad[e]));
  assert_true(maxstep < 0.1);
  /* far segments: uniform marginal (mean 2.25, sd 3.5/sqrt(12) = 1.01; with 3000 nearly
   * independent values the mean is within 0.15 and both ends of the range are reached) and
   * no correlation between successive far segments (|r| < 0.2, about 4.5 standard errors of the
   * random-Fourier-feature estimate 1/sqrt(2 x 256)). */
  double mean = 0, sxy = 0, sxx = 0;
  for (int i = 0; i < far; i++) {
    double x = rad[n + i];
    mean += x / far;
    lo = fmin(lo, x);
    hi = fmax(hi, x);
  }
  for (int i = 0; i + 1 < far; i++) {
    sxy += (rad[n + i] - mean) * (rad[n + i + 1] - mean);
    sxx += (rad[n + i] - mean) * (rad[n + i] - mean);
  }
  assert_close(mean, 2.25, 0.15);
  assert_true(lo >= 0.5 && hi <= 4.0);
  assert_true(lo < 0.7 && hi > 3.8);
  assert_true(fabs(sxy / sxx) < 0.2);
  /* the same stream gives the same radii */
  karst_network_t copy;
  assert_int_equal(karst_network_copy(&copy, &net), 0);
  karst_rng_init(&r, 3, 6);
  assert_int_equal(run(&ctx, &sc, &r, &copy), KARST_SUCCESS);
  const double *rad2 = karst_network_attr_find(&copy, KARST_ATTR_EDGE, "radius")->data;
  for (karst_int_t e = 0; e < net.n_edges; e++)
    assert_true(rad2[e] == rad[e]);
  karst_network_destroy(&copy);
  karst_network_destroy(&net);
  sc.permeability.root = NULL;
  karst_scenario_destroy(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_decision_table),
      cmocka_unit_test(test_own_water_table),
      cmocka_unit_test(test_run_radii),
      cmocka_unit_test(test_run_radii_correlated),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
