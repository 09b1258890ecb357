/* Hostile input for the rock blocks: the blocks section of a scenario
 * (src/scenario/scenario_blocks.inc); the relief images are read by
 * src/io/image.c, whose hostile inputs are in test_image.c. Every bad file must give a non-zero
 * code and a message naming the file, the line and column (scenario) and the field, never a crash
 * (the suite runs under ASan and UBSan). */
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
#include "karst/blocks.h"
#include "test_util.h"

static char dir[256];

static void write_file(const char *path, const void *data, size_t n) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  assert_int_equal(fwrite(data, 1, n, fp), n);
  fclose(fp);
}

static const char *base = "domain: {min: [0, 0, 0], max: [100, 100, 100]}\n"
                          "terrain: {elevation: 90}\n"
                          "key_points:\n"
                          "  - {type: sink, position: [10, 10, 80]}\n"
                          "  - {type: spring, position: [90, 90, 20]}\n";

/* Load a scenario made of base + @p blocks; returns the code, message in ctx. */
static karst_error_t load(karst_ctx_t *ctx, const char *blocks, karst_scenario_t *sc) {
  char path[300], text[4096];
  snprintf(path, sizeof path, "%s/s.yaml", dir);
  snprintf(text, sizeof text, "%s%s", base, blocks);
  write_file(path, text, strlen(text));
  karst_scenario_init(sc);
  return karst_scenario_load(ctx, path, sc);
}

static void expect_error(const char *blocks, const char *line_col, const char *words) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_error_t err = load(&ctx, blocks, &sc);
  if (err == KARST_SUCCESS || !strstr(ctx.errmsg, line_col) || !strstr(ctx.errmsg, words)) {
    print_error("for:\n%s\ngot %d: %s\nexpected %s and '%s'\n", blocks, err, ctx.errmsg, line_col,
                words);
    karst_scenario_destroy(&sc);
    fail();
  }
  karst_scenario_destroy(&sc);
}

/* expect_error on @p head followed by @p body (the rows of a list under test). */
static void expect_error_after(const char *head, const char *body, const char *line_col,
                               const char *words) {
  char text[1024];
  snprintf(text, sizeof text, "%s%s", head, body);
  expect_error(text, line_col, words);
}

static void test_section_ok(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  assert_int_equal(load(&ctx,
                        "blocks:\n"
                        "  tile_size: 10\n"
                        "  poisson_radius: 0.5\n"
                        "  seed: 42\n"
                        "  region: [10, 20, 60, 80]\n"
                        "  presence: {distance: [-2, 0.5], max_slope: 0.4, anchors: 5}\n"
                        "  strata: [{name: lower, below: 120, tile: equidimensional},\n"
                        "           {name: upper, tile: tabular}]\n",
                        &sc),
                   KARST_SUCCESS);
  const karst_blocks_section_t *b = sc.blocks;
  assert_non_null(b);
  assert_close(b->tile_size, 10, 0);
  assert_close(b->poisson_radius, 0.5, 0);
  assert_true(b->has_seed && b->seed == 42);
  assert_true(b->has_region);
  assert_close(b->region[3], 80, 0);
  assert_close(b->presence.dist_min, -2, 0);
  assert_close(b->presence.dist_max, 0.5, 0);
  assert_int_equal(b->presence.n_anchors, 5);
  assert_int_equal(b->n_strata, 2);
  assert_string_equal(b->strata[0].name, "lower");
  assert_close(b->strata[0].below, 120, 0);
  assert_int_equal(b->strata[1].tile, KARST_BLOCK_TABULAR);
  assert_true(isinf(b->strata[1].below));
  double lo[3] = {0, 0, 119.9}, hi[3] = {0, 0, 120};
  assert_int_equal(karst_blocks_section_stratum(sc.blocks, lo), 0);
  assert_int_equal(karst_blocks_section_stratum(sc.blocks, hi), 1);
  karst_scenario_destroy(&sc);
  /* no section: NULL, nothing else changes */
  assert_int_equal(load(&ctx, "", &sc), KARST_SUCCESS);
  assert_null(sc.blocks);
  karst_scenario_destroy(&sc);
}

static void test_section_errors(void **state) {
  (void)state;
  expect_error("blocks: 5\n", ":6:9:", "blocks must be a map");
  expect_error("blocks:\n  tile_sise: 20\n  strata: [{name: a, tile: tabular}]\n",
               ":7:3:", "did you mean 'tile_size'");
  expect_error("blocks:\n  strata: [{name: a, tile: tabulr}]\n",
               ":7:28:", "did you mean 'tabular'");
  expect_error("blocks:\n  tile_size: 20\n", ":7:3:", "required key 'strata'");
  expect_error("blocks:\n  strata: []\n", ":7:3:", "at least one stratum");
  expect_error("blocks:\n  strata: 3\n", ":7:11:", "list of maps");
  expect_error("blocks:\n  strata: [{name: a, tile: tabular}, {name: b, tile: columnar}]\n",
               ":7:12:", "needs 'below'");
  expect_error("blocks:\n  strata: [{name: a, below: 50, tile: tabular}, {name: b, below: 40, "
               "tile: columnar}]\n",
               ":7:49:", "must be above");
  expect_error("blocks:\n  strata: [{name: a, below: 50, tile: tabular}, {name: a, tile: "
               "columnar}]\n",
               ":7:49:", "already named");
  expect_error("blocks:\n  poisson_radius: .nan\n  strata: [{name: a, tile: tabular}]\n",
               ":7:19:", "finite");
  expect_error("blocks:\n  poisson_radius: -1\n  strata: [{name: a, tile: tabular}]\n",
               ":7:19:", "> 0 m");
  expect_error("blocks:\n  poisson_radius: ten\n  strata: [{name: a, tile: tabular}]\n",
               ":7:19:", "must be a number");
  expect_error("blocks:\n  poisson_radius: 5\n  strata: [{name: a, tile: tabular}]\n",
               ":7:3:", "poisson_radius must be within");
  expect_error("blocks:\n  presence: {max_slope: 2}\n  strata: [{name: a, tile: tabular}]\n",
               ":7:25:", "max_slope must be within (0, 1]");
  expect_error("blocks:\n  presence: {distance: [3, 1]}\n  strata: [{name: a, tile: tabular}]\n",
               ":7:3:", "v_a <= v_b");
  expect_error("blocks:\n  presence: {anchors: 0}\n  strata: [{name: a, tile: tabular}]\n",
               ":7:23:", "anchors");
  expect_error("blocks:\n  region: [5, 0, 1, 10]\n  strata: [{name: a, tile: tabular}]\n",
               ":7:11:", "x0 < x1");
  expect_error("blocks:\n  region: [5, 0, 1]\n  strata: [{name: a, tile: tabular}]\n",
               ":7:11:", "4 numbers");
  expect_error("blocks:\n  warp: {relief: image}\n  strata: [{name: a, tile: tabular}]\n",
               ":7:3:", "needs warp.image");
  expect_error("blocks:\n  warp: {relief: bumps}\n  strata: [{name: a, tile: tabular}]\n",
               ":7:18:", "none, noise, image");
  expect_error("blocks:\n  seed: -3\n  strata: [{name: a, tile: tabular}]\n",
               ":7:9:", "unsigned 64-bit");
  expect_error("blocks:\n  strata: [{name: \"\", tile: tabular}]\n", ":7:19:", "non-empty");
  expect_error("blocks:\n  strata: [{tile: tabular}]\n", ":7:12:", "required key 'name'");
  expect_error("blocks:\n  strata: [{name: a, tile: tabular}]\nblocks:\n  strata: []\n",
               ":8:1:", "duplicate key 'blocks'");
}

/* blocks.authored: a construction tree read, built and evaluated (hand values: a 2 m cube minus
 * a sphere of radius 1 at its corner, in the union with a sphere of radius 0.5 elsewhere). */
static void test_authored_ok(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  assert_int_equal(load(&ctx,
                        "blocks:\n"
                        "  tile_size: 10\n"
                        "  strata: [{name: a, tile: tabular}]\n"
                        "  authored:\n"
                        "    - tile: tabular\n"
                        "      union:\n"
                        "        - difference: [{box: {min: [1, 1, 1], max: [3, 3, 3]}},\n"
                        "                       {sphere: {center: [3, 3, 3], radius: 1}}]\n"
                        "        - {sphere: {center: [7, 7, 7], radius: 0.5}}\n"
                        "    - {tile: tabular, box: {min: [5, 1, 1], max: [6, 2, 2]}}\n",
                        &sc),
                   KARST_SUCCESS);
  const karst_blocks_section_t *b = sc.blocks;
  assert_int_equal(b->n_authored, 2);
  assert_int_equal(b->authored[0].tile, KARST_BLOCK_TABULAR);
  assert_int_equal(b->authored[0].shape.kind, KARST_BLOCKS_SHAPE_UNION);
  assert_int_equal(b->authored[0].shape.n_children, 2);
  assert_int_equal(b->authored[0].shape.children[0].kind, KARST_BLOCKS_SHAPE_DIFFERENCE);
  assert_int_equal(b->authored[0].line, 10);
  double box[6];
  karst_blocks_shape_box(&b->authored[0].shape, box);
  assert_close(box[0], 1, 0);
  assert_close(box[5], 7.5, 0);
  karst_sdf_t *tree;
  assert_int_equal(karst_sdf_create(NULL, &tree), KARST_SUCCESS);
  karst_int_t nodes[2];
  int n = -1;
  assert_int_equal(
      karst_blocks_section_authored(&ctx, b, KARST_BLOCK_EQUIDIMENSIONAL, tree, nodes, &n),
      KARST_SUCCESS);
  assert_int_equal(n, 0); /* none in that tile */
  assert_int_equal(karst_blocks_section_authored(&ctx, b, KARST_BLOCK_TABULAR, tree, nodes, &n),
                   KARST_SUCCESS);
  assert_int_equal(n, 2);
  double in_cube[3] = {1.5, 1.5, 2}, in_hole[3] = {2.8, 2.8, 2.8}, in_small[3] = {7, 7, 7.25},
         out[3] = {5, 5, 5};
  assert_true(karst_sdf_eval_node(tree, nodes[0], in_cube, NULL, NULL) < 0);
  assert_true(karst_sdf_eval_node(tree, nodes[0], in_hole, NULL, NULL) > 0);
  assert_close(karst_sdf_eval_node(tree, nodes[0], in_small, NULL, NULL), -0.25, 1e-12);
  assert_true(karst_sdf_eval_node(tree, nodes[0], out, NULL, NULL) > 0);
  double in_box[3] = {5.5, 1.5, 1.25};
  assert_close(karst_sdf_eval_node(tree, nodes[1], in_box, NULL, NULL), -0.25, 1e-12);
  karst_sdf_free(tree);
  karst_scenario_destroy(&sc);
}

static void test_authored_errors(void **state) {
  (void)state;
  const char *head =
      "blocks:\n  tile_size: 10\n  strata: [{name: a, tile: tabular}]\n  authored:\n";
#define AUTH(body, lc, words) expect_error_after(head, body, lc, words)
  AUTH("    - {sphere: {center: [5, 5, 5], radius: 1}}\n", ":10:7:", "needs 'tile'");
  AUTH("    - {tile: tabular}\n", ":10:7:", "must contain one of sphere, box");
  AUTH("    - {tile: columnar, sphere: {center: [5, 5, 5], radius: 1}}\n",
       ":10:7:", "no stratum has the tile 'columnar'");
  AUTH("    - {tile: tabulr, sphere: {center: [5, 5, 5], radius: 1}}\n",
       ":10:14:", "did you mean 'tabular'");
  AUTH("    - {tile: tabular, sphere: {center: [5, 5, 5], radius: 0}}\n", ":10:59:", "> 0 m");
  AUTH("    - {tile: tabular, sphere: {center: [5, 5], radius: 1}}\n", ":10:40:", "3 numbers");
  AUTH("    - {tile: tabular, sphere: {center: [9.5, 5, 5], radius: 1}}\n",
       ":10:7:", "within the tile");
  AUTH("    - {tile: tabular, box: {min: [1, 1, 1], max: [2, 0, 2]}}\n",
       ":10:28:", "min must be below max");
  AUTH("    - {tile: tabular, sphere: {center: [5, 5, 5], radius: 1}, box: {min: [1, 1, 1], max: "
       "[2, 2, 2]}}\n",
       ":10:63:", "has both 'sphere' and 'box'");
  AUTH("    - {tile: tabular, cone: {}}\n", ":10:23:", "unknown key 'cone'");
  AUTH("    - {tile: tabular, union: []}\n", ":10:30:", "from 1 to");
  AUTH("    - {tile: tabular, difference: [{sphere: {center: [5, 5, 5], radius: 1}}]}\n",
       ":10:35:", "from 2 to");
  AUTH("    - {tile: tabular, union: 3}\n", ":10:30:", "list of nodes");
  AUTH("    - {tile: tabular, union: [7]}\n", ":10:31:", "must be a map with one of");
  AUTH("    - {tile: tabular, intersection: [{box: {min: [1, 1, 1], max: [2, 2, 2]}}, {box: {min: "
       "[3, 3, 3], max: [4, 4, 4]}}]}\n",
       ":10:7:", "non-empty shape");
  AUTH("    - 5\n", ":10:7:", "must be a map");
  expect_error("blocks:\n  strata: [{name: a, tile: tabular}]\n  authored: 5\n",
               ":8:13:", "list of blocks");
  /* an alias cycle or a very deep tree stops at the depth limit */
  char deep[4096] = "";
  size_t len = 0;
  len += (size_t)snprintf(deep + len, sizeof deep - len, "%s    - tile: tabular\n      union:\n",
                          head);
  for (int i = 0; i < 20; i++)
    len += (size_t)snprintf(deep + len, sizeof deep - len, "%*s- union:\n", 8 + 2 * i, "");
  snprintf(deep + len, sizeof deep - len, "%*s- {sphere: {center: [5, 5, 5], radius: 1}}\n",
           8 + 2 * 20, "");
  expect_error(deep, ":", "nest deeper than 16 levels");
#undef AUTH
}

/* blocks.user_discs: discs read as given, sorted to their tiles by karst_blocks_section_user_discs
 * (hand values: two discs in the tabular tile, one in the equidimensional tile). */
static void test_user_discs_ok(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  assert_int_equal(
      load(&ctx,
           "blocks:\n"
           "  tile_size: 10\n"
           "  strata: [{name: a, below: 50, tile: equidimensional},\n"
           "           {name: b, tile: tabular}]\n"
           "  user_discs:\n"
           "    - {tile: tabular, center: [2.5, 5, 5], normal: [2, 0, 0], radius: 20}\n"
           "    - {tile: equidimensional, center: [0, 10, 3], normal: [0, 1, 1], "
           "radius: 1.5}\n"
           "    - {tile: tabular, center: [5, 5, 7], normal: [0, 0, 1], radius: 4}\n",
           &sc),
      KARST_SUCCESS);
  const karst_blocks_section_t *b = sc.blocks;
  assert_int_equal(b->n_user_discs, 3);
  assert_int_equal(b->user_discs[0].tile, KARST_BLOCK_TABULAR);
  assert_int_equal(b->user_discs[1].tile, KARST_BLOCK_EQUIDIMENSIONAL);
  assert_int_equal(b->user_discs[0].line, 11);
  assert_int_equal(b->user_discs[2].line, 13);
  karst_blocks_disc_t d[3];
  assert_int_equal(karst_blocks_section_user_discs(b, KARST_BLOCK_TABULAR, d), 2);
  assert_close(d[0].c[0], 2.5, 0);
  assert_close(d[0].n[0], 2, 0); /* as given: the tile normalises */
  assert_close(d[0].radius, 20, 0);
  assert_close(d[1].c[2], 7, 0);
  assert_close(d[1].radius, 4, 0);
  assert_int_equal(karst_blocks_section_user_discs(b, KARST_BLOCK_EQUIDIMENSIONAL, d), 1);
  assert_close(d[0].c[1], 10, 0);
  assert_close(d[0].n[2], 1, 0);
  assert_int_equal(karst_blocks_section_user_discs(b, KARST_BLOCK_COLUMNAR, d), 0);
  karst_scenario_destroy(&sc);
}

/* blocks.warp.image is resolved relative to the scenario's directory, like every file a scenario
 * names, and karst_scenario_files lists it (so no output may replace it). */
static void test_warp_image_path(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  assert_int_equal(load(&ctx,
                        "blocks:\n"
                        "  strata: [{name: a, tile: tabular}]\n"
                        "  warp: {relief: image, image: relief.pgm, amplitude: 0.1}\n",
                        &sc),
                   KARST_SUCCESS);
  char want[300];
  snprintf(want, sizeof want, "%s/relief.pgm", dir);
  assert_string_equal(sc.blocks->warp_image, want);
  karst_scenario_destroy(&sc);
  char path[300], **files = NULL;
  int n = 0;
  snprintf(path, sizeof path, "%s/s.yaml", dir);
  assert_int_equal(karst_scenario_files(&ctx, path, &files, &n), KARST_SUCCESS);
  int found = 0;
  for (int i = 0; i < n; i++) {
    found |= strcmp(files[i], want) == 0;
    free(files[i]);
  }
  free(files);
  assert_true(found);
}

static void test_user_discs_errors(void **state) {
  (void)state;
  const char *head =
      "blocks:\n  tile_size: 10\n  strata: [{name: a, tile: tabular}]\n  user_discs:\n";
#define DISC(body, lc, words) expect_error_after(head, body, lc, words)
  DISC("    - {center: [5, 5, 5], normal: [0, 0, 1], radius: 1}\n",
       ":10:7:", "required key 'tile'");
  DISC("    - {tile: tabular, normal: [0, 0, 1], radius: 1}\n", ":10:7:", "required key 'center'");
  DISC("    - {tile: tabular, center: [5, 5, 5], radius: 1}\n", ":10:7:", "required key 'normal'");
  DISC("    - {tile: tabular, center: [5, 5, 5], normal: [0, 0, 1]}\n",
       ":10:7:", "required key 'radius'");
  DISC("    - {tile: tabulr, center: [5, 5, 5], normal: [0, 0, 1], radius: 1}\n",
       ":10:14:", "did you mean 'tabular'");
  DISC("    - {tile: columnar, center: [5, 5, 5], normal: [0, 0, 1], radius: 1}\n",
       ":10:7:", "no stratum has the tile 'columnar'");
  DISC("    - {tile: tabular, center: [5, 5], normal: [0, 0, 1], radius: 1}\n",
       ":10:31:", "3 numbers");
  DISC("    - {tile: tabular, center: [5, 11, 5], normal: [0, 0, 1], radius: 1}\n",
       ":10:7:", "y = 11 is outside the tile");
  DISC("    - {tile: tabular, center: [5, 5, .nan], normal: [0, 0, 1], radius: 1}\n", ":10:", "");
  DISC("    - {tile: tabular, center: [5, 5, 5], normal: [0, 0, 0], radius: 1}\n",
       ":10:7:", "normal must not be zero");
  DISC("    - {tile: tabular, center: [5, 5, 5], normal: [0, 0, 1], radius: 0}\n",
       ":10:69:", "> 0 m");
  DISC("    - {tile: tabular, center: [5, 5, 5], normal: [0, 0, 1], radius: 41}\n",
       ":10:7:", "at most 4 tile_size = 40 m");
  DISC("    - {tile: tabular, center: [5, 5, 5], normal: [0, 0, 1], radius: 1, dip: 3}\n",
       ":10:", "unknown key 'dip'");
  DISC("    - 5\n", ":10:7:", "must be a map");
  expect_error("blocks:\n  strata: [{name: a, tile: tabular}]\n  user_discs: 5\n",
               ":8:15:", "list of maps");
#undef DISC
}

static int setup(void **state) {
  (void)state;
  snprintf(dir, sizeof dir, "/tmp/karst_blocks_input_XXXXXX");
  return mkdtemp(dir) ? 0 : -1;
}
static int teardown(void **state) {
  (void)state;
  return test_util_remove_dir(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_section_ok),      cmocka_unit_test(test_section_errors),
      cmocka_unit_test(test_authored_ok),     cmocka_unit_test(test_authored_errors),
      cmocka_unit_test(test_user_discs_ok),   cmocka_unit_test(test_user_discs_errors),
      cmocka_unit_test(test_warp_image_path),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
