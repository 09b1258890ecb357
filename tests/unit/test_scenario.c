/* Scenario reader, cross-field checks and geological fields (Paris et al. 2021, §4.2).
 *
 * Expected values are hand calculations (stated beside each assert), the
 * published FNV-1a test vectors, or the values written in the fixture files
 * under tests/data/scenarios/. Each bad-input fixture has its own test that
 * checks the error code, the exact "FILE:LINE:COLUMN: " prefix (positions
 * counted by hand in the fixture) and the key part of the message. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "karst.h"
#include "scenario/scenario_internal.h"
#include "test_util.h"

#define DATA KARST_SOURCE_DIR "/tests/data/scenarios/"

/* ------------------------------------------------------------------------ */
/* Good files                                                               */
/* ------------------------------------------------------------------------ */

static int count_type(const karst_scenario_t *sc, karst_keypoint_type_t t) {
  int n = 0;
  for (int i = 0; i < sc->n_key_points; i++)
    n += sc->key_points[i].type == t;
  return n;
}

/* karst_scenario_init() gives the defaults documented in docs/scenario.md
 * (values copied from its tables). */
static void test_init_defaults(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_close(sc.domain_min[0], 0, 0);
  assert_close(sc.domain_max[2], 100, 0);
  assert_int_equal(sc.terrain.is_grid, 0);
  assert_close(sc.terrain.elevation, 100, 0);
  assert_int_equal(sc.water_table.given, 0); /* each spring's own horizontal plane */
  assert_close(sc.routing.vadose_factor, 2, 0);
  assert_close(sc.routing.rise_cost, 4, 0);
  assert_close(sc.routing.phreatic_depth, 50, 0);
  assert_close(sc.routing.water_table_band, 5, 0);
  assert_close(sc.permeability.background, 1, 0);
  assert_close(sc.cost.w0, 1, 0);
  assert_close(sc.cost.horizon, 1, 0);
  assert_close(sc.cost.fracture, 1, 0);
  assert_close(sc.cost.permeability, 1, 0);
  assert_close(sc.cost.prescribed, 0.1, 0);
  assert_close(sc.sampling.fill_radius, 10, 0);
  assert_close(sc.sampling.feature_radius, 3, 0);
  assert_close(sc.sampling.permeable_threshold, 0.3, 0);
  assert_close(sc.sampling.feature_band, 1, 0);
  assert_int_equal(sc.sampling.k, 40);
  assert_true(sc.sampling.max_samples == 5000000);
  assert_close(sc.gamma, 2, 0);
  assert_close(sc.reuse, KARST_SCENARIO_DEFAULT_REUSE, 0);
  assert_int_equal(sc.cost.fracture_combine, KARST_FRACTURE_SUM);
  assert_int_equal(sc.amplification.steps, 0);
  assert_int_equal(sc.amplification.points, 0);
  assert_close(sc.amplification.dead_end_fraction, 0, 0);
  assert_close(sc.amplification.reach, 0, 0); /* the paper's bounding-box draw */
  assert_close(sc.amplification.reach_ratio, 0.5, 0);
  assert_close(sc.amplification.points_ratio, 1, 0);
  assert_int_equal(sc.amplification.anchor, KARST_ANCHOR_PREVIOUS);
  assert_close(sc.tortuosity, 0.1, 0);
  assert_close(sc.classification.vertical_angle, 60, 0);
  assert_close(sc.classification.epikarst_depth, 10, 0);
  assert_close(sc.classification.chamber_resistance, 0.05, 0);
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    assert_close(sc.classification.radius[t].min, 0.5, 0);
    assert_close(sc.classification.radius[t].max, t == KARST_TUNNEL_EPIKARST ? 0.5 : 4.0, 0);
  }
  assert_true(sc.seed == 1);
  assert_int_equal(sc.realisations, 1);
  karst_scenario_destroy(&sc);
}

/* The shipped default: values as written in datasets/scenarios/branchwork.yaml,
 * which follows Paris et al. 2021 Table 1 (branchwork: 0.4 x 0.6 x 0.1 km,
 * 17 key points, θ = 0.1, γ = 2) and §4.1 (k = 40). */
static void test_branchwork(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_error_t err =
      karst_scenario_load(&ctx, KARST_SOURCE_DIR "/datasets/scenarios/branchwork.yaml", &sc);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  assert_string_equal(sc.name, "branchwork");
  assert_close(sc.domain_max[0] - sc.domain_min[0], 400.0, 0);
  assert_close(sc.domain_max[1] - sc.domain_min[1], 600.0, 0);
  assert_close(sc.domain_max[2] - sc.domain_min[2], 100.0, 0);
  assert_int_equal(sc.n_key_points, 17);
  assert_int_equal(count_type(&sc, KARST_KEYPOINT_SINK), 12);
  assert_int_equal(count_type(&sc, KARST_KEYPOINT_SPRING), 1);
  assert_int_equal(count_type(&sc, KARST_KEYPOINT_WAYPOINT), 4);
  assert_int_equal(sc.n_horizons, 1);
  assert_int_equal(sc.n_fractures, 1);
  assert_close(sc.gamma, 2.0, 0);
  assert_close(sc.tortuosity, 0.4, 0);
  assert_close(sc.amplification.reach, 250, 0);
  assert_int_equal(sc.amplification.anchor, KARST_ANCHOR_PREVIOUS);
  assert_int_equal(sc.sampling.k, 40);
  assert_int_equal(sc.terrain.is_grid, 0);
  assert_close(sc.terrain.elevation, 100.0, 0);
  assert_int_equal(sc.water_table.given, 1);
  assert_close(sc.water_table.elevation, 20.0, 0);
  /* The horizon's origin defaults to the domain centre (200, 300). */
  assert_close(sc.horizons[0].origin[0], 200.0, 0);
  assert_close(sc.horizons[0].origin[1], 300.0, 0);
  assert_close(sc.horizons[0].elevation, 50.0, 0);
  /* The spring sits at the water table (§5.3: outlets drain to it). */
  for (int i = 0; i < sc.n_key_points; i++)
    if (sc.key_points[i].type == KARST_KEYPOINT_SPRING)
      assert_close(sc.key_points[i].p[2], sc.water_table.elevation, 0);
  /* Epikarst radius fixed at 0.5 m, others 0.5-4 m (§5.3). */
  assert_close(sc.classification.radius[KARST_TUNNEL_EPIKARST].max, 0.5, 0);
  assert_close(sc.classification.radius[KARST_TUNNEL_TUBE].max, 4.0, 0);
  assert_true(sc.seed == 2021);
  /* Sample count "of the order of 25 000" (Table 1: 25 265), estimated
   * independently from the jamming densities of random sequential addition:
   * 3-D fill 0.3841 V / (π r³ / 6), plus 0.5472 A / (π r² / 4) on each of
   * the horizon and the water table. Accept a factor of two. */
  double V = 400.0 * 600.0 * 100.0, A = 400.0 * 600.0;
  double rf = sc.sampling.fill_radius, rs = sc.sampling.feature_radius;
  double n = 0.3841 * V / (M_PI * rf * rf * rf / 6) + 2 * 0.5472 * A / (M_PI * rs * rs / 4);
  assert_true(n > 12500 && n < 50000);
  karst_scenario_destroy(&sc);
}

/* Everything absent takes the karst_scenario_init() default; the water table
 * the domain bottom; names sink1/spring1; the scenario name the file's. */
static void test_minimal_defaults(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc, def;
  karst_scenario_init(&sc);
  karst_scenario_init(&def);
  assert_int_equal(karst_scenario_load(&ctx, DATA "good/minimal.yaml", &sc), KARST_SUCCESS);
  assert_string_equal(sc.name, "minimal");
  assert_string_equal(sc.path, DATA "good/minimal.yaml");
  assert_int_equal(sc.water_table.given, 0);
  assert_string_equal(sc.key_points[0].name, "sink1");
  assert_string_equal(sc.key_points[1].name, "spring1");
  assert_int_equal(sc.key_points[0].line, 8);
  assert_int_equal(sc.key_points[0].column, 5);
  assert_true(memcmp(&sc.cost, &def.cost, sizeof def.cost) == 0);
  assert_true(memcmp(&sc.sampling, &def.sampling, sizeof def.sampling) == 0);
  assert_true(memcmp(&sc.amplification, &def.amplification, sizeof def.amplification) == 0);
  assert_true(memcmp(&sc.classification, &def.classification, sizeof def.classification) == 0);
  assert_close(sc.gamma, def.gamma, 0);
  assert_close(sc.tortuosity, def.tortuosity, 0);
  assert_true(sc.seed == def.seed);
  assert_int_equal(sc.realisations, def.realisations);
  assert_close(sc.permeability.background, 1.0, 0);
  assert_null(sc.permeability.root);
  assert_int_equal(sc.n_horizons, 0);
  assert_int_equal(sc.n_prescribed, 0);
  karst_scenario_destroy(&sc);
}

/* Every optional block, values as written in good/grid.yaml. */
static void test_full_file(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_error_t err = karst_scenario_load(&ctx, DATA "good/grid.yaml", &sc);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  /* Heightfield z = 30 + 0.1 x + 0.05 y on a 3 x 3 grid, 50 m cells, centres at 0, 50, 100. */
  assert_int_equal(sc.terrain.is_grid, 1);
  assert_int_equal(sc.terrain.ncols, 3);
  assert_int_equal(sc.terrain.nrows, 3);
  assert_close(sc.terrain.xll, 0.0, 0);
  assert_close(sc.terrain.cellsize, 50.0, 0);
  assert_close(sc.terrain.zmin, 30.0, 0);
  assert_close(sc.terrain.zmax, 45.0, 0);
  assert_close(sc.terrain.lipschitz, sqrt(0.1 * 0.1 + 0.05 * 0.05), 1e-12);
  assert_close(karst_terrain_height(&sc.terrain, 10, 50), 33.5, 1e-12);
  assert_close(sc.water_table.elevation, 12.5, 0);
  assert_int_equal(sc.n_horizons, 2);
  assert_close(sc.horizons[0].dip, 10, 0);
  assert_close(sc.horizons[0].dip_direction, 45, 0);
  assert_close(sc.horizons[0].origin[0], 10, 0);
  assert_close(sc.horizons[0].origin[1], 20, 0);
  assert_close(sc.horizons[0].radius, 4, 0);
  assert_close(sc.horizons[1].dip, 0, 0);
  assert_close(sc.horizons[1].origin[0], 50, 0); /* domain centre */
  assert_close(sc.horizons[1].origin[1], 50, 0);
  assert_int_equal(sc.n_fractures, 2);
  assert_close(sc.fractures[0].weight, 2, 0);
  assert_close(sc.fractures[1].weight, 1, 0); /* default */
  assert_close(sc.fractures[1].dip_direction, 120, 0);
  const karst_perm_node_t *root = sc.permeability.root;
  assert_non_null(root);
  assert_int_equal(root->kind, KARST_PERM_BLEND);
  assert_int_equal(root->n_children, 2);
  assert_int_equal(root->children[0].kind, KARST_PERM_SPHERE);
  assert_close(root->children[0].weight, 3, 0);
  assert_close(root->children[0].falloff, 5, 0);
  assert_close(root->children[0].center[2], 25, 0);
  assert_int_equal(root->children[1].kind, KARST_PERM_STRATUM);
  assert_close(root->children[1].weight, 1, 0);
  assert_close(root->children[1].top, 20, 0);
  /* Unnamed key points take the ordinal among their type, skipping names in
   * use: the first sink would be sink1, which the second sink holds. */
  assert_int_equal(sc.n_key_points, 5);
  assert_string_equal(sc.key_points[0].name, "sink2");
  assert_string_equal(sc.key_points[1].name, "sink1");
  assert_string_equal(sc.key_points[2].name, "sink3");
  assert_string_equal(sc.key_points[3].name, "spring1");
  assert_string_equal(sc.key_points[4].name, "waypoint1");
  assert_int_equal(sc.n_prescribed, 2);
  assert_int_equal(sc.prescribed[0].a, 0);
  assert_int_equal(sc.prescribed[0].b, 4);
  assert_int_equal(sc.prescribed[1].a, 4);
  assert_int_equal(sc.prescribed[1].b, 3);
  assert_int_equal(sc.prescribed[1].line, 36);
  assert_close(sc.cost.w0, 2, 0);
  assert_close(sc.cost.prescribed, 0.2, 0);
  assert_int_equal(sc.sampling.k, 24);
  assert_true(sc.sampling.max_samples == 2000000); /* written 2e6: a whole number */
  assert_close(sc.sampling.feature_band, 0.5, 0);
  assert_close(sc.gamma, 1.5, 0);
  assert_close(sc.reuse, 0.25, 0);
  assert_int_equal(sc.cost.fracture_combine, KARST_FRACTURE_MIN);
  assert_int_equal(sc.amplification.steps, 3);
  assert_int_equal(sc.amplification.points, 12);
  assert_close(sc.amplification.reach, 40, 0);
  assert_close(sc.amplification.reach_ratio, 0.25, 0);
  assert_close(sc.amplification.points_ratio, 3, 0);
  assert_int_equal(sc.amplification.anchor, KARST_ANCHOR_NETWORK);
  /* points × points_ratio^(s-1), by hand: 12, 36, 108 */
  assert_close(karst_amplification_step_points(&sc.amplification, 1), 12, 0);
  assert_close(karst_amplification_step_points(&sc.amplification, 3), 108, 0);
  assert_close(sc.tortuosity, 0.4, 0);
  assert_close(sc.classification.radius[KARST_TUNNEL_TUBE].min, 1, 0);
  assert_close(sc.classification.radius[KARST_TUNNEL_EPIKARST].min, 0.25, 0);
  assert_close(sc.classification.radius[KARST_TUNNEL_CANYON].max, 4, 0); /* default kept */
  assert_true(sc.seed == UINT64_MAX);
  assert_int_equal(sc.realisations, 5);
  assert_int_equal(sc.pos_terrain.line, 8);
  assert_int_equal(sc.pos_terrain.column, 16);
  /* The loaded tree at two points, by hand: blend of the sphere (weight 3)
   * and the stratum (weight 1), background 0.9.
   * (50,50,25): sphere 0.1, stratum outside -> 0.9: (3*0.1 + 0.9)/4 = 0.3.
   * (50,50,12): sphere distance 3 of falloff 5, g(0.6) = 0.648,
   *   0.352*0.1 + 0.648*0.9 = 0.6184; stratum 0.4: (3*0.6184 + 0.4)/4 = 0.5638. */
  assert_close(karst_permeability_eval(&sc.permeability, (double[]){50, 50, 25}), 0.3, 1e-12);
  assert_close(karst_permeability_eval(&sc.permeability, (double[]){50, 50, 12}), 0.5638, 1e-12);
  karst_scenario_destroy(&sc);
}

/* A failed load leaves the caller's scenario as it was. */
static void test_failure_keeps_scenario(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, DATA "good/minimal.yaml", &sc), KARST_SUCCESS);
  assert_int_not_equal(karst_scenario_load(&ctx, DATA "bad/dip_range.yaml", &sc), KARST_SUCCESS);
  assert_string_equal(sc.name, "minimal");
  assert_int_equal(sc.n_key_points, 2);
  assert_int_equal(sc.n_fractures, 0);
  karst_scenario_destroy(&sc);
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, "/nonexistent/dir/s.yaml", &sc), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/nonexistent/dir/s.yaml: cannot open"));
  assert_null(sc.path);
  karst_scenario_destroy(&sc);
}

/* ------------------------------------------------------------------------ */
/* Bad files: one test per case                                             */
/* ------------------------------------------------------------------------ */

/* Load @p file (under bad/), expect @p code, the exact prefix
 * "PATH:LINE:COLUMN: " and @p part somewhere in the message. */
static void expect_bad(const char *file, karst_error_t code, int line, int col, const char *part) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  char path[1024], prefix[1100];
  snprintf(path, sizeof path, DATA "bad/%s", file);
  snprintf(prefix, sizeof prefix, "%s:%d:%d: ", path, line, col);
  karst_error_t err = karst_scenario_load(&ctx, path, &sc);
  if (!err) { /* what only the geology checks (as karst validate does) */
    karst_geology_t *g = NULL;
    err = karst_geology_create(&ctx, &sc, 0, 0, &g);
    karst_geology_free(g);
    if (err) karst_scenario_destroy(&sc), karst_scenario_init(&sc);
  }
  if (err != code || strncmp(ctx.errmsg, prefix, strlen(prefix)) != 0 || !strstr(ctx.errmsg, part))
    print_error("got %s: \"%s\"\nexpected %s: \"%s...%s...\"\n", karst_error_name(err), ctx.errmsg,
                karst_error_name(code), prefix, part);
  assert_int_equal(err, code);
  assert_true(strncmp(ctx.errmsg, prefix, strlen(prefix)) == 0);
  assert_non_null(strstr(ctx.errmsg, part));
  assert_null(sc.path); /* nothing half-built */
  assert_int_equal(sc.n_key_points, 0);
  karst_scenario_destroy(&sc);
}

#define BAD(name, code, line, col, part)                                                           \
  static void test_bad_##name(void **state) {                                                      \
    (void)state;                                                                                   \
    expect_bad(#name ".yaml", code, line, col, part);                                              \
  }

/* YAML syntax: libyaml's problem and the position where it noticed it. */
BAD(syntax, KARST_EPARSE, 11, 1, "YAML syntax error: did not find expected ',' or ']'")
BAD(empty, KARST_EPARSE, 1, 1, "the scenario file is empty")
BAD(comments_only, KARST_EPARSE, 1, 1, "the scenario file is empty")
BAD(invalid_utf8, KARST_EPARSE, 4, 1, "invalid leading UTF-8 octet")
BAD(two_documents, KARST_EPARSE, 13, 1, "holds one YAML document")
BAD(root_list, KARST_EINVAL, 1, 1, "the scenario must be a map")
/* 257th "[" after "horizons: " (10 columns); the quoted "[[[" on line 2 is not counted. */
BAD(deep_nesting, KARST_EPARSE, 3, 267, "lists and maps are nested more than 256 levels deep")
/* Keys. */
BAD(unknown_key, KARST_EINVAL, 16, 5, "unknown key 'dipp' in fractures[1] (did you mean 'dip'?)")
BAD(misplaced_key, KARST_EINVAL, 13, 1,
    "unknown key 'gamma' at the top level (did you mean 'skeleton.gamma'?)")
BAD(duplicate_key, KARST_EINVAL, 15, 1,
    "duplicate key 'skeleton' at the top level (first given at line 13)")
BAD(missing_required, KARST_EINVAL, 14, 5, "horizons[0] is missing the required key 'radius'")
/* Types. */
BAD(not_a_number, KARST_EINVAL, 15, 10, "horizons[0].dip must be a number, got 'steep'")
BAD(quoted_number, KARST_EINVAL, 15, 13,
    "horizons[0].radius must be a number, got the string \"5\"")
BAD(map_for_list, KARST_EINVAL, 14, 3, "horizons must be a list of maps, got a map")
BAD(short_vector, KARST_EINVAL, 11, 38,
    "key_points[0].position must be a list of 3 numbers [x, y, z], got 2 items")
BAD(k_not_integer, KARST_EINVAL, 14, 6, "sampling.k must be an integer, got 2.5")
BAD(seed_negative, KARST_EINVAL, 14, 9, "random.seed must be an unsigned 64-bit integer")
BAD(seed_overflow, KARST_EINVAL, 14, 9, "got 18446744073709551616")
/* Enumerations. */
BAD(enum_typo, KARST_EINVAL, 11, 22,
    "key_points[0].type must be one of sink, spring, waypoint, got 'sinkk' (did you mean 'sink'?)")
BAD(units, KARST_EUNSUPPORTED, 2, 8, "units must be m (metres")
/* Ranges. */
BAD(dip_range, KARST_ERANGE, 17, 10, "fractures[2].dip must be within [0, 90] degrees, got 135")
BAD(dip_direction_range, KARST_ERANGE, 14, 21,
    "fractures[0].dip_direction must be within [0, 360) degrees, got 360")
BAD(negative_radius, KARST_ERANGE, 15, 13, "horizons[0].radius must be > 0 m, got -5")
BAD(resistance_range, KARST_ERANGE, 17, 64,
    "permeability.tree.union[1].sphere.resistance must be within [0, 1], got 1.5")
BAD(theta_range, KARST_ERANGE, 13, 13, "tortuosity must be within [0, 1], got 1.2")
BAD(gamma_zero, KARST_ERANGE, 14, 10, "skeleton.gamma must be > 0, got 0")
BAD(reuse_zero, KARST_ERANGE, 15, 10, "skeleton.reuse must be within (0, 1], got 0")
BAD(reuse_above_one, KARST_ERANGE, 14, 10, "skeleton.reuse must be within (0, 1], got 1.5")
BAD(fracture_combine, KARST_EINVAL, 14, 21,
    "cost.fracture_combine must be one of sum, min, got 'max'")
BAD(k_zero, KARST_ERANGE, 14, 6, "sampling.k must be >= 1, got 0")
BAD(weight_negative, KARST_ERANGE, 14, 42, "fractures[0].weight must be >= 0, got -1")
BAD(fraction_range, KARST_ERANGE, 14, 22,
    "amplification.dead_end_fraction must be within [0, 1], got 1.5")
BAD(reach_ratio_zero, KARST_ERANGE, 14, 16,
    "amplification.reach_ratio must be within (0, 1], got 0")
BAD(points_ratio_zero, KARST_ERANGE, 14, 17, "amplification.points_ratio must be > 0, got 0")
BAD(anchor_typo, KARST_EINVAL, 14, 11,
    "amplification.anchor must be one of previous, network, got 'previos'")
/* sampling.refine: a list of known names, each at most once. */
BAD(refine_not_list, KARST_EINVAL, 14, 11,
    "sampling.refine must be a list of the names horizons, water_table, permeability ([] for "
    "none), got 'water_table'")
BAD(refine_typo, KARST_EINVAL, 14, 22,
    "sampling.refine[1] must be one of horizons, water_table, permeability, got 'watertable' "
    "(did you mean 'water_table'?)")
BAD(refine_twice, KARST_EINVAL, 14, 39, "sampling.refine[2]: 'water_table' is listed twice")
/* 1000 × (2^30 − 1) points (by hand: about 1.07e12) are refused before any work is done. */
BAD(amplification_points_total, KARST_ERANGE, 14, 3,
    "amplification: 30 steps of 1000 points growing by points_ratio 2 make")
BAD(realisations_zero, KARST_ERANGE, 14, 17, "random.realisations must be >= 1, got 0")
BAD(radius_min_max, KARST_ERANGE, 15, 11,
    "classification.radius.tube: min must be <= max, got [4, 1]")
BAD(radius_min_zero, KARST_ERANGE, 15, 13, "classification.radius.canyon: min must be > 0 m, got 0")
BAD(domain_order, KARST_ERANGE, 4, 3, "domain.max z (-5 m) must be greater than domain.min z")
BAD(stratum_order, KARST_ERANGE, 15, 16, "stratum: bottom (30 m) must be below top (20 m)")
BAD(feature_radius, KARST_ERANGE, 14, 3, "sampling.feature_radius (8 m) must not exceed")
BAD(water_table_outside, KARST_ERANGE, 9, 14,
    "water_table.elevation must be within the domain's z range [0, 50] m, got 70")
/* Geology sections (docs/scenario.md): names resolved with a did-you-mean, one shape per
 * exclusion, matrices of the right size and values, ranges, and the moved key. */
BAD(drains_unknown, KARST_ENOTFOUND, 7, 63,
    "key_points[0].drains_to[0] names an unknown spring 'sprng' (did you mean 'spring'?)")
BAD(drains_not_sink, KARST_EINVAL, 8, 66,
    "key_points[1].drains_to: only a sink drains to springs; 'w' is a waypoint")
BAD(connectivity_rows, KARST_EINVAL, 11, 5,
    "connectivity.matrix must be a list of 1 rows (one per sink), got 2 rows")
BAD(connectivity_value, KARST_ERANGE, 11, 8,
    "connectivity.matrix[0][0] must be an integer between 0 and 2, got 3")
BAD(connectivity_zero_row, KARST_EINVAL, 11, 7,
    "connectivity.matrix[0]: sink 's' may drain to no spring (every value is 0)")
BAD(exclusion_two_shapes, KARST_EINVAL, 10, 53,
    "exclusions[0].sphere: an exclusion is one shape; this one is already a box")
BAD(exclusion_no_shape, KARST_EINVAL, 10, 5, "exclusions[0] needs one of box, sphere, prism")
BAD(prism_collinear, KARST_EINVAL, 10, 22,
    "exclusions[0].prism.polygon has zero area (its vertices are collinear)")
BAD(keypoint_excluded, KARST_EINVAL, 7, 5,
    "key_points[0] 's' at (10, 10, 50) is inside exclusions[0] 'cave_guard' (line 10)")
BAD(fault_dip, KARST_ERANGE, 10, 52, "faults[0].dip must be within [0, 90] degrees, got 95")
BAD(fault_kind, KARST_EINVAL, 10, 62, "faults[0].kind must be one of conduit, barrier, got 'wall'")
BAD(dfn_radii, KARST_ERANGE, 10, 38, "fractures[0].dfn: r_min (20 m) must not exceed r_max (5 m)")
BAD(kappa_negative, KARST_ERANGE, 10, 47, "fractures[0].fisher_kappa must be > 0, got -2")
BAD(water_table_on_sink, KARST_EINVAL, 7, 76,
    "key_points[0].water_table: only a spring has a water table; 's' is a sink")
BAD(vadose_factor, KARST_ERANGE, 10, 18, "routing.vadose_factor must be >= 1, got 0.5")
BAD(stratum_plane_and_file, KARST_EINVAL, 10, 20,
    "strata[0].top gives both a surface file and plane keys")
BAD(band_in_classification, KARST_EINVAL, 10, 21,
    "classification.water_table_band is now routing.water_table_band")
/* Non-finite values. */
BAD(nan, KARST_ERANGE, 14, 16, "horizons[0].elevation must be a finite number, got .nan")
BAD(inf, KARST_ERANGE, 14, 12, "cost.horizon must be a finite number, got -.inf")
BAD(overflow, KARST_ERANGE, 14, 16, "sampling.fill_radius must be a finite number, got 1e999")
/* Key points. */
BAD(outside_domain, KARST_ERANGE, 11, 5,
    "key_points[0] 'in' at (150, 10, 40) is outside the domain: x must be within [0, 100] m")
BAD(above_terrain, KARST_ERANGE, 13, 5, "key_points[2] 'high' at z = 50.5 m is above the terrain")
/* Heightfield z = 30 + 0.1 x + 0.05 y: 33.5 m at (10, 50), below the key point at 35 m. */
BAD(above_heightfield, KARST_ERANGE, 11, 5,
    "key_points[0] 'in' at z = 35 m is above the terrain (33.5 m at x = 10, y = 50)")
BAD(no_spring, KARST_EINVAL, 11, 3, "no spring among the 2 key points")
BAD(duplicate_name, KARST_EINVAL, 13, 5,
    "key_points[2].name 'in' is already used by key_points[0] (line 11)")
BAD(unknown_path_point, KARST_ENOTFOUND, 15, 10,
    "prescribed_paths[1][1] names an unknown key point 'outt' (did you mean 'out'?)")
/* Permeability tree. */
BAD(perm_two_kinds, KARST_EINVAL, 16, 5, "permeability.tree has both 'sphere' and 'union'")
BAD(perm_empty, KARST_EINVAL, 15, 12, "permeability.tree.blend must list at least one node")
BAD(perm_alias_cycle, KARST_ERANGE, 14, 9, "nested deeper than 64 levels")
/* Terrain and heightfields. */
BAD(terrain_both, KARST_EINVAL, 7, 3,
    "terrain gives more than one of elevation, heightfield and surface")
BAD(heightfield_missing, KARST_EIO, 7, 16, "terrain.heightfield: ")
BAD(heightfield_short, KARST_ERANGE, 7, 16,
    "covers x in [-25, 125], y in [-25, 125] m but the domain spans x in [0, 200]")

/* A malformed grid is reported at the grid's own line and column, then
 * where the scenario names it. */
static void test_bad_heightfield_malformed(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, DATA "bad/heightfield_malformed.yaml", &sc),
                   KARST_ERANGE);
  const char *want =
      DATA "bad/../terrain/bad_cellsize.asc:5:10: cellsize must be > 0, got -5 "
           "(the heightfield of terrain at " DATA "bad/heightfield_malformed.yaml:7:16)";
  assert_string_equal(ctx.errmsg, want);
  karst_scenario_destroy(&sc);
}

/* good/geology.yaml: every geology section read as written. */
static void test_geology_file(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_error_t err = karst_scenario_load(&ctx, DATA "good/geology.yaml", &sc);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  assert_true(sc.water_table.given && !sc.water_table.path);
  assert_close(sc.water_table.elevation, 30, 0);
  assert_close(sc.water_table.dip, 2, 0);
  assert_close(sc.water_table.origin[0], 200, 0); /* the domain centre */
  assert_string_equal(sc.horizons[0].name, "bed_a");
  assert_close(sc.fractures[0].kappa, 40, 0);
  assert_int_equal(sc.fractures[0].dfn, 0);
  assert_close(sc.fractures[1].kappa, 0, 0); /* not given: no dispersion */
  assert_int_equal(sc.fractures[1].dfn, 1);
  assert_close(sc.fractures[1].p32, 0.01, 0);
  assert_close(sc.fractures[1].size_exponent, 2.2, 0);
  assert_close(sc.fractures[1].r_min, 4, 0);
  assert_close(sc.fractures[1].r_max, 30, 0);
  assert_close(sc.fractures[1].factor, 0.4, 0);
  assert_close(sc.fractures[1].influence, 2, 0);
  assert_close(sc.fractures[0].influence, 3, 0); /* sampling.feature_radius */
  assert_int_equal(sc.n_strata, 2);
  assert_string_equal(sc.strata[0].name, "marl");
  assert_int_equal(sc.strata[0].soluble, 0);
  assert_close(sc.strata[0].top.elevation, 20, 0);
  assert_close(sc.strata[0].bottom.elevation, 10, 0);
  assert_int_equal(sc.strata[1].soluble, 1);
  assert_int_equal(sc.strata[1].bottom.given, 0);
  assert_close(sc.strata[1].top.dip_direction, 180, 0);
  assert_int_equal(sc.n_exclusions, 3);
  assert_int_equal(sc.exclusions[0].kind, KARST_EXCLUSION_BOX);
  assert_string_equal(sc.exclusions[0].name, "quarry");
  assert_close(sc.exclusions[0].max[2], 120, 0);
  assert_int_equal(sc.exclusions[1].kind, KARST_EXCLUSION_SPHERE);
  assert_close(sc.exclusions[1].radius, 12, 0);
  assert_int_equal(sc.exclusions[2].kind, KARST_EXCLUSION_PRISM);
  assert_int_equal(sc.exclusions[2].n_vertices, 4);
  assert_close(sc.exclusions[2].polygon[7], 260, 0);
  assert_int_equal(sc.n_faults, 2);
  assert_true(isinf(sc.faults[0].radius));
  assert_int_equal(sc.faults[0].barrier, 0);
  assert_close(sc.faults[0].factor, 0.3, 0);
  assert_int_equal(sc.faults[1].barrier, 1);
  assert_close(sc.faults[1].radius, 50, 0);
  assert_close(sc.faults[1].crossing_cost, 250, 0);
  assert_int_equal(sc.key_points[0].n_drains_to, 1);
  assert_int_equal(sc.key_points[0].drains_to[0], 3);
  assert_true(sc.key_points[4].water_table.given);
  assert_close(sc.key_points[4].water_table.elevation, 60, 0);
  assert_close(sc.key_points[4].water_table.origin[1], 295, 0);
  assert_true(sc.connectivity.given);
  assert_int_equal(sc.connectivity.n_sinks, 2);
  assert_int_equal(sc.connectivity.sinks[0], 1);
  assert_int_equal(sc.connectivity.springs[1], 4);
  assert_int_equal(sc.connectivity.matrix[1], 2);
  assert_int_equal(sc.connectivity.matrix[2], 0);
  assert_close(sc.routing.vadose_factor, 3, 0);
  assert_close(sc.routing.rise_cost, 6, 0);
  assert_close(sc.routing.phreatic_depth, 25, 0);
  assert_close(sc.routing.water_table_band, 4, 0);
  karst_geology_t *g = NULL;
  assert_int_equal(karst_geology_create(&ctx, &sc, 1, 0, &g), KARST_SUCCESS);
  assert_int_equal(karst_geology_n_springs(g), 2);
  assert_close(karst_geology_water_table(g, 1, 200, 305), 60 - 10 * tan(3 * M_PI / 180), 1e-9);
  karst_geology_free(g);
  karst_scenario_destroy(&sc);
}

/* Every fixture must fail (none may crash or leak: run under ASan). */
/* sampling.refine: all three features by default, the named ones, or none; the names written
 * back as the scenario spells them. */
static void test_refine_key(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(sc.sampling.refine, KARST_REFINE_ALL);
  char buf[64];
  assert_string_equal(karst_refine_names(sc.sampling.refine, ", ", buf, sizeof buf),
                      "horizons, water_table, permeability");
  assert_string_equal(karst_refine_names(0, ", ", buf, sizeof buf), "");
  assert_string_equal(karst_refine_names(KARST_REFINE_ALL, "/", buf, 12), "horizons/wa");
  assert_int_equal(karst_scenario_load(&ctx, DATA "refine_some.yaml", &sc), KARST_SUCCESS);
  assert_int_equal(sc.sampling.refine, KARST_REFINE_HORIZONS | KARST_REFINE_PERMEABILITY);
  assert_string_equal(karst_refine_names(sc.sampling.refine, ", ", buf, sizeof buf),
                      "horizons, permeability");
  karst_scenario_destroy(&sc);
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, DATA "refine_none.yaml", &sc), KARST_SUCCESS);
  assert_int_equal(sc.sampling.refine, 0);
  karst_scenario_destroy(&sc);
}

static void test_all_bad_fail(void **state) {
  (void)state;
  static const char *const files[] = {"above_heightfield",
                                      "above_terrain",
                                      "comments_only",
                                      "dip_direction_range",
                                      "dip_range",
                                      "domain_order",
                                      "duplicate_key",
                                      "duplicate_name",
                                      "empty",
                                      "enum_typo",
                                      "feature_radius",
                                      "fraction_range",
                                      "fracture_combine",
                                      "gamma_zero",
                                      "heightfield_malformed",
                                      "heightfield_missing",
                                      "heightfield_short",
                                      "inf",
                                      "invalid_utf8",
                                      "k_not_integer",
                                      "k_zero",
                                      "map_for_list",
                                      "misplaced_key",
                                      "missing_required",
                                      "nan",
                                      "negative_radius",
                                      "no_spring",
                                      "not_a_number",
                                      "outside_domain",
                                      "overflow",
                                      "perm_alias_cycle",
                                      "perm_empty",
                                      "perm_two_kinds",
                                      "quoted_number",
                                      "radius_min_max",
                                      "radius_min_zero",
                                      "realisations_zero",
                                      "resistance_range",
                                      "root_list",
                                      "seed_negative",
                                      "seed_overflow",
                                      "short_vector",
                                      "stratum_order",
                                      "syntax",
                                      "terrain_both",
                                      "theta_range",
                                      "two_documents",
                                      "units",
                                      "unknown_key",
                                      "unknown_path_point",
                                      "water_table_outside",
                                      "weight_negative",
                                      "drains_unknown",
                                      "drains_not_sink",
                                      "connectivity_rows",
                                      "connectivity_value",
                                      "connectivity_zero_row",
                                      "exclusion_two_shapes",
                                      "exclusion_no_shape",
                                      "prism_collinear",
                                      "keypoint_excluded",
                                      "fault_dip",
                                      "fault_kind",
                                      "dfn_radii",
                                      "kappa_negative",
                                      "water_table_on_sink",
                                      "vadose_factor",
                                      "stratum_plane_and_file",
                                      "band_in_classification",
                                      "refine_not_list",
                                      "refine_typo",
                                      "refine_twice"};
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
    char path[1024];
    snprintf(path, sizeof path, DATA "bad/%s.yaml", files[i]);
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    karst_scenario_t sc;
    karst_scenario_init(&sc);
    karst_error_t err = karst_scenario_load(&ctx, path, &sc);
    if (!err) { /* the geology's own checks, as karst validate makes them */
      karst_geology_t *g = NULL;
      err = karst_geology_create(&ctx, &sc, 0, 0, &g);
      karst_geology_free(g);
    }
    if (err == KARST_SUCCESS) print_error("%s loaded without error\n", files[i]);
    assert_int_not_equal(err, KARST_SUCCESS);
    assert_true(strncmp(ctx.errmsg, DATA, strlen(DATA)) == 0);
    karst_scenario_destroy(&sc);
  }
}

/* ------------------------------------------------------------------------ */
/* Scenarios built in code                                                  */
/* ------------------------------------------------------------------------ */

static void add_kp(karst_scenario_t *sc, const char *name, karst_keypoint_type_t t, double x,
                   double y, double z) {
  sc->key_points = realloc(sc->key_points, sizeof *sc->key_points * (sc->n_key_points + 1));
  assert_non_null(sc->key_points);
  karst_keypoint_t *kp = &sc->key_points[sc->n_key_points++];
  memset(kp, 0, sizeof *kp);
  snprintf(kp->name, sizeof kp->name, "%s", name);
  kp->type = t;
  kp->p[0] = x;
  kp->p[1] = y;
  kp->p[2] = z;
}

/* Without a file the messages have no position; the same rules apply. */
static void test_check_in_code(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  /* No key points at all: no spring. */
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_EINVAL);
  assert_string_equal(ctx.errmsg, "no spring among the 0 key points: the network needs at least "
                                  "one (key_points: - {type: spring, position: [x, y, z]})");
  add_kp(&sc, "a", KARST_KEYPOINT_SINK, 10, 10, 90);
  add_kp(&sc, "b", KARST_KEYPOINT_SPRING, 90, 90, 5);
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_SUCCESS);
  /* Single key point (a lone spring) is valid. */
  karst_scenario_t one;
  karst_scenario_init(&one);
  add_kp(&one, "s", KARST_KEYPOINT_SPRING, 50, 50, 50);
  assert_int_equal(karst_scenario_check(&ctx, &one), KARST_SUCCESS);
  karst_scenario_destroy(&one);

  sc.horizons = calloc(1, sizeof *sc.horizons);
  sc.n_horizons = 1;
  sc.horizons[0].radius = 5;
  sc.horizons[0].dip = 95;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_string_equal(ctx.errmsg, "horizons[0].dip must be within [0, 90) degrees, got 95");
  sc.horizons[0].dip = 0;
  sc.horizons[0].elevation = NAN;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "horizons[0].elevation must be a finite number"));
  sc.horizons[0].elevation = 50;
  sc.gamma = 0;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_string_equal(ctx.errmsg, "skeleton.gamma must be > 0, got 0");
  sc.gamma = 2;
  sc.reuse = 0;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_string_equal(ctx.errmsg, "skeleton.reuse must be within (0, 1], got 0");
  sc.reuse = 1;
  sc.cost.fracture_combine = 2;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_string_equal(ctx.errmsg, "cost.fracture_combine must be one of 2 names (such as 'sum'), "
                                  "got the index 2");
  sc.cost.fracture_combine = KARST_FRACTURE_MIN;
  sc.prescribed = calloc(1, sizeof *sc.prescribed);
  sc.n_prescribed = 1;
  sc.prescribed[0].a = sc.prescribed[0].b = 1;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_EINVAL);
  assert_string_equal(ctx.errmsg, "prescribed_paths[0] joins key point 'b' to itself");
  sc.prescribed[0].a = 0;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_SUCCESS);
  /* Degenerate (zero-thickness) domain. */
  sc.domain_max[2] = 0;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "domain.max z (0 m) must be greater than domain.min z"));
  sc.domain_max[2] = 100;
  strcpy(sc.key_points[1].name, "a");
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "key_points[1].name 'a' is already used"));
  karst_scenario_destroy(&sc);
}

/* ------------------------------------------------------------------------ */
/* Geology                                                                  */
/* ------------------------------------------------------------------------ */

/* π(p) by hand (Paris et al. 2021 §4.2; smooth step g(x) = 3x² - 2x³).
 * Sphere: centre 0, radius 10, resistance 0.2, falloff 10, weight 3.
 * Stratum: 0 <= z <= 5, resistance 0.5, weight 1. Background 1. */
static void test_permeability_eval(void **state) {
  (void)state;
  karst_perm_node_t kids[2];
  memset(kids, 0, sizeof kids);
  kids[0].kind = KARST_PERM_SPHERE;
  kids[0].radius = 10;
  kids[0].resistance = 0.2;
  kids[0].falloff = 10;
  kids[0].weight = 3;
  kids[1].kind = KARST_PERM_STRATUM;
  kids[1].bottom = 0;
  kids[1].top = 5;
  kids[1].resistance = 0.5;
  kids[1].weight = 1;
  karst_perm_node_t root;
  memset(&root, 0, sizeof root);
  root.children = kids;
  root.n_children = 2;
  karst_permeability_t perm = {1.0, NULL};
  const double tol = 1e-12;
  /* No tree: the background everywhere. */
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 0}), 1.0, 0);
  perm.root = &root;
  root.kind = KARST_PERM_UNION;
  /* Inside the sphere and the stratum: min(0.2, 0.5). */
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 3}), 0.2, tol);
  /* 5 m outside the sphere: g(0.5) = 0.5 -> 0.5*0.2 + 0.5*1 = 0.6. */
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 15}), 0.6, tol);
  /* 2.5 m outside: g(0.25) = 0.15625 -> 0.84375*0.2 + 0.15625 = 0.325. */
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 12.5}), 0.325, tol);
  /* Beyond the falloff: the background; in the stratum far away: 0.5. */
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 25}), 1.0, tol);
  assert_close(karst_permeability_eval(&perm, (double[]){100, 0, 3}), 0.5, tol);
  root.kind = KARST_PERM_INTERSECTION;
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 3}), 0.5, tol);
  assert_close(karst_permeability_eval(&perm, (double[]){100, 0, 3}), 1.0, tol);
  root.kind = KARST_PERM_BLEND;
  /* (3*0.2 + 1*0.5) / 4 = 0.275. */
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 3}), 0.275, tol);
  /* Sphere without falloff: a sharp edge. */
  kids[0].falloff = 0;
  root.kind = KARST_PERM_UNION;
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 10.001}), 1.0, 0);
  assert_close(karst_permeability_eval(&perm, (double[]){0, 0, 9.999}), 0.2, 0);
}

/* Horizon z = e - tan(dip) * (offset along the dip direction), by hand. */
static void test_horizon_elevation(void **state) {
  (void)state;
  karst_horizon_t h = {
      .elevation = 100, .dip = 30, .dip_direction = 90, .origin = {10, 20}, .radius = 5};
  /* 10 m east, dipping 30° east: 100 - 10 tan 30° = 94.226497... */
  assert_close(karst_horizon_elevation(&h, 20, 20), 100 - 10 / sqrt(3.0), 1e-12);
  /* Along the strike (north): unchanged. */
  assert_close(karst_horizon_elevation(&h, 10, 35), 100, 1e-12);
  /* Up-dip (west): rises. */
  assert_close(karst_horizon_elevation(&h, 0, 20), 100 + 10 / sqrt(3.0), 1e-12);
  /* Dip 45° towards south-west (225°): from the origin to (9, 19) moves
   * sqrt(2) m down-dip -> 100 - sqrt(2). */
  h.dip = 45;
  h.dip_direction = 225;
  assert_close(karst_horizon_elevation(&h, 9, 19), 100 - sqrt(2.0), 1e-12);
  /* Flat horizon. */
  h.dip = 0;
  assert_close(karst_horizon_elevation(&h, -1000, 5000), 100, 0);
}

/* n = (sin δ sin α, sin δ cos α, cos δ): the plane's upward normal leans toward the dip direction.
 */
static void test_plane_normal(void **state) {
  (void)state;
  double n[3];
  karst_plane_normal(0, 0, n);
  assert_close(n[0], 0, 1e-15);
  assert_close(n[1], 0, 1e-15);
  assert_close(n[2], 1, 1e-15);
  karst_plane_normal(90, 90, n); /* vertical plane striking N-S */
  assert_close(n[0], 1, 1e-15);
  assert_close(n[1], 0, 1e-15);
  assert_close(n[2], 0, 1e-15);
  karst_plane_normal(180, 45, n);
  assert_close(n[0], 0, 1e-15);
  assert_close(n[1], -sqrt(0.5), 1e-15);
  assert_close(n[2], sqrt(0.5), 1e-15);
}

/* Bilinear terrain on corner.asc, by hand: XLLCORNER 100, YLLCORNER 200,
 * CELLSIZE 10 -> centres at x 105, 115 and y 205, 215; rows north to south
 * "20 40" / "0 10" -> z00 = 0, z10 = 10, z01 = 20, z11 = 40. */
static void test_terrain_bilinear(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  t.elevation = 7;
  assert_close(karst_terrain_height(&t, 1e6, -1e6), 7, 0); /* flat */
  assert_int_equal(karst_terrain_load_grid(&ctx, DATA "terrain/corner.asc", &t), KARST_SUCCESS);
  assert_int_equal(t.is_grid, 1);
  assert_string_equal(t.path, DATA "terrain/corner.asc");
  assert_close(t.xll, 105, 0);
  assert_close(t.yll, 205, 0);
  assert_close(t.z[0], 0, 0);
  assert_close(t.z[3], 40, 0);
  assert_close(t.zmin, 0, 0);
  assert_close(t.zmax, 40, 0);
  assert_close(karst_terrain_height(&t, 105, 205), 0, 1e-12);
  assert_close(karst_terrain_height(&t, 115, 215), 40, 1e-12);
  /* Centre: mean of the corners = 17.5. */
  assert_close(karst_terrain_height(&t, 110, 210), 17.5, 1e-12);
  /* u = 0.25, v = 0.5: 0.5*(0.75*0 + 0.25*10) + 0.5*(0.75*20 + 0.25*40) = 13.75. */
  assert_close(karst_terrain_height(&t, 107.5, 210), 13.75, 1e-12);
  /* Clamped outside the centres: (110, 0) -> u = 0.5, v = 0 -> 5. */
  assert_close(karst_terrain_height(&t, 110, 0), 5, 1e-12);
  assert_close(karst_terrain_height(&t, 0, 0), 0, 1e-12);
  assert_close(karst_terrain_height(&t, 1000, 1000), 40, 1e-12);
  /* Lipschitz: |dh/dx| <= max(10, 20)/10, |dh/dy| <= max(20, 30)/10, reached
   * together at the corner (u, v) = (1, 1): sqrt(2² + 3²) = 3.6055512754639891. */
  assert_close(t.lipschitz, sqrt(13.0), 1e-12);
  free(t.z);
  free(t.path);
}

static void expect_grid_error(const char *file, karst_error_t code, int line, int col,
                              const char *part) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  char path[1024], prefix[1100];
  snprintf(path, sizeof path, DATA "terrain/%s", file);
  snprintf(prefix, sizeof prefix, "%s:%d:%d: ", path, line, col);
  karst_error_t err = karst_terrain_load_grid(&ctx, path, &t);
  if (err != code || strncmp(ctx.errmsg, prefix, strlen(prefix)) || !strstr(ctx.errmsg, part))
    print_error("got %s: \"%s\"\nexpected \"%s...%s\"\n", karst_error_name(err), ctx.errmsg, prefix,
                part);
  assert_int_equal(err, code);
  assert_true(strncmp(ctx.errmsg, prefix, strlen(prefix)) == 0);
  assert_non_null(strstr(ctx.errmsg, part));
  /* The terrain is untouched on failure. */
  assert_int_equal(t.is_grid, 0);
  assert_null(t.z);
  assert_null(t.path);
}

/* Heightfield errors name the .asc file, line, column and field. */
static void test_heightfield_errors(void **state) {
  (void)state;
  expect_grid_error("bad_cellsize.asc", KARST_ERANGE, 5, 10, "cellsize must be > 0, got -5");
  expect_grid_error("short_row.asc", KARST_EPARSE, 7, 4, "row 2 has 2 values, expected ncols = 3");
  expect_grid_error("nodata.asc", KARST_EINVAL, 8, 3, "row 2, column 2 is NODATA (-9999)");
  expect_grid_error("unknown_header.asc", KARST_EPARSE, 5, 1,
                    "unknown ESRI grid header field 'cellsise'");
  expect_grid_error("unknown_header.asc", KARST_EPARSE, 5, 1, "did you mean 'cellsize'?");
  expect_grid_error("missing_cellsize.asc", KARST_EPARSE, 5, 1,
                    "the ESRI grid header is missing cellsize");
  expect_grid_error("too_few_rows.asc", KARST_EPARSE, 7, 1,
                    "the file ends after 2 rows, expected nrows = 3");
  expect_grid_error("not_a_number.asc", KARST_EPARSE, 7, 3,
                    "row 2, column 2: elevation must be a number, got x4");
  expect_grid_error("empty.asc", KARST_EPARSE, 1, 1, "empty heightfield");
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  assert_int_equal(karst_terrain_load_grid(&ctx, DATA "terrain/missing.asc", &t), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "terrain/missing.asc: cannot open"));
}

/* FNV-1a 64 test vectors from the FNV reference (Fowler, Noll, Vo):
 * "" -> cbf29ce484222325, "a" -> af63dc4c8601ec8c, "foobar" -> 85944171f73967e8. */
static void test_file_hash(void **state) {
  (void)state;
  static const struct {
    const char *text, *hash;
  } v[] = {{"", "cbf29ce484222325"}, {"a", "af63dc4c8601ec8c"}, {"foobar", "85944171f73967e8"}};
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char path[] = "/tmp/karst_hash_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  close(fd);
  for (size_t i = 0; i < 3; i++) {
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    fputs(v[i].text, fp);
    fclose(fp);
    char out[17];
    assert_int_equal(karst_file_hash(&ctx, path, out), KARST_SUCCESS);
    assert_string_equal(out, v[i].hash);
  }
  unlink(path);
  char out[17];
  assert_int_equal(karst_file_hash(&ctx, path, out), KARST_EIO);
}

/* Levenshtein distances by hand; suggestions only when close. */
static void test_suggest(void **state) {
  (void)state;
  assert_int_equal(karst_i_edit_distance("kitten", "sitting", 10), 3);
  assert_int_equal(karst_i_edit_distance("", "abc", 10), 3);
  assert_int_equal(karst_i_edit_distance("dip", "dip", 10), 0);
  assert_int_equal(karst_i_edit_distance("abcdef", "uvwxyz", 2), 3); /* stopped at cap + 1 */
  static const char *const kinds[] = {"sink", "spring", "waypoint"};
  assert_string_equal(karst_i_suggest("sinkk", kinds, 3), "sink");
  assert_string_equal(karst_i_suggest("sprnig", kinds, 3), "spring");
  assert_null(karst_i_suggest("outlet", kinds, 3));
  assert_null(karst_i_suggest("x", kinds, 0));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_init_defaults),
      cmocka_unit_test(test_branchwork),
      cmocka_unit_test(test_minimal_defaults),
      cmocka_unit_test(test_full_file),
      cmocka_unit_test(test_failure_keeps_scenario),
      cmocka_unit_test(test_bad_syntax),
      cmocka_unit_test(test_bad_empty),
      cmocka_unit_test(test_bad_comments_only),
      cmocka_unit_test(test_bad_invalid_utf8),
      cmocka_unit_test(test_bad_two_documents),
      cmocka_unit_test(test_bad_root_list),
      cmocka_unit_test(test_bad_deep_nesting),
      cmocka_unit_test(test_bad_unknown_key),
      cmocka_unit_test(test_bad_misplaced_key),
      cmocka_unit_test(test_bad_duplicate_key),
      cmocka_unit_test(test_bad_missing_required),
      cmocka_unit_test(test_bad_not_a_number),
      cmocka_unit_test(test_bad_quoted_number),
      cmocka_unit_test(test_bad_map_for_list),
      cmocka_unit_test(test_bad_short_vector),
      cmocka_unit_test(test_bad_k_not_integer),
      cmocka_unit_test(test_bad_seed_negative),
      cmocka_unit_test(test_bad_seed_overflow),
      cmocka_unit_test(test_bad_enum_typo),
      cmocka_unit_test(test_bad_units),
      cmocka_unit_test(test_bad_dip_range),
      cmocka_unit_test(test_bad_dip_direction_range),
      cmocka_unit_test(test_bad_negative_radius),
      cmocka_unit_test(test_bad_resistance_range),
      cmocka_unit_test(test_bad_theta_range),
      cmocka_unit_test(test_bad_gamma_zero),
      cmocka_unit_test(test_bad_reuse_zero),
      cmocka_unit_test(test_bad_reuse_above_one),
      cmocka_unit_test(test_bad_fracture_combine),
      cmocka_unit_test(test_bad_k_zero),
      cmocka_unit_test(test_bad_weight_negative),
      cmocka_unit_test(test_bad_fraction_range),
      cmocka_unit_test(test_bad_reach_ratio_zero),
      cmocka_unit_test(test_bad_points_ratio_zero),
      cmocka_unit_test(test_bad_anchor_typo),
      cmocka_unit_test(test_bad_refine_not_list),
      cmocka_unit_test(test_bad_refine_typo),
      cmocka_unit_test(test_bad_refine_twice),
      cmocka_unit_test(test_refine_key),
      cmocka_unit_test(test_bad_amplification_points_total),
      cmocka_unit_test(test_bad_realisations_zero),
      cmocka_unit_test(test_bad_radius_min_max),
      cmocka_unit_test(test_bad_radius_min_zero),
      cmocka_unit_test(test_bad_domain_order),
      cmocka_unit_test(test_bad_stratum_order),
      cmocka_unit_test(test_bad_feature_radius),
      cmocka_unit_test(test_bad_water_table_outside),
      cmocka_unit_test(test_bad_drains_unknown),
      cmocka_unit_test(test_bad_drains_not_sink),
      cmocka_unit_test(test_bad_connectivity_rows),
      cmocka_unit_test(test_bad_connectivity_value),
      cmocka_unit_test(test_bad_connectivity_zero_row),
      cmocka_unit_test(test_bad_exclusion_two_shapes),
      cmocka_unit_test(test_bad_exclusion_no_shape),
      cmocka_unit_test(test_bad_prism_collinear),
      cmocka_unit_test(test_bad_keypoint_excluded),
      cmocka_unit_test(test_bad_fault_dip),
      cmocka_unit_test(test_bad_fault_kind),
      cmocka_unit_test(test_bad_dfn_radii),
      cmocka_unit_test(test_bad_kappa_negative),
      cmocka_unit_test(test_bad_water_table_on_sink),
      cmocka_unit_test(test_bad_vadose_factor),
      cmocka_unit_test(test_bad_stratum_plane_and_file),
      cmocka_unit_test(test_bad_band_in_classification),
      cmocka_unit_test(test_geology_file),
      cmocka_unit_test(test_bad_nan),
      cmocka_unit_test(test_bad_inf),
      cmocka_unit_test(test_bad_overflow),
      cmocka_unit_test(test_bad_outside_domain),
      cmocka_unit_test(test_bad_above_terrain),
      cmocka_unit_test(test_bad_above_heightfield),
      cmocka_unit_test(test_bad_no_spring),
      cmocka_unit_test(test_bad_duplicate_name),
      cmocka_unit_test(test_bad_unknown_path_point),
      cmocka_unit_test(test_bad_perm_two_kinds),
      cmocka_unit_test(test_bad_perm_empty),
      cmocka_unit_test(test_bad_perm_alias_cycle),
      cmocka_unit_test(test_bad_terrain_both),
      cmocka_unit_test(test_bad_heightfield_missing),
      cmocka_unit_test(test_bad_heightfield_short),
      cmocka_unit_test(test_bad_heightfield_malformed),
      cmocka_unit_test(test_all_bad_fail),
      cmocka_unit_test(test_check_in_code),
      cmocka_unit_test(test_permeability_eval),
      cmocka_unit_test(test_horizon_elevation),
      cmocka_unit_test(test_plane_normal),
      cmocka_unit_test(test_terrain_bilinear),
      cmocka_unit_test(test_heightfield_errors),
      cmocka_unit_test(test_file_hash),
      cmocka_unit_test(test_suggest),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
