/* The geological model (src/geology): Fisher poles and tensors, exclusion-zone geometry,
 * insoluble strata, fault and fracture-disc cost terms, discrete fracture networks, and the
 * routed costs of the two-stage routing (A* against Dijkstra on them). Expected values are
 * derived by hand in each test's comment. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "geology/geology_internal.h"
#include "geology_fixture.h"
#include "graph_fixture.h"
#include "karst.h"
#include "test_util.h"

/* A 100 m cube under a flat terrain at 100 m, unit base cost, no other cost term. */
static void plain(karst_scenario_t *sc) {
  karst_scenario_init(sc);
  sc->cost.horizon = 0, sc->cost.fracture = 0, sc->cost.permeability = 0;
}

/* κ → ∞: the draws are the pole; finite κ: the sample mean of cos θ matches A(κ) = coth κ − 1/κ
 * (Fisher, Lewis & Embleton 1987, eq. 4.22) within 4 standard errors, the azimuth is uniform (the
 * mean transverse component vanishes), and the tensor matches the sample second moment. */
static void test_fisher(void **state) {
  (void)state;
  double mu[3];
  karst_plane_normal(30, 60, mu);
  karst_rng_t r;
  karst_rng_init(&r, 5, 0);
  for (int i = 0; i < 1000; i++) {
    double n[3];
    karst_i_fisher_draw(&r, mu, 1e12, n);
    double c = n[0] * mu[0] + n[1] * mu[1] + n[2] * mu[2];
    assert_true(c > 1 - 1e-9);           /* angle below 4.5e-5 rad */
    karst_i_fisher_draw(&r, mu, 0.0, n); /* 0: no dispersion */
    assert_memory_equal(n, mu, sizeof n);
  }
  const double kappa = 20.0, A = 1.0 / tanh(kappa) - 1.0 / kappa;
  const int N = 200000;
  double sum = 0, sum2 = 0, tx = 0, M[9] = {0};
  for (int i = 0; i < N; i++) {
    double n[3];
    karst_i_fisher_draw(&r, mu, kappa, n);
    double c = n[0] * mu[0] + n[1] * mu[1] + n[2] * mu[2];
    sum += c, sum2 += c * c;
    tx += n[0] - c * mu[0];
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++)
        M[3 * a + b] += n[a] * n[b] / N;
    assert_close(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-12);
  }
  double mean = sum / N, sd = sqrt(sum2 / N - mean * mean);
  assert_close(mean, A, 4 * sd / sqrt(N));
  assert_close(tx / N, 0.0, 4.0 / sqrt(N));
  double T[9];
  karst_i_fisher_tensor(mu, kappa, T);
  for (int i = 0; i < 9; i++)
    assert_close(T[i], M[i], 5e-3);
  /* κ = ∞ tensor: μμᵀ exactly; trace 1 always. */
  karst_i_fisher_tensor(mu, INFINITY, T);
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++)
      assert_close(T[3 * a + b], mu[a] * mu[b], 1e-15);
  karst_i_fisher_tensor(mu, 0.5, T);
  assert_close(T[0] + T[4] + T[8], 1.0, 1e-14);
}

/* A dispersed family attracts less: for a vertical N–S plane (pole east), an east-going edge
 * costs w E[(n·x)²] = w c with c = 1 − 2A(κ)/κ, and a north-going one w (1 − c)/2. */
static void test_dispersed_fracture_term(void **state) {
  (void)state;
  karst_scenario_t sc;
  plain(&sc);
  sc.cost.fracture = 1;
  sc.n_fractures = 1;
  sc.fractures = calloc(1, sizeof *sc.fractures);
  sc.fractures[0].dip_direction = 90, sc.fractures[0].dip = 90, sc.fractures[0].weight = 2;
  const double x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
  assert_close(T_fracture_term(&sc, x), 2.0, 1e-12);
  assert_close(T_fracture_term(&sc, y), 0.0, 1e-12);
  sc.fractures[0].kappa = 10;
  double A = 1 / tanh(10.0) - 0.1, c = 1 - 2 * A / 10;
  assert_close(T_fracture_term(&sc, x), 2 * c, 1e-12);
  assert_close(T_fracture_term(&sc, y), 2 * (1 - c) / 2, 1e-12);
  /* The lower bound: λmin(w T) = w (1 − c)/2 (the transverse eigenvalue), plus w0. */
  assert_close(karst_cost_lower_bound_per_metre(&sc),
               (1 + 2 * (1 - c) / 2) * (1 - KARST_COST_LB_MARGIN), 1e-12);
  karst_scenario_destroy(&sc);
}

/* Exclusion zones: points and segments against a box, a sphere and an L-shaped prism, by hand. */
static void test_exclusions(void **state) {
  (void)state;
  karst_exclusion_t box = {.kind = KARST_EXCLUSION_BOX, .min = {10, 10, 10}, .max = {20, 20, 20}};
  const double in[3] = {15, 15, 15}, out[3] = {25, 15, 15}, edge[3] = {20, 15, 15};
  assert_true(karst_i_point_in_exclusion(&box, in));
  assert_true(karst_i_point_in_exclusion(&box, edge)); /* closed */
  assert_false(karst_i_point_in_exclusion(&box, out));
  const double a[3] = {0, 15, 15}, b[3] = {30, 15, 15}, c[3] = {0, 25, 15}, d[3] = {30, 25, 15};
  assert_true(karst_i_segment_hits_exclusion(&box, a, b));  /* straight through */
  assert_false(karst_i_segment_hits_exclusion(&box, c, d)); /* passes 5 m north */
  const double e[3] = {0, 0, 15}, f[3] = {30, 30, 15};      /* the diagonal crosses */
  assert_true(karst_i_segment_hits_exclusion(&box, e, f));
  const double g[3] = {21, 0, 15}, h[3] = {40, 30, 15}; /* east of the box all along */
  assert_false(karst_i_segment_hits_exclusion(&box, g, h));

  karst_exclusion_t sph = {.kind = KARST_EXCLUSION_SPHERE, .center = {50, 50, 50}, .radius = 10};
  const double s0[3] = {30, 59, 50}, s1[3] = {70, 59, 50}, s2[3] = {30, 61, 50},
               s3[3] = {70, 61, 50};
  assert_true(karst_i_segment_hits_exclusion(&sph, s0, s1));  /* 9 m from the centre */
  assert_false(karst_i_segment_hits_exclusion(&sph, s2, s3)); /* 11 m */
  const double s4[3] = {30, 50, 50}, s5[3] = {39, 50, 50};    /* stops 1 m short */
  assert_false(karst_i_segment_hits_exclusion(&sph, s4, s5));

  /* L-shaped prism: (0,0) (20,0) (20,10) (10,10) (10,20) (0,20), z in [0, 5]. The notch
   * (15, 15) is outside; a segment across the notch's mouth from (15, 12) to (12, 15) stays
   * outside, one from (15, 15) to (5, 5) enters. */
  double poly[12] = {0, 0, 20, 0, 20, 10, 10, 10, 10, 20, 0, 20};
  karst_exclusion_t pr = {
      .kind = KARST_EXCLUSION_PRISM, .n_vertices = 6, .polygon = poly, .bottom = 0, .top = 5};
  const double n1[3] = {15, 15, 2}, n2[3] = {5, 5, 2}, n3[3] = {15, 12, 2}, n4[3] = {12, 15, 2};
  assert_false(karst_i_point_in_exclusion(&pr, n1));
  assert_true(karst_i_point_in_exclusion(&pr, n2));
  assert_true(karst_i_segment_hits_exclusion(&pr, n1, n2));
  assert_false(karst_i_segment_hits_exclusion(&pr, n3, n4));
  const double hi1[3] = {5, 5, 6}, hi2[3] = {15, 5, 9}; /* above the prism */
  assert_false(karst_i_segment_hits_exclusion(&pr, hi1, hi2));
  const double v1[3] = {5, 5, 9}, v2[3] = {5, 5, -3}; /* a shaft through it */
  assert_true(karst_i_segment_hits_exclusion(&pr, v1, v2));
}

/* An insoluble stratum between planes at 40 and 60 m is not bedrock (open layer: its contacts
 * are); a segment from 30 to 70 m crosses it, one from 20 to 40 m touches it only at its end. A
 * key point inside an exclusion is refused with its position in the file. */
static void test_insoluble_stratum_and_key_points(void **state) {
  (void)state;
  karst_scenario_t sc;
  plain(&sc);
  sc.n_strata = 1;
  sc.strata = calloc(1, sizeof *sc.strata);
  strcpy(sc.strata[0].name, "shale");
  sc.strata[0].top = (karst_surface_def_t){.given = 1, .elevation = 60};
  sc.strata[0].bottom = (karst_surface_def_t){.given = 1, .elevation = 40};
  sc.strata[0].soluble = 0;
  const double p50[3] = {50, 50, 50}, p40[3] = {50, 50, 40}, p70[3] = {50, 50, 70},
               p30[3] = {50, 50, 30}, p20[3] = {50, 50, 20};
  assert_false(T_in_bedrock(&sc, p50));
  assert_true(T_in_bedrock(&sc, p40));
  assert_false(T_segment_in_bedrock(&sc, p30, p70));
  assert_true(T_segment_in_bedrock(&sc, p20, p40));
  assert_true(T_segment_in_bedrock(&sc, p70, (double[]){80, 50, 90}));
  karst_geology_t *g = geo_make(&sc);
  assert_int_equal(karst_geology_stratum_at(g, p50), 0);
  assert_int_equal(karst_geology_stratum_at(g, p20), -1);
  int idx = -1;
  assert_int_equal(karst_geology_exclusion_at(g, p50, &idx), KARST_EXCLUDED_STRATUM);
  assert_int_equal(idx, 0);
  karst_geology_free(g);
  /* A key point inside a box exclusion: the message names it and where both were given. */
  sc.path = strdup("here.yaml");
  sc.n_exclusions = 1;
  sc.exclusions = calloc(1, sizeof *sc.exclusions);
  sc.exclusions[0] = (karst_exclusion_t){.name = "quarry",
                                         .kind = KARST_EXCLUSION_BOX,
                                         .min = {0, 0, 70},
                                         .max = {10, 10, 90},
                                         .line = 30};
  sc.n_key_points = 1;
  sc.key_points = calloc(1, sizeof *sc.key_points);
  strcpy(sc.key_points[0].name, "doline");
  sc.key_points[0].p[0] = 5, sc.key_points[0].p[1] = 5, sc.key_points[0].p[2] = 80;
  sc.key_points[0].line = 12, sc.key_points[0].column = 5;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  assert_int_equal(karst_geology_create(&ctx, &sc, 0, 0, &g), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "here.yaml:12:5: key_points[0] 'doline'"));
  assert_non_null(strstr(ctx.errmsg, "exclusions[0] 'quarry' (line 30)"));
  karst_scenario_destroy(&sc);
}

/* Faults in the cost (docs/generation.md): a vertical fault plane x = 50 (dip direction 90°,
 * damage zone 10 m) of factor 0.2 makes an edge running north inside it cost 0.2 of its length
 * (the direction lies in the plane), one running east through it f_eff = 0.2 + 0.8·1 = 1 (no
 * gain across), and a north edge half inside (x from 53 to 57: 2 of its 4 m x-extent... here the
 * edge runs obliquely from (53, 0, 50) to (57, 10, 50), 1/2 of its parameter range in the slab
 * 45 ≤ x ≤ 55) costs L (1 − 0.5 (1 − f_eff)) with f_eff = 0.2 + 0.8 (4/√116)². A barrier fault
 * adds its crossing cost to an edge crossing the plane within its radius and nothing beyond. */
static void test_fault_terms(void **state) {
  (void)state;
  karst_scenario_t sc;
  plain(&sc);
  sc.n_faults = 1;
  sc.faults = calloc(1, sizeof *sc.faults);
  karst_fault_t *F = &sc.faults[0];
  F->center[0] = 50, F->center[1] = 50, F->center[2] = 50;
  F->dip_direction = 90, F->dip = 90, F->radius = INFINITY, F->damage_zone = 10, F->factor = 0.2;
  const double a[3] = {50, 10, 50}, b[3] = {50, 30, 50};
  assert_close(T_cost_edge(&sc, a, b), 0.2 * 20, 1e-12);
  const double c[3] = {40, 50, 50}, d[3] = {60, 50, 50};
  assert_close(T_cost_edge(&sc, c, d), 20, 1e-12);
  const double e[3] = {53, 0, 50}, f[3] = {57, 10, 50};
  double L = sqrt(116.0), feff = 0.2 + 0.8 * 16 / 116.0;
  assert_close(T_cost_edge(&sc, e, f), L * (1 - 0.5 * (1 - feff)), 1e-12);
  /* Lower bound: 1 × 0.2 (the smallest factor). */
  assert_close(karst_cost_lower_bound_per_metre(&sc), 0.2 * (1 - KARST_COST_LB_MARGIN), 1e-15);
  /* Barrier disc of radius 20 about (50, 50, 50): crossing at y = 50 adds 100; at y = 80 (30 m
   * from the centre, beyond the disc) nothing. */
  F->barrier = 1, F->radius = 20, F->crossing_cost = 100;
  assert_close(T_cost_edge(&sc, c, d), 20 + 100, 1e-12);
  const double g[3] = {40, 80, 50}, h[3] = {60, 80, 50};
  assert_close(T_cost_edge(&sc, g, h), 20, 1e-12);
  assert_close(T_cost_edge(&sc, a, b), 20, 1e-12); /* along it: no crossing */
  karst_scenario_destroy(&sc);
}

/* Discrete fracture networks: the count is Poisson with mean P32 V' / E[π r²] (V' the domain
 * grown by r_max); the same seed gives the same discs, another seed others; an edge lying in a
 * disc costs the family's factor, one crossing it its full cost. */
static void test_dfn(void **state) {
  (void)state;
  karst_scenario_t sc;
  plain(&sc);
  sc.n_fractures = 1;
  sc.fractures = calloc(1, sizeof *sc.fractures);
  karst_fracture_t *fr = &sc.fractures[0];
  fr->dip_direction = 0, fr->dip = 90, fr->weight = 0; /* vertical E-W planes, pole north */
  fr->dfn = 1, fr->p32 = 0.02, fr->size_exponent = 2.5, fr->r_min = 5, fr->r_max = 20;
  fr->factor = 0.25, fr->influence = 2;
  /* E[r²] for p ∝ r^-2.5 on [5, 20]: ∫r^-0.5 / ∫r^-2.5 = 2(√20 − √5) / ((5^-1.5 − 20^-1.5)/1.5). */
  double m2 = 2 * (sqrt(20.0) - sqrt(5.0)) / ((pow(5, -1.5) - pow(20, -1.5)) / 1.5);
  double mean = 0.02 * pow(140.0, 3) / (M_PI * m2);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double total = 0;
  const int R = 40;
  for (int rz = 0; rz < R; rz++) {
    karst_geology_t *g = NULL;
    assert_int_equal(karst_geology_create(&ctx, &sc, 9, (uint64_t)rz, &g), KARST_SUCCESS);
    karst_int_t n;
    const karst_disc_t *d = karst_geology_discs(g, &n);
    total += (double)n;
    for (karst_int_t i = 0; i < n; i++) {
      assert_true(d[i].r >= 5 && d[i].r <= 20);
      assert_close(fabs(d[i].n[1]), 1.0, 1e-12); /* no dispersion: the pole */
    }
    karst_geology_free(g);
  }
  /* The mean of R Poisson counts: standard error sqrt(mean / R). */
  assert_close(total / R, mean, 4 * sqrt(mean / R));
  karst_geology_t *g1 = NULL, *g2 = NULL, *g3 = NULL;
  assert_int_equal(karst_geology_create(&ctx, &sc, 9, 3, &g1), KARST_SUCCESS);
  assert_int_equal(karst_geology_create(&ctx, &sc, 9, 3, &g2), KARST_SUCCESS);
  assert_int_equal(karst_geology_create(&ctx, &sc, 9, 4, &g3), KARST_SUCCESS);
  karst_int_t n1, n2, n3;
  const karst_disc_t *d1 = karst_geology_discs(g1, &n1), *d2 = karst_geology_discs(g2, &n2),
                     *d3 = karst_geology_discs(g3, &n3);
  assert_int_equal(n1, n2);
  assert_memory_equal(d1, d2, (size_t)n1 * sizeof *d1);
  assert_true(n1 != n3 || memcmp(d1, d3, (size_t)n1 * sizeof *d1) != 0);
  /* An edge in the plane of the first disc that lies inside the domain, within its radius. */
  karst_int_t k = 0;
  while (k < n1 && !(d1[k].c[0] > 20 && d1[k].c[0] < 80 && d1[k].c[1] > 20 && d1[k].c[1] < 80 &&
                     d1[k].c[2] > 20 && d1[k].c[2] < 80))
    k++;
  assert_true(k < n1);
  const karst_disc_t *D = &d1[k];
  const double a[3] = {D->c[0] - 2, D->c[1], D->c[2]}, b[3] = {D->c[0] + 2, D->c[1], D->c[2]};
  const double c[3] = {D->c[0], D->c[1] - 2, D->c[2]}, e[3] = {D->c[0], D->c[1] + 2, D->c[2]};
  /* Along the disc: 4 m × 0.25 (unless another disc crosses there too: then at most that). */
  assert_true(karst_cost_edge(g1, a, b) <= 4 * 0.25 + 1e-12);
  /* Across (along the pole): f + (1 − f)·1 = 1, unless another disc makes it cheaper. */
  assert_true(karst_cost_edge(g1, c, e) <= 4 + 1e-12);
  assert_true(karst_cost_edge(g1, c, e) >= 4 * 0.25 - 1e-12);
  karst_geology_free(g1), karst_geology_free(g2), karst_geology_free(g3);
  karst_scenario_destroy(&sc);
}

/* Routed costs by hand (karst_route_t): band 5 around a table at depth 0; vadose_factor 2,
 * rise_cost 4, phreatic_depth 10. */
static void test_route_costs(void **state) {
  (void)state;
  /* vertices: 0 vadose at z 50 (depth −20), 1 vadose at z 60, 2 in the band (depth 0, z 30),
   * 3 phreatic (depth 25, z 5), 4 phreatic (depth 15, z 15) */
  const float dz[10] = {-20, 50, -30, 60, 0, 30, 25, 5, 15, 15};
  karst_route_t r = {dz, 5.0f, 2.0, 4.0, 0.1, NULL, NULL};
  assert_close(karst_route_arc_cost(&r, 10, 0, 1), 10 * 2 + 4 * 10, 1e-12); /* rises 10 m */
  assert_close(karst_route_arc_cost(&r, 10, 1, 0), 20, 1e-12);              /* descends */
  assert_close(karst_route_arc_cost(&r, 10, 0, 2), 20, 1e-12); /* into the band: vadose */
  assert_true(isinf(karst_route_arc_cost(&r, 10, 2, 0)));      /* back up: forbidden */
  assert_true(isinf(karst_route_arc_cost(&r, 10, 3, 1)));
  /* phreatic: mean depth below the band of 3 → 4: (20 + 10)/2 = 15 → 10 (1 + 1.5) */
  assert_close(karst_route_arc_cost(&r, 10, 3, 4), 25, 1e-12);
  /* band → phreatic 3: the depth below the band goes linearly from −5 to 20, positive on the
   * last 20/25 of the arc, a triangle of mean 20² / (2 × 25) = 8 → 10 × 1.8; band → band: the
   * base cost */
  assert_close(karst_route_arc_cost(&r, 10, 2, 3), 18, 1e-12);
  assert_close(karst_route_arc_cost(&r, 10, 2, 2), 10, 1e-12);
  assert_close(karst_route_arc_cost(NULL, 10, 0, 1), 10, 0);
}

/* A* (with the routed costs, the backward rows as heuristic, and path sharing) against
 * Dijkstra on the same directed costs: a jittered lattice in a slab whose water table dips, every
 * pair of a few vertices, both the exact cost and the reuse search's cost equal the forward
 * Dijkstra's (to 1e-9 relative), and no path rises back from the band into the vadose zone. */
static void test_routed_astar_matches_dijkstra(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 11, 0);
  const double o[3] = {0, 0, 0};
  const int nx = 16, ny = 16, nz = 8;
  double *xyz = fx_jittered_grid(nx, ny, nz, 5.0, o, 0.3, &rng);
  const karst_int_t n = (karst_int_t)nx * ny * nz;
  karst_graph_t g;
  fx_knn_graph(&g, n, xyz, 12, fx_euclid_cost, NULL);
  /* water table W(x, y) = 25 − 0.3 x: depth W − z */
  float *dz = malloc(sizeof *dz * 2 * (size_t)n);
  for (karst_int_t v = 0; v < n; v++)
    dz[2 * v] = (float)(25 - 0.3 * xyz[3 * v] - xyz[3 * v + 2]),
           dz[2 * v + 1] = (float)xyz[3 * v + 2];
  karst_route_t route = {dz, 2.0f, 2.5, 3.0, 1.0 / 15, NULL, NULL};
  const karst_route_t *routes[1] = {&route};
  /* The tabulated route (karst_route_tabulate, two threads): every arc's value is the formula's,
   * bit for bit, and every search below must give bit-identical results with it. */
  karst_arc_cost_t *fwd = malloc(sizeof *fwd * (size_t)g.n_arcs),
                   *bwd = malloc(sizeof *bwd * (size_t)g.n_arcs);
  karst_ctx_t ctx2;
  karst_ctx_init(&ctx2);
  ctx2.nthreads = 2;
  karst_route_tabulate(&ctx2, &g, &route, fwd, bwd);
  for (karst_int_t v = 0; v < n; v++) {
    karst_arc_reader_t rd = karst_graph_arcs(&g, v);
    for (karst_int_t a = g.offsets[v]; a < g.offsets[v + 1]; a++) {
      karst_int_t w = karst_arc_next(&rd);
      assert_true(fwd[a] == karst_route_arc_cost(&route, g.cost[a], v, w));
      assert_true(bwd[a] == karst_route_arc_cost(&route, g.cost[a], w, v));
    }
  }
  karst_route_t tabbed = route;
  tabbed.arc_fwd = fwd;
  tabbed.arc_bwd = bwd;
  const karst_route_t *troutes[1] = {&tabbed};
  float *bound2 = malloc(sizeof *bound2 * (size_t)n);
  karst_path_t p2;
  karst_path_init(&p2);
  karst_search_t *s = NULL, *s2 = NULL;
  assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
  assert_int_equal(karst_search_create(&ctx, &g, &s2), KARST_SUCCESS);
  float *bound = malloc(sizeof *bound * (size_t)n);
  karst_path_t p;
  karst_path_init(&p);
  const karst_int_t targets[4] = {n - 1, 1000, 300, 77};
  const karst_int_t sources[5] = {0, 1234, n - 17, 640, 2000};
  int checked = 0;
  for (int t = 0; t < 4; t++) {
    double dist[5];
    assert_int_equal(karst_paths_target_rows(&ctx, &g, 1, &targets[t], routes, NULL, 5, sources,
                                             dist, bound, NULL),
                     KARST_SUCCESS);
    double dist2[5];
    assert_int_equal(karst_paths_target_rows(&ctx, &g, 1, &targets[t], troutes, NULL, 5, sources,
                                             dist2, bound2, NULL),
                     KARST_SUCCESS);
    assert_memory_equal(dist, dist2, sizeof dist);
    assert_memory_equal(bound, bound2, sizeof *bound * (size_t)n);
    for (int k = 0; k < 5; k++) {
      karst_int_t last = -1;
      unsigned char *is_t = calloc((size_t)n, 1);
      is_t[targets[t]] = 1;
      assert_int_equal(
          karst_paths_dijkstra_routed(&ctx, s2, &route, 1, &sources[k], NULL, is_t, 1, &last),
          KARST_SUCCESS);
      free(is_t);
      double ref = karst_search_dist(s2, targets[t]);
      if (!(ref < INFINITY)) {
        assert_true(isinf(dist[k]));
        continue;
      }
      assert_rel(dist[k], ref, 1e-9);
      const karst_reuse_t ru = {1.0, NULL, NULL, NULL, NULL, 0, &route, NULL};
      assert_int_equal(
          karst_paths_astar_reuse(&ctx, s, sources[k], targets[t], 1.0, bound, &ru, &p),
          KARST_SUCCESS);
      assert_rel(p.cost, ref, 1e-9);
      const karst_reuse_t ru2 = {1.0, NULL, NULL, NULL, NULL, 0, &tabbed, NULL};
      assert_int_equal(
          karst_paths_astar_reuse(&ctx, s2, sources[k], targets[t], 1.0, bound, &ru2, &p2),
          KARST_SUCCESS);
      assert_true(p2.cost == p.cost && p2.n == p.n);
      assert_memory_equal(p.v, p2.v, sizeof *p.v * (size_t)p.n);
      /* Euclidean bound alone: the same optimum. */
      assert_int_equal(karst_paths_astar_reuse(&ctx, s, sources[k], targets[t], 1.0, NULL, &ru, &p),
                       KARST_SUCCESS);
      assert_rel(p.cost, ref, 1e-9);
      int met = 0;
      for (karst_int_t i = 0; i < p.n; i++) {
        float d = dz[2 * p.v[i]];
        if (d >= -2.0f) met = 1;
        if (met) assert_true(d >= -2.0f); /* never above the band again */
      }
      checked++;
    }
  }
  assert_true(checked >= 12);
  karst_path_destroy(&p);
  karst_path_destroy(&p2);
  free(bound2);
  free(fwd);
  free(bwd);
  karst_search_free(s);
  karst_search_free(s2);
  free(bound);
  free(dz);
  fx_graph_free(&g);
  free(xyz);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_fisher),      cmocka_unit_test(test_dispersed_fracture_term),
      cmocka_unit_test(test_exclusions),  cmocka_unit_test(test_insoluble_stratum_and_key_points),
      cmocka_unit_test(test_fault_terms), cmocka_unit_test(test_dfn),
      cmocka_unit_test(test_route_costs), cmocka_unit_test(test_routed_astar_matches_dijkstra),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
