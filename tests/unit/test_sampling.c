/* Adaptive Poisson sampling (Paris et al. 2021, §4.1): the Poisson property
 * per source class, placement rules, order, determinism and errors. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "karst.h"
#include "test_util.h"

static void add_key(karst_scenario_t *sc, const char *name, double x, double y, double z) {
  sc->key_points =
      realloc(sc->key_points, sizeof(karst_keypoint_t) * (size_t)(sc->n_key_points + 1));
  karst_keypoint_t *k = &sc->key_points[sc->n_key_points++];
  memset(k, 0, sizeof *k);
  snprintf(k->name, sizeof k->name, "%s", name);
  if (!strcmp(name, "spring")) k->type = KARST_KEYPOINT_SPRING; /* its water table is sampled */
  k->p[0] = x, k->p[1] = y, k->p[2] = z;
}

static void add_horizon(karst_scenario_t *sc, double elev, double dip, double dipdir) {
  sc->horizons = realloc(sc->horizons, sizeof(karst_horizon_t) * (size_t)(sc->n_horizons + 1));
  karst_horizon_t *h = &sc->horizons[sc->n_horizons++];
  memset(h, 0, sizeof *h);
  h->elevation = elev, h->radius = 5, h->dip = dip, h->dip_direction = dipdir;
  h->origin[0] = 50, h->origin[1] = 40;
}

/* 100 x 80 x 60 m box under a flat terrain at 50 m, a horizon at 20 m, the
 * water table at 32 m, a permeable sphere, three key points. */
static void scenario(karst_scenario_t *sc) {
  karst_scenario_init(sc);
  sc->domain_min[0] = 0, sc->domain_min[1] = 0, sc->domain_min[2] = 0;
  sc->domain_max[0] = 100, sc->domain_max[1] = 80, sc->domain_max[2] = 60;
  sc->terrain.elevation = 50;
  T_set_water_table(sc, 32);
  sc->sampling.feature_radius = 3;
  sc->sampling.fill_radius = 8;
  sc->sampling.feature_band = 1;
  sc->sampling.permeable_threshold = 0.3;
  add_horizon(sc, 20, 0, 0);
  add_key(sc, "sink1", 10, 10, 45);
  add_key(sc, "spring", 90, 70, 5);
  add_key(sc, "w1", 50.5, 40.25, 30.125);
  sc->permeability.background = 1;
  sc->permeability.root = calloc(1, sizeof(karst_perm_node_t));
  karst_perm_node_t *s = sc->permeability.root;
  s->kind = KARST_PERM_SPHERE, s->center[0] = 70, s->center[1] = 30, s->center[2] = 10;
  s->radius = 6, s->falloff = 2, s->resistance = 0.0;
}

static double dist(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

/* Checks every pair (O(n²), independent of the grids): feature samples
 * (any feature class, key points included) keep r_f from each other, fill
 * samples keep r_c, and fill keeps min(r_f, r_c) from features. */
static void check_poisson(const karst_scenario_t *sc, const karst_samples_t *s) {
  double rf = sc->sampling.feature_radius, rc = sc->sampling.fill_radius, rm = fmin(rf, rc);
  for (karst_int_t i = 0; i < s->n; i++)
    for (karst_int_t j = i + 1; j < s->n; j++) {
      int a = s->source[i], b = s->source[j];
      if (a == KARST_SAMPLE_KEYPOINT && b == KARST_SAMPLE_KEYPOINT) continue;
      double d = dist(s->xyz + 3 * i, s->xyz + 3 * j), need;
      if (a == KARST_SAMPLE_FILL && b == KARST_SAMPLE_FILL)
        need = rc;
      else if (a == KARST_SAMPLE_FILL || b == KARST_SAMPLE_FILL)
        need = rm;
      else
        need = rf;
      if (!(d >= need)) {
        print_error("samples %lld (%s) and %lld (%s) are %g m apart, need %g\n", (long long)i,
                    karst_sample_source_name(a), (long long)j, karst_sample_source_name(b), d,
                    need);
        fail();
      }
    }
}

static void test_sampling_rules(void **state) {
  (void)state;
  karst_scenario_t sc;
  scenario(&sc);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 11, 3);
  karst_samples_t s;
  karst_samples_init(&s);
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
  /* Key points first, exact, in order. */
  assert_int_equal(s.n_key_points, 3);
  for (int i = 0; i < 3; i++) {
    assert_int_equal(s.source[i], KARST_SAMPLE_KEYPOINT);
    assert_memory_equal(s.xyz + 3 * i, sc.key_points[i].p, 3 * sizeof(double));
  }
  int count[KARST_SAMPLE_SOURCE_COUNT] = {0};
  for (karst_int_t i = 0; i < s.n; i++) {
    const double *p = s.xyz + 3 * i;
    count[s.source[i]]++;
    if (i >= 3) assert_int_not_equal(s.source[i], KARST_SAMPLE_KEYPOINT);
    for (int a = 0; a < 3; a++)
      assert_true(p[a] >= sc.domain_min[a] && p[a] <= sc.domain_max[a]);
    assert_true(p[2] < 50.0);
    if (s.source[i] == KARST_SAMPLE_HORIZON) assert_true(fabs(p[2] - 20) <= 1.0);
    if (s.source[i] == KARST_SAMPLE_WATER_TABLE) assert_true(fabs(p[2] - 32) <= 1.0);
    if (s.source[i] == KARST_SAMPLE_PERMEABILITY)
      assert_true(karst_permeability_eval(&sc.permeability, p) < 0.3);
  }
  /* Layer of 100 x 80 m, 2 m thick, r = 3. Upper bound (any r-separated set):
   * xy projections are >= sqrt(3² − 2²) = 2.24 m apart, so at most
   * 8000 · 0.9069 / (π 1.118²) ≈ 1850 (+ border). A 2-D saturated random
   * packing alone holds ≈ 0.55 / r² per m² ≈ 490 (Lagae & Dutré 2008) and
   * the slab's thickness only adds room; measured: 776. */
  assert_true(count[KARST_SAMPLE_HORIZON] > 490 && count[KARST_SAMPLE_HORIZON] < 1900);
  assert_true(count[KARST_SAMPLE_WATER_TABLE] > 490 && count[KARST_SAMPLE_WATER_TABLE] < 1900);
  /* Sphere of radius 6 + part of the falloff where π < 0.3: ~ 1000 m³ at
   * r = 3 gives tens of samples. */
  assert_true(count[KARST_SAMPLE_PERMEABILITY] > 10);
  assert_true(count[KARST_SAMPLE_FILL] > 100);
  check_poisson(&sc, &s);
  /* Coverage: a maximal sampling leaves no point of the bedrock farther than
   * r_c from a sample; with bounded darts, at least 99 % of random points
   * (measured 99.96 % with 5000 points). */
  int covered = 0, trials = 2000;
  for (int t = 0; t < trials; t++) {
    double p[3] = {karst_rng_uniform_range(&rng, 0, 100), karst_rng_uniform_range(&rng, 0, 80),
                   karst_rng_uniform_range(&rng, 0, 50)};
    for (karst_int_t i = 0; i < s.n; i++)
      if (dist(p, s.xyz + 3 * i) < sc.sampling.fill_radius) {
        covered++;
        break;
      }
  }
  assert_true(covered >= 0.99 * trials);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* sampling.refine: a feature left out of the list gets no sample of its own (its room is
 * filled at fill_radius instead); the named ones are sampled as by default; the key points
 * are always first; every pair keeps its distance (check_poisson). */
static void test_sampling_refine(void **state) {
  (void)state;
  static const unsigned masks[] = {0,
                                   KARST_REFINE_HORIZONS,
                                   KARST_REFINE_WATER_TABLE,
                                   KARST_REFINE_PERMEABILITY,
                                   KARST_REFINE_HORIZONS | KARST_REFINE_PERMEABILITY,
                                   KARST_REFINE_ALL};
  static const struct {
    unsigned bit;
    karst_sample_source_t src;
    int least; /* named: as test_sampling_rules' lower bounds */
  } feats[] = {{KARST_REFINE_HORIZONS, KARST_SAMPLE_HORIZON, 490},
               {KARST_REFINE_WATER_TABLE, KARST_SAMPLE_WATER_TABLE, 490},
               {KARST_REFINE_PERMEABILITY, KARST_SAMPLE_PERMEABILITY, 10}};
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_int_t n_none = 0, n_all = 0;
  for (size_t m = 0; m < sizeof masks / sizeof masks[0]; m++) {
    karst_scenario_t sc;
    scenario(&sc);
    sc.sampling.refine = masks[m];
    karst_rng_t rng;
    karst_rng_init(&rng, 11, 3);
    karst_samples_t s;
    karst_samples_init(&s);
    assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
    int count[KARST_SAMPLE_SOURCE_COUNT] = {0};
    for (karst_int_t i = 0; i < s.n; i++)
      count[s.source[i]]++;
    assert_int_equal(count[KARST_SAMPLE_KEYPOINT], 3);
    for (int i = 0; i < 3; i++)
      assert_memory_equal(s.xyz + 3 * i, sc.key_points[i].p, 3 * sizeof(double));
    for (size_t f = 0; f < 3; f++) {
      if (masks[m] & feats[f].bit)
        assert_true(count[feats[f].src] > feats[f].least);
      else
        assert_int_equal(count[feats[f].src], 0);
    }
    assert_true(count[KARST_SAMPLE_FILL] > 100);
    check_poisson(&sc, &s);
    if (masks[m] == 0) n_none = s.n;
    if (masks[m] == KARST_REFINE_ALL) n_all = s.n;
    karst_samples_destroy(&s);
    karst_scenario_destroy(&sc);
  }
  /* The fine layers hold more samples than the fill they displace (r_f = 3 against r_c = 8). */
  assert_true(n_all > n_none + 1000);
}

/* Same stream: identical samples; another stream: different ones. */
static void test_sampling_determinism(void **state) {
  (void)state;
  karst_scenario_t sc;
  scenario(&sc);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_samples_t s[3];
  for (int r = 0; r < 3; r++) {
    karst_rng_t rng;
    karst_rng_init(&rng, 5, r == 2 ? 1 : 0);
    karst_samples_init(&s[r]);
    assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s[r]), KARST_SUCCESS);
  }
  assert_int_equal(s[0].n, s[1].n);
  assert_memory_equal(s[0].xyz, s[1].xyz, sizeof(double) * 3 * (size_t)s[0].n);
  assert_memory_equal(s[0].source, s[1].source, (size_t)s[0].n);
  karst_int_t m = s[0].n < s[2].n ? s[0].n : s[2].n;
  assert_true(s[0].n != s[2].n ||
              memcmp(s[0].xyz + 9, s[2].xyz + 9, sizeof(double) * 3 * (size_t)(m - 3)) != 0);
  /* Key points are the same whatever the stream. */
  assert_memory_equal(s[0].xyz, s[2].xyz, sizeof(double) * 9);
  for (int r = 0; r < 3; r++)
    karst_samples_destroy(&s[r]);
  karst_scenario_destroy(&sc);
}

/* The fill runs in parallel by tiles with their own derived streams: 1, 2
 * and 4 threads give byte-identical samples (here about 240 tiles of the
 * fill grid), which still satisfy every distance rule. */
static void test_sampling_threads(void **state) {
  (void)state;
  karst_scenario_t sc;
  scenario(&sc);
  sc.sampling.fill_radius = 3;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_samples_t s[3];
  const int threads[3] = {1, 2, 4};
  for (int t = 0; t < 3; t++) {
    karst_rng_t rng;
    karst_rng_init(&rng, 11, 0);
    karst_samples_init(&s[t]);
    ctx.nthreads = threads[t];
    assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s[t]), KARST_SUCCESS);
  }
  for (int t = 1; t < 3; t++) {
    assert_int_equal(s[0].n, s[t].n);
    assert_memory_equal(s[0].xyz, s[t].xyz, sizeof(double) * 3 * (size_t)s[0].n);
    assert_memory_equal(s[0].source, s[t].source, (size_t)s[0].n);
  }
  assert_true(s[0].n > 5000);
  check_poisson(&sc, &s[0]);
  for (int t = 0; t < 3; t++)
    karst_samples_destroy(&s[t]);
  karst_scenario_destroy(&sc);
}

/* The Morton key of p in the domain box as docs/generation.md and sampling.c define it (each
 * coordinate quantised to 21 bits, x's bit b at bit 3b, y's at 3b + 1, z's at 3b + 2), written
 * bit by bit here: an independent form of the sampler's spread-and-or. */
static uint64_t morton_key(const karst_scenario_t *sc, const double p[3]) {
  uint64_t key = 0;
  for (int a = 0; a < 3; a++) {
    double f = (p[a] - sc->domain_min[a]) / (sc->domain_max[a] - sc->domain_min[a]);
    f = f < 0 ? 0 : (f > 1 ? 1 : f);
    uint64_t q = (uint64_t)(f * 2097151.0);
    for (int b = 0; b < 21; b++)
      key |= ((q >> b) & 1) << (3 * b + a);
  }
  return key;
}

/* Runs of more than 65 536 samples of one source are put in Morton order on the threads (a
 * radix sort whose passes split the run between them): 1 and 3 threads give the same samples,
 * and within each source's run the keys, recomputed independently, never decrease. */
static void test_sampling_morton_threads(void **state) {
  (void)state;
  karst_scenario_t sc;
  scenario(&sc);
  sc.sampling.fill_radius = 1.05;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_samples_t s[2];
  const int threads[2] = {1, 3};
  for (int t = 0; t < 2; t++) {
    karst_rng_t rng;
    karst_rng_init(&rng, 5, 0);
    karst_samples_init(&s[t]);
    ctx.nthreads = threads[t];
    assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s[t]), KARST_SUCCESS);
  }
  assert_int_equal(s[0].n, s[1].n);
  assert_memory_equal(s[0].xyz, s[1].xyz, sizeof(double) * 3 * (size_t)s[0].n);
  assert_memory_equal(s[0].source, s[1].source, (size_t)s[0].n);
  karst_int_t fill = 0;
  for (karst_int_t i = s[0].n_key_points; i < s[0].n; i++) {
    fill += s[0].source[i] == KARST_SAMPLE_FILL;
    if (i > s[0].n_key_points && s[0].source[i] == s[0].source[i - 1])
      assert_true(morton_key(&sc, s[0].xyz + 3 * (i - 1)) <= morton_key(&sc, s[0].xyz + 3 * i));
  }
  assert_true(fill > 65536); /* the threaded sort ran */
  for (int t = 0; t < 2; t++)
    karst_samples_destroy(&s[t]);
  karst_scenario_destroy(&sc);
}

/* Dipping horizon under a tilted grid terrain; no key points; water table
 * below the box (no water-table samples); prescribed path samples. */
static void test_sampling_dip_grid_prescribed(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.domain_max[0] = 100, sc.domain_max[1] = 80, sc.domain_max[2] = 60;
  T_set_water_table(&sc, -50);
  sc.sampling.feature_radius = 3, sc.sampling.fill_radius = 8, sc.sampling.feature_band = 1.5;
  add_horizon(&sc, 25, 15, 120);
  /* Terrain plane z = 30 + 0.2 x on a 5 x 5 grid of 25 m cells (exact in bilinear). */
  sc.terrain.is_grid = 1, sc.terrain.ncols = 5, sc.terrain.nrows = 5, sc.terrain.cellsize = 25;
  sc.terrain.z = malloc(25 * sizeof(double));
  for (int j = 0; j < 5; j++)
    for (int i = 0; i < 5; i++)
      sc.terrain.z[j * 5 + i] = 30 + 0.2 * 25 * i;
  add_key(&sc, "a", 10, 40, 20);
  add_key(&sc, "b", 90, 40, 20);
  sc.n_prescribed = 1;
  sc.prescribed = calloc(1, sizeof(karst_prescribed_path_t));
  sc.prescribed[0].a = 0, sc.prescribed[0].b = 1;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 2, 0);
  karst_samples_t s;
  karst_samples_init(&s);
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
  int nh = 0, np = 0;
  for (karst_int_t i = 0; i < s.n; i++) {
    const double *p = s.xyz + 3 * i;
    assert_true(p[2] < 30 + 0.2 * p[0]);
    assert_int_not_equal(s.source[i], KARST_SAMPLE_WATER_TABLE);
    if (s.source[i] == KARST_SAMPLE_HORIZON) {
      nh++;
      assert_true(fabs(p[2] - karst_horizon_elevation(&sc.horizons[0], p[0], p[1])) <= 1.5);
    }
    if (s.source[i] == KARST_SAMPLE_PRESCRIBED) {
      np++;
      assert_close(p[1], 40, 1e-12);
      assert_close(p[2], 20, 1e-12);
    }
  }
  assert_true(nh > 200);
  /* 80 m at spacing >= 3 m: floor(80/3) = 26 intervals, 25 interior points. */
  assert_int_equal(np, 25);
  check_poisson(&sc, &s);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* Degenerate inputs: no horizon (none sampled), a single key point in a box
 * smaller than the fill radius, and clear errors. */
static void test_sampling_degenerate(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 1, 0);
  karst_scenario_t sc;
  karst_samples_t s;
  karst_samples_init(&s);

  karst_scenario_init(&sc); /* 100 m box, flat terrain at 100 m, water table at 0 */
  sc.domain_max[2] = 99;
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
  assert_int_equal(s.n_key_points, 0);
  for (karst_int_t i = 0; i < s.n; i++)
    assert_int_not_equal(s.source[i], KARST_SAMPLE_HORIZON);
  assert_true(s.n > 100);
  karst_scenario_destroy(&sc);

  karst_scenario_init(&sc);
  sc.domain_max[0] = sc.domain_max[1] = sc.domain_max[2] = 1;
  T_set_water_table(&sc, -10);
  add_key(&sc, "only", 0.5, 0.5, 0.5);
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
  assert_true(s.n >= 1 && s.n_key_points == 1);
  assert_int_equal(s.source[0], KARST_SAMPLE_KEYPOINT);
  karst_scenario_destroy(&sc);

  /* A domain entirely above the terrain: error, output unchanged. */
  karst_int_t before = s.n;
  karst_scenario_init(&sc);
  sc.domain_min[2] = 150, sc.domain_max[2] = 200;
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "entirely above the terrain"));
  assert_int_equal(s.n, before);
  karst_scenario_destroy(&sc);

  /* A key point above the terrain is named. */
  karst_scenario_init(&sc);
  sc.terrain.elevation = 50;
  add_key(&sc, "sinkhole7", 10, 10, 70);
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "sinkhole7"));
  karst_scenario_destroy(&sc);

  /* max_samples respected with a clear error. */
  karst_scenario_init(&sc);
  sc.sampling.max_samples = 500;
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "max_samples = 500"));
  karst_scenario_destroy(&sc);

  /* Invalid radius, empty box axis. */
  karst_scenario_init(&sc);
  sc.sampling.fill_radius = 0;
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "fill_radius"));
  sc.sampling.fill_radius = 10;
  sc.domain_max[1] = sc.domain_min[1];
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_EINVAL);
  karst_scenario_destroy(&sc);
  assert_int_equal(s.n, before);
  karst_samples_destroy(&s);
  assert_string_equal(karst_sample_source_name(KARST_SAMPLE_WATER_TABLE), "water_table");
  assert_string_equal(karst_sample_source_name((karst_sample_source_t)99), "unknown");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sampling_rules),
      cmocka_unit_test(test_sampling_refine),
      cmocka_unit_test(test_sampling_determinism),
      cmocka_unit_test(test_sampling_threads),
      cmocka_unit_test(test_sampling_morton_threads),
      cmocka_unit_test(test_sampling_dip_grid_prescribed),
      cmocka_unit_test(test_sampling_degenerate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
