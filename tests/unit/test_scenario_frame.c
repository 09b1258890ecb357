/* The scenario keys of issue 12 (docs/scenario.md "Coordinates", "Conditioning", "Generations"):
 * what they read (positions from latitude/longitude against cs2cs, stations and entrances from
 * DowProv.3d against Survex's dump3d values, generations' defaults), and hostile input: every
 * bad value refused with FILE:LINE and the key named, nothing half-built, and 200 random
 * mutations of a conditioned scenario loaded without a crash. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"
#include "karst/conditioning.h"
#include "test_util.h"

#define SURVEY KARST_SOURCE_DIR "/datasets/surveys/dowprov/DowProv.3d"
/* The agreement: 1 mm. */
#define TOL_M 1e-3
/* Mutations of test_mutations: each load opens PROJ and reads DowProv.3d (about 15 ms, ten times
 * that under ASan), so a few hundred keep the test well under a minute there. */
#define MUTATIONS 200

/* A domain around DowProv in EPSG:7405 (its own CRS), every station below the flat terrain. */
#define HEAD                                                                                       \
  "name: t\ncrs: EPSG:7405\ndomain: {min: [398200, 472750, 250], max: [399400, 474450, 700]}\n"    \
  "terrain: {elevation: 600}\nwater_table: {elevation: 320}\n"                                     \
  "sampling: {fill_radius: 60, feature_radius: 45, k: 16}\n"

static char path_buf[256];

static const char *write_yaml(const char *text) {
  snprintf(path_buf, sizeof path_buf, "scenario_frame_%d.yaml", (int)getpid());
  FILE *f = fopen(path_buf, "wb");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
  return path_buf;
}

/* Load @p text; expect @p code and @p part in the message, "FILE:" first and nothing half-built. */
static void expect_bad(const char *text, karst_error_t code, const char *part) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  const char *p = write_yaml(text);
  karst_error_t err = karst_scenario_load(&ctx, p, &sc);
  if (err != code || !strstr(ctx.errmsg, part) || strncmp(ctx.errmsg, p, strlen(p)) != 0)
    print_error("got %s: \"%s\"\nexpected %s: \"%s:...%s...\"\n", karst_error_name(err), ctx.errmsg,
                karst_error_name(code), p, part);
  assert_int_equal(err, code);
  assert_non_null(strstr(ctx.errmsg, part));
  assert_int_equal(strncmp(ctx.errmsg, p, strlen(p)), 0);
  assert_null(sc.path);
  assert_int_equal(sc.n_key_points, 0);
  assert_null(sc.conditioning.data);
  karst_scenario_destroy(&sc);
  remove(p);
}

static void test_hostile(void **state) {
  (void)state;
  const char *kp = "key_points:\n  - {name: sp, type: spring, position: [398360, 474310, 320]}\n";
  char buf[4096];
#define CASE(body, code, part)                                                                     \
  do {                                                                                             \
    snprintf(buf, sizeof buf, "%s%s%s", HEAD, kp, body);                                           \
    expect_bad(buf, code, part);                                                                   \
  } while (0)
  CASE("crs: NOT A CRS\n", KARST_EINVAL, "crs");
  CASE("crs: [1, 2]\n", KARST_EINVAL, "crs");
  CASE("conditioning: {surveys: nope.3d}\n", KARST_EINVAL, "must be a list of survey files");
  CASE("conditioning: {surveys: []}\n", KARST_ERANGE, "1 to 1000 surveys");
  CASE("conditioning: {surveys: [/nonexistent/x.3d]}\n", KARST_EIO, "/nonexistent/x.3d");
  CASE("conditioning: {}\n", KARST_EINVAL, "'surveys'");
  CASE("conditioning: {surveys: [" SURVEY "], sinks: maybe}\n", KARST_EINVAL, "sinks");
  CASE("conditioning: {surveys: [" SURVEY "], sinks: [no.such.station]}\n", KARST_ENOTFOUND,
       "no.such.station");
  CASE("conditioning: {surveys: [" SURVEY "], cost_factor: 0}\n", KARST_ERANGE, "cost_factor");
  CASE("conditioning: {surveys: [" SURVEY "], cost_factor: 2}\n", KARST_ERANGE, "cost_factor");
  CASE("conditioning: {surveys: [" SURVEY "], generation: 2}\n", KARST_ERANGE,
       "conditioning.generation is 2");
  CASE("conditioning: {surveys: [{file: " SURVEY ", crs: BOGUS}]}\n", KARST_EINVAL, "BOGUS");
  CASE("conditioning: {surveys: [{crs: EPSG:27700}]}\n", KARST_EINVAL, "'file'");
  CASE("conditioning: {surveys: [" SURVEY "], frob: 1}\n", KARST_EINVAL, "unknown key 'frob'");
  CASE("generations: 3\n", KARST_EINVAL, "generations must be a list");
  CASE("generations: []\n", KARST_ERANGE, "1 to 16 generations");
  CASE("generations: [{cohesion: 0}]\n", KARST_ERANGE, "cohesion");
  CASE("generations: [{cohesion: 1.5}]\n", KARST_ERANGE, "cohesion");
  CASE("generations: [{frob: 1}]\n", KARST_EINVAL, "unknown key 'frob'");
  CASE("generations: [{key_points: 7}]\n", KARST_EINVAL, "key_points must be a list");
  CASE("generations: [{skeleton: {gamma: -1}}]\n", KARST_ERANGE, "gamma");
  CASE("generations: [{water_table: {elevation: nope}}]\n", KARST_EINVAL, "water_table");
#undef CASE
  /* Key-point positions. */
  static const struct {
    const char *kp, *part;
    karst_error_t code;
  } kps[] = {
      {"{name: a, type: sink, position: [398400, 474000, 400], latitude: 54.1, longitude: -2, "
       "elevation: 400}",
       "needs exactly one of", KARST_EINVAL},
      {"{name: a, type: sink}", "needs exactly one of", KARST_EINVAL},
      {"{name: a, type: sink, latitude: 54.15, longitude: -2.02}",
       "needs all of latitude, longitude and elevation", KARST_EINVAL},
      {"{name: a, type: sink, latitude: 95, longitude: -2.02, elevation: 400}", "latitude",
       KARST_ERANGE},
      {"{name: a, type: sink, latitude: 54.15, longitude: 400, elevation: 400}", "longitude",
       KARST_ERANGE},
      {"{name: a, type: sink, station: dowcave.dow1.1}", "needs a conditioning section",
       KARST_ENOTFOUND},
      {"{name: a, type: sink, station: [1]}", "station", KARST_EINVAL},
      {"{name: a, type: sink, latitude: 40.0, longitude: -2.02, elevation: 400}",
       "outside the domain", KARST_ERANGE},
  };
  for (size_t i = 0; i < sizeof kps / sizeof kps[0]; i++) {
    snprintf(buf, sizeof buf, "%s%s  - %s\n", HEAD, kp, kps[i].kp);
    expect_bad(buf, kps[i].code, kps[i].part);
  }
  /* Latitude/longitude without a crs. */
  snprintf(buf, sizeof buf,
           "name: t\ndomain: {min: [0, 0, 0], max: [100, 100, 100]}\nkey_points:\n"
           "  - {name: sp, type: spring, position: [50, 50, 10]}\n"
           "  - {name: a, type: sink, latitude: 54.15, longitude: -2.02, elevation: 40}\n");
  expect_bad(buf, KARST_EINVAL, "states no crs");
}

/* What the keys read: a latitude/longitude key point where cs2cs puts it, a station key point and
 * the entrance sinks at the stations' dump3d positions, one waypoint per unjoined survey piece,
 * generations with their defaults. */
static void test_reads(void **state) {
  (void)state;
  char buf[4096];
  snprintf(buf, sizeof buf,
           "%skey_points:\n  - {name: sp, type: spring, position: [398360, 474310, 320]}\n"
           "  - {name: ll, type: sink, latitude: 54.15731224, longitude: -2.01527792, "
           "elevation: 470}\n"
           "  - {name: pp, type: waypoint, station: providencepot.ppot1.10}\n"
           "skeleton: {gamma: 1.5}\n"
           "generations:\n  - {name: old, cohesion: 1}\n  - {water_table: {elevation: 300}}\n"
           "conditioning: {surveys: [" SURVEY "], sinks: entrances}\n",
           HEAD);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  const char *p = write_yaml(buf);
  karst_error_t err = karst_scenario_load(&ctx, p, &sc);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  remove(p);
  /* cs2cs -f %.6f EPSG:4326 EPSG:27700 <<< "54.15731224 -2.01527792": 399100.000565 473500.000053
   * (PROJ 9.1.1, Debian 12), and the height passes through. */
  const double want_ll[3] = {399100.000565, 473500.000053, 470};
  const karst_keypoint_t *ll = &sc.key_points[1];
  for (int a = 0; a < 3; a++)
    assert_true(fabs(ll->p[a] - want_ll[a]) <= TOL_M);
  /* dump3d DowProv.3d: NODE 398378.00 474300.00 334.00 [dowcave.entrance] ENTRANCE ...;
   * NODE 399213.00 472887.00 401.00 [providencepot.entrance] ENTRANCE ... */
  /* (Survex equates dowcave.entrance with dowcave.dow1.1: the key point may carry either name.) */
  static const double entrances[2][3] = {{398378.00, 474300.00, 334.00},
                                         {399213.00, 472887.00, 401.00}};
  int found = 0;
  for (int k = 0; k < sc.n_key_points; k++) {
    const karst_keypoint_t *q = &sc.key_points[k];
    for (int e = 0; e < 2; e++)
      if (fabs(q->p[0] - entrances[e][0]) <= TOL_M && fabs(q->p[1] - entrances[e][1]) <= TOL_M &&
          fabs(q->p[2] - entrances[e][2]) <= TOL_M) {
        found++;
        assert_int_equal(q->type, KARST_KEYPOINT_SINK);
        assert_int_equal(q->generation, 2); /* the survey joins the last generation */
        assert_true(q->station_index >= 0);
      }
  }
  assert_int_equal(found, 2);
  const karst_survey_set_t *s = sc.conditioning.data;
  assert_non_null(s);
  /* 689 legs: dump3d's 759 LINEs less 25 SURFACE, 25 DUPLICATE and 20 SPLAY. */
  assert_int_equal(s->n_legs, 689);
  karst_int_t st = karst_survey_find_station(s, "providencepot.ppot1.10");
  assert_true(st >= 0);
  assert_int_equal(sc.key_points[2].station_index, st);
  assert_memory_equal(sc.key_points[2].p, &s->xyz[3 * st], 3 * sizeof(double));
  /* Every piece of the survey has a key point on one of its stations. */
  for (karst_int_t c = 0; c < s->n_components; c++) {
    int on = 0;
    for (int k = 0; k < sc.n_key_points && !on; k++)
      on = sc.key_points[k].station_index >= 0 && s->component[sc.key_points[k].station_index] == c;
    assert_true(on);
  }
  /* Generations: defaults from the top level, names, water tables. */
  assert_int_equal(sc.n_generations, 2);
  assert_string_equal(sc.generations[0].name, "old");
  assert_string_equal(sc.generations[1].name, "generation2");
  assert_true(sc.generations[0].gamma == 1.5 && sc.generations[1].gamma == 1.5);
  assert_true(sc.generations[0].cohesion == 1.0);
  assert_true(sc.generations[1].cohesion == KARST_SCENARIO_DEFAULT_COHESION);
  assert_true(sc.generations[1].water_table.given && !sc.generations[0].water_table.given);
  assert_string_equal(sc.crs, "EPSG:7405");
  karst_scenario_destroy(&sc);
}

/* MUTATIONS (200) random mutations (a byte replaced, deleted or duplicated) of a conditioned
 * two-generation scenario: each loads or is refused with a message, never a crash (ASan/UBSan
 * builds). */
static void test_mutations(void **state) {
  (void)state;
  char good[4096];
  snprintf(good, sizeof good,
           "%skey_points:\n  - {name: sp, type: spring, position: [398360, 474310, 320]}\n"
           "  - {name: ll, type: sink, latitude: 54.15731224, longitude: -2.01527792, "
           "elevation: 470}\n"
           "generations:\n  - {name: old, cohesion: 1, key_points: [{name: w, type: waypoint, "
           "station: dowcave.dow1.3}]}\n  - {water_table: {elevation: 300}}\n"
           "conditioning: {surveys: [{file: " SURVEY
           ", crs: EPSG:7405}], sinks: [dowcave.dow1.5]}\n",
           HEAD);
  const char *alphabet = "{}[]:,- \n'\"#&*!|>%@`0123456789.eE+abcxyz\t\\";
  uint64_t x = 0x9E3779B97F4A7C15ull;
  size_t n = strlen(good);
  char *m = malloc(n + 2);
  assert_non_null(m);
  int loaded = 0, refused = 0;
  for (int it = 0; it < MUTATIONS; it++) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    size_t at = (size_t)(x % n);
    int op = (int)((x >> 20) % 3);
    char c = alphabet[(x >> 32) % strlen(alphabet)];
    size_t len = 0;
    for (size_t i = 0; i < n; i++) {
      if (i == at && op == 1) continue;
      m[len++] = i == at && op == 0 ? c : good[i];
      if (i == at && op == 2) m[len++] = good[i];
    }
    m[len] = '\0';
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    karst_scenario_t sc;
    karst_scenario_init(&sc);
    const char *p = write_yaml(m);
    karst_error_t err = karst_scenario_load(&ctx, p, &sc);
    if (err) {
      refused++;
      assert_true(ctx.errmsg[0] != '\0');
      assert_int_equal(sc.n_key_points, 0);
    } else {
      loaded++;
    }
    karst_scenario_destroy(&sc);
  }
  remove(path_buf);
  free(m);
  print_message("mutations: %d loaded, %d refused\n", loaded, refused);
  assert_true(loaded > 0 && refused > 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_hostile),
      cmocka_unit_test(test_reads),
      cmocka_unit_test(test_mutations),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
