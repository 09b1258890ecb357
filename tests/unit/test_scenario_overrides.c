/* Scenario overrides by key path (karst_scenario_load_with_overrides) and the scenario written
 * back with them (karst_scenario_write_with_overrides), src/scenario/overrides.c.
 *
 * Expected values are the override values themselves or the values written in the fixture
 * files (tests/data/scenarios/good/, datasets/scenarios/); messages are checked for the
 * override's origin, the key path and the parser's own wording (the same rule as a value of
 * the file). Hostile key paths and values are refused with a message, never a crash. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"
#include "test_util.h"

#define GOOD KARST_SOURCE_DIR "/tests/data/scenarios/good/"
#define BRANCHWORK KARST_SOURCE_DIR "/datasets/scenarios/branchwork.yaml"

/* Load @p path with one numeric override KEY=VALUE (origin "test"); returns the error. */
static karst_error_t load1(karst_ctx_t *ctx, const char *path, const char *key, const char *value,
                           karst_override_type_t *type, karst_scenario_t *sc) {
  karst_scenario_override_t ov = {key, value, "test", 1};
  return karst_scenario_load_with_overrides(ctx, path, &ov, 1, type, sc);
}

/* An override replaces the file's value and leaves every other one alone; integer keys are read
 * as integers (branchwork.yaml: gamma 2.0, tortuosity 0.4, amplification.steps 2, reach 250,
 * reach_ratio 0.06, fracture 0 weight 1, domain max z 100). */
static void test_replace_values(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_scenario_override_t ov[] = {{"skeleton.gamma", "3.25", NULL, 1},
                                    {"amplification.steps", "4", NULL, 1},
                                    {"fractures[0].weight", "2.5", NULL, 1},
                                    {"domain.max[2]", "120", NULL, 1},
                                    {"amplification.reach", "100", NULL, 1}};
  karst_override_type_t types[5] = {0};
  karst_error_t err = karst_scenario_load_with_overrides(&ctx, BRANCHWORK, ov, 5, types, &sc);
  assert_int_equal(err, KARST_SUCCESS);
  assert_close(sc.gamma, 3.25, 0);
  assert_int_equal(sc.amplification.steps, 4);
  assert_close(sc.fractures[0].weight, 2.5, 0);
  assert_close(sc.domain_max[2], 120, 0);
  assert_close(sc.amplification.reach, 100, 0);
  assert_close(sc.amplification.reach_ratio, 0.06, 0); /* untouched */
  assert_close(sc.tortuosity, 0.4, 0);                 /* untouched */
  assert_int_equal(sc.amplification.points, 10);       /* untouched */
  assert_int_equal(types[0], KARST_OVERRIDE_NUMBER);
  assert_int_equal(types[1], KARST_OVERRIDE_INTEGER);
  assert_int_equal(types[2], KARST_OVERRIDE_NUMBER);
  assert_int_equal(types[3], KARST_OVERRIDE_NUMBER);
  assert_int_equal(types[4], KARST_OVERRIDE_NUMBER);
  karst_scenario_destroy(&sc);
}

/* Keys read by custom readers: a node of the permeability tree and the flat terrain
 * (hillside.yaml: union[0] is a sphere of radius 30; its heightfield still resolves). */
static void test_nested_readers(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_override_type_t t;
  assert_int_equal(load1(&ctx, KARST_SOURCE_DIR "/datasets/scenarios/hillside.yaml",
                         "permeability.tree.union[0].sphere.radius", "40", &t, &sc),
                   KARST_SUCCESS);
  assert_int_equal(t, KARST_OVERRIDE_NUMBER);
  assert_close(sc.permeability.root->children[0].radius, 40, 0);
  assert_int_equal(sc.terrain.is_grid, 1);
  assert_int_equal(load1(&ctx, KARST_SOURCE_DIR "/datasets/scenarios/hillside.yaml",
                         "permeability.tree.union[0].sphere.center[2]", "75", &t, &sc),
                   KARST_SUCCESS);
  assert_close(sc.permeability.root->children[0].center[2], 75, 0);
  assert_int_equal(load1(&ctx, BRANCHWORK, "terrain.elevation", "110", &t, &sc), KARST_SUCCESS);
  assert_close(sc.terrain.elevation, 110, 0);
  karst_scenario_destroy(&sc);
}

/* A key the file leaves out is added with the maps leading to it (minimal.yaml has no skeleton
 * and no amplification block); the default is replaced. */
static void test_add_missing_key(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_scenario_override_t ov[] = {{"skeleton.gamma", "0.75", NULL, 1},
                                    {"amplification.points", "7", NULL, 1},
                                    {"tortuosity", "0.6", NULL, 1}};
  assert_int_equal(karst_scenario_load_with_overrides(&ctx, GOOD "minimal.yaml", ov, 3, NULL, &sc),
                   KARST_SUCCESS);
  assert_close(sc.gamma, 0.75, 0);
  assert_int_equal(sc.amplification.points, 7);
  assert_close(sc.tortuosity, 0.6, 0);
  assert_close(sc.reuse, KARST_SCENARIO_DEFAULT_REUSE, 0); /* default kept */
  karst_scenario_destroy(&sc);
}

/* Each refused override: error code and the pieces the message must contain. */
typedef struct bad_case {
  const char *path, *key, *value;
  karst_error_t code;
  const char *expect[3];
} bad_case_t;

static void test_refused(void **state) {
  (void)state;
  static const bad_case_t cases[] = {
      /* unknown keys get the parser's "did you mean" */
      {BRANCHWORK,
       "skeleton.gama",
       "1",
       KARST_EINVAL,
       {": test: ", "unknown key 'gama' in skeleton", "did you mean 'gamma'?"}},
      {BRANCHWORK,
       "amplifcation.steps",
       "1",
       KARST_EINVAL,
       {"unknown key 'amplifcation'", "did you mean 'amplification'?", NULL}},
      /* keys that hold no number */
      {BRANCHWORK, "name", "1", KARST_EINVAL, {"name is not a numeric key (it holds a string)"}},
      {BRANCHWORK,
       "cost.fracture_combine",
       "1",
       KARST_EINVAL,
       {"cost.fracture_combine is not a numeric key", "one of the names sum, min", NULL}},
      {BRANCHWORK, "random.seed", "5", KARST_EINVAL, {"random.seed is not a numeric key", NULL}},
      {BRANCHWORK, "units", "1", KARST_EINVAL, {"units is not a numeric key", NULL}},
      {BRANCHWORK, "skeleton", "1", KARST_EINVAL, {"skeleton must be a map of keys, got 1", NULL}},
      {BRANCHWORK,
       "key_points[0].name",
       "3",
       KARST_EINVAL,
       {"key_points[0].name is not a numeric"}},
      /* the file's rules apply to the value */
      {BRANCHWORK,
       "tortuosity",
       "2",
       KARST_ERANGE,
       {": test: ", "tortuosity must be within [0, 1], got 2", NULL}},
      {BRANCHWORK, "skeleton.gamma", "0", KARST_ERANGE, {"skeleton.gamma must be > 0, got 0"}},
      {BRANCHWORK,
       "amplification.steps",
       "2.5",
       KARST_EINVAL,
       {"amplification.steps must be an integer, got 2.5", NULL}},
      {BRANCHWORK, "skeleton.gamma", "abc", KARST_EINVAL, {"skeleton.gamma must be a number"}},
      {BRANCHWORK, "skeleton.gamma", ".nan", KARST_ERANGE, {"must be a finite number"}},
      {BRANCHWORK, "skeleton.gamma", "[1, 2]", KARST_EINVAL, {"skeleton.gamma must be a number"}},
      /* a cross-field rule names the overrides */
      {BRANCHWORK,
       "sampling.feature_radius",
       "50",
       KARST_ERANGE,
       {"must not exceed sampling.fill_radius", "(with sampling.feature_radius=50)", NULL}},
      /* paths that lead nowhere */
      {BRANCHWORK,
       "tortuosity.x",
       "1",
       KARST_EINVAL,
       {"tortuosity is a single value (line ", "not a map: there is no key tortuosity.x", NULL}},
      {BRANCHWORK,
       "fractures[3].weight",
       "1",
       KARST_ERANGE,
       {"fractures has 1 item (indices from 0), so there is no fractures[3]", NULL}},
      {BRANCHWORK, "skeleton[0]", "1", KARST_EINVAL, {"skeleton is a map (line ", "not a list"}},
      {GOOD "minimal.yaml",
       "fractures[0].weight",
       "1",
       KARST_EINVAL,
       {"fractures is not in the scenario file, so it has no item [0]", NULL}},
      /* malformed paths */
      {BRANCHWORK, "", "1", KARST_EINVAL, {"the key is empty", NULL}},
      {BRANCHWORK, "skeleton..gamma", "1", KARST_EINVAL, {"each part of the key must be a name"}},
      {BRANCHWORK, "fractures[x].dip", "1", KARST_EINVAL, {"a list index must be a whole number"}},
      {BRANCHWORK, "fractures[-1].dip", "1", KARST_EINVAL, {"a list index must be a whole number"}},
      {BRANCHWORK,
       "fractures[99999999999999999999].dip",
       "1",
       KARST_EINVAL,
       {"a list index must be a whole number"}},
      {BRANCHWORK, "skeleton gamma", "1", KARST_EINVAL, {"joined by '.'", NULL}},
      {BRANCHWORK, "skeleton.gamma\n", "1", KARST_EINVAL, {"joined by '.'", NULL}},
  };
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const bad_case_t *c = &cases[i];
    karst_scenario_t sc;
    karst_scenario_init(&sc);
    karst_error_t err = load1(&ctx, c->path, c->key, c->value, NULL, &sc);
    if (err != c->code) {
      print_error("case %zu (%s=%s): code %d, expected %d: %s\n", i, c->key, c->value, err, c->code,
                  ctx.errmsg);
      fail();
    }
    for (int k = 0; k < 3 && c->expect[k]; k++) {
      if (!strstr(ctx.errmsg, c->expect[k])) {
        print_error("case %zu (%s=%s): message lacks \"%s\": %s\n", i, c->key, c->value,
                    c->expect[k], ctx.errmsg);
        fail();
      }
    }
    assert_null(sc.path); /* untouched on failure */
    karst_scenario_destroy(&sc);
  }
}

/* A key overridden twice, a NULL value and a path longer than the limit are refused. */
static void test_refused_lists(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_scenario_override_t twice[] = {{"tortuosity", "0.2", NULL, 1},
                                       {"tortuosity", "0.3", NULL, 1}};
  assert_int_equal(karst_scenario_load_with_overrides(&ctx, BRANCHWORK, twice, 2, NULL, &sc),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "the key tortuosity is overridden twice"));
  karst_scenario_override_t null_value = {"tortuosity", NULL, NULL, 1};
  assert_int_equal(karst_scenario_load_with_overrides(&ctx, BRANCHWORK, &null_value, 1, NULL, &sc),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "override tortuosity=: no value given"));
  char longkey[600];
  memset(longkey, 'a', sizeof longkey - 1);
  longkey[sizeof longkey - 1] = '\0';
  karst_scenario_override_t lk = {longkey, "1", NULL, 1};
  assert_int_equal(karst_scenario_load_with_overrides(&ctx, BRANCHWORK, &lk, 1, NULL, &sc),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "longer than 255 characters"));
  karst_scenario_destroy(&sc);
}

static char *read_all(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  if (s && fread(s, 1, (size_t)n, fp) != (size_t)n) n = 0;
  if (s) s[n] = '\0';
  fclose(fp);
  return s;
}

/* Written in place: the file's text with only the values changed (comments kept), loading
 * back to the overridden values. */
static void test_write_in_place(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_overrides_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char out[256];
  snprintf(out, sizeof out, "%s/best.yaml", dir);
  karst_scenario_override_t ov[] = {{"skeleton.gamma", "2.75", NULL, 1},
                                    {"amplification.steps", "3", NULL, 1}};
  assert_int_equal(karst_scenario_write_with_overrides(&ctx, BRANCHWORK, ov, 2, "# header\n", out),
                   KARST_SUCCESS);
  char *text = read_all(out), *orig = read_all(BRANCHWORK);
  assert_non_null(text);
  assert_non_null(orig);
  assert_memory_equal(text, "# header\n", 9);
  assert_non_null(strstr(text, "# The shipped default scenario")); /* comments kept */
  assert_non_null(strstr(text, "gamma: 2.75              # Gabriel-like graph"));
  assert_non_null(strstr(text, "steps: 3\n"));
  /* Same length as the original apart from the header and the two values ("2.0" -> "2.75",
   * "2" -> "3"). */
  assert_int_equal(strlen(text), strlen(orig) + 9 + 1);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, out, &sc), KARST_SUCCESS);
  assert_close(sc.gamma, 2.75, 0);
  assert_int_equal(sc.amplification.steps, 3);
  karst_scenario_destroy(&sc);
  free(text);
  free(orig);
  unlink(out);
  rmdir(dir);
}

/* A key the file lacks: the document is re-emitted, and loads back with the value; a relative
 * heightfield (grid.yaml: ../terrain/slope.asc) is rewritten to resolve from the output
 * directory, whose contents it then matches (same grid read). */
static void test_write_emitted_and_rebased(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_overrides_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char out[300], sub[256];
  snprintf(sub, sizeof sub, "%s/deeper", dir);
  assert_int_equal(mkdir(sub, 0777), 0);
  snprintf(out, sizeof out, "%s/best.yaml", sub);
  karst_scenario_override_t ov = {"skeleton.gamma", "1.25", NULL, 1};
  assert_int_equal(
      karst_scenario_write_with_overrides(&ctx, GOOD "minimal.yaml", &ov, 1, NULL, out),
      KARST_SUCCESS);
  karst_scenario_t sc, ref;
  karst_scenario_init(&sc);
  karst_scenario_init(&ref);
  assert_int_equal(karst_scenario_load(&ctx, out, &sc), KARST_SUCCESS);
  assert_close(sc.gamma, 1.25, 0);
  assert_close(sc.domain_max[2], 50, 0);
  assert_int_equal(sc.n_key_points, 2);
  karst_scenario_destroy(&sc);
  char *text = read_all(out);
  assert_non_null(strstr(text, "original comments are not kept"));
  free(text);

  /* grid.yaml, in place, with the heightfield rebased. */
  karst_scenario_override_t ov2 = {"tortuosity", "0.5", NULL, 1};
  assert_int_equal(karst_scenario_write_with_overrides(&ctx, GOOD "grid.yaml", &ov2, 1, NULL, out),
                   KARST_SUCCESS);
  assert_int_equal(karst_scenario_load(&ctx, out, &sc), KARST_SUCCESS);
  assert_int_equal(karst_scenario_load(&ctx, GOOD "grid.yaml", &ref), KARST_SUCCESS);
  assert_close(sc.tortuosity, 0.5, 0);
  assert_int_equal(sc.terrain.is_grid, 1);
  assert_true(sc.terrain.ncols == ref.terrain.ncols && sc.terrain.nrows == ref.terrain.nrows);
  for (karst_int_t i = 0; i < ref.terrain.ncols * ref.terrain.nrows; i++)
    assert_close(sc.terrain.z[i], ref.terrain.z[i], 0);
  text = read_all(out);
  assert_non_null(strstr(text, "heightfield: \"")); /* quoted, relative */
  assert_null(strstr(text, "heightfield: \"/"));
  free(text);
  karst_scenario_destroy(&sc);
  karst_scenario_destroy(&ref);

  /* A failing override leaves no output. */
  unlink(out);
  karst_scenario_override_t bad = {"tortuosity", "7", NULL, 1};
  assert_int_equal(karst_scenario_write_with_overrides(&ctx, GOOD "grid.yaml", &bad, 1, NULL, out),
                   KARST_ERANGE);
  assert_int_equal(access(out, F_OK), -1);
  rmdir(sub);
  rmdir(dir);
}

/* Every file path the reader resolves is rebased, not only the heightfield: plateau.yaml gives
 * terrain.heightfield, water_table.surface (a grid) and horizons[0].surface (a GOCAD TSurf), all
 * relative to itself; written two directories away, the scenario loads with the same surfaces. */
static void test_write_rebases_every_file(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_overrides_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char sub[300], out[320];
  snprintf(sub, sizeof sub, "%s/a", dir);
  assert_int_equal(mkdir(sub, 0777), 0);
  snprintf(out, sizeof out, "%s/best.yaml", sub);
  karst_scenario_override_t ov = {"tortuosity", "0.25", NULL, 1};
  const char *plateau = KARST_SOURCE_DIR "/datasets/scenarios/plateau.yaml";
  assert_int_equal(karst_scenario_write_with_overrides(&ctx, plateau, &ov, 1, NULL, out),
                   KARST_SUCCESS);
  karst_scenario_t sc, ref;
  karst_scenario_init(&sc);
  karst_scenario_init(&ref);
  assert_int_equal(karst_scenario_load(&ctx, out, &sc), KARST_SUCCESS);
  assert_int_equal(karst_scenario_load(&ctx, plateau, &ref), KARST_SUCCESS);
  assert_close(sc.tortuosity, 0.25, 0);
  assert_int_equal(sc.n_horizons, ref.n_horizons);
  assert_true(sc.terrain.ncols == ref.terrain.ncols && sc.terrain.nrows == ref.terrain.nrows);
  char *text = read_all(out);
  int rebased = 0;
  for (const char *p = text; (p = strstr(p, ": \"../")) != NULL; p++)
    rebased++;
  assert_int_equal(rebased, 3);
  assert_non_null(strstr(text, "plateau/fold_horizon.ts\""));
  free(text);
  karst_scenario_destroy(&sc);
  karst_scenario_destroy(&ref);
  unlink(out);
  rmdir(sub);
  rmdir(dir);
}

/* The file's own text of a key (branchwork.yaml: tortuosity 0.4, skeleton.gamma 2.0,
 * fractures[0].dip 85, domain.max[1] 600); a key the file leaves out is KARST_ENOTFOUND. */
static void test_value_text(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char v[64];
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "tortuosity", v, sizeof v), 0);
  assert_string_equal(v, "0.4");
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "skeleton.gamma", v, sizeof v), 0);
  assert_string_equal(v, "2.0");
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "fractures[0].dip", v, sizeof v), 0);
  assert_string_equal(v, "85");
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "domain.max[1]", v, sizeof v), 0);
  assert_string_equal(v, "600");
  assert_int_equal(
      karst_scenario_value_text(&ctx, GOOD "minimal.yaml", "skeleton.gamma", v, sizeof v),
      KARST_ENOTFOUND);
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "skeleton", v, sizeof v),
                   KARST_ENOTFOUND);
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "fractures[7].dip", v, sizeof v),
                   KARST_ENOTFOUND);
  assert_int_equal(karst_scenario_value_text(&ctx, BRANCHWORK, "a..b", v, sizeof v), KARST_EINVAL);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_replace_values),
      cmocka_unit_test(test_add_missing_key),
      cmocka_unit_test(test_refused),
      cmocka_unit_test(test_refused_lists),
      cmocka_unit_test(test_write_in_place),
      cmocka_unit_test(test_write_emitted_and_rebased),
      cmocka_unit_test(test_value_text),
      cmocka_unit_test(test_nested_readers),
      cmocka_unit_test(test_write_rebases_every_file),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
