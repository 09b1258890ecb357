/* Therion SQL export reader.
 *
 * Expected values and their sources:
 *  - g_huttes.sql (Grotte des Huttes, Karstnet data): 748 STATION rows, 707
 *    of them splay stations named "."; 748 SHOT rows, 41 between named
 *    stations (counted by an independent script over the INSERT lines). The
 *    same cave ships as Huttes_nodes.dat / Huttes_links.dat (41 nodes, 41
 *    links): matching nodes by their x, y, the two networks have exactly the
 *    same edge set, and every z of the .dat files is the SQL z + 700.00 m
 *    (a constant datum offset applied when the .dat files were made).
 *  - Small hand-written exports: networks computed by hand.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"
#include "test_util.h"

#define DATA KARST_SOURCE_DIR "/datasets/surveys/karstnet/"

static const char *tmp_path(void) {
  static char buf[128];
  snprintf(buf, sizeof buf, "test_therion_%ld.sql", (long)getpid());
  return buf;
}

static karst_error_t read_text(karst_ctx_t *ctx, const char *text, karst_network_t *net) {
  FILE *fp = fopen(tmp_path(), "wb");
  assert_non_null(fp);
  fputs(text, fp);
  assert_int_equal(fclose(fp), 0);
  karst_ctx_init(ctx);
  karst_error_t err = karst_read_therion_sql(ctx, tmp_path(), net);
  remove(tmp_path());
  return err;
}

static karst_int_t find_label(const karst_network_t *net, const char *label) {
  for (karst_int_t i = 0; net->node_labels && i < net->n_nodes; i++)
    if (net->node_labels[i] && strcmp(net->node_labels[i], label) == 0) return i;
  return -1;
}

static int has_edge(const karst_network_t *net, karst_int_t a, karst_int_t b) {
  for (karst_int_t e = 0; e < net->n_edges; e++)
    if ((net->edges[2 * e] == a && net->edges[2 * e + 1] == b) ||
        (net->edges[2 * e] == b && net->edges[2 * e + 1] == a))
      return 1;
  return 0;
}

static void test_huttes(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err = karst_read_therion_sql(&ctx, DATA "g_huttes.sql", &net);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 41);
  assert_int_equal(net.n_edges, 41);
  /* Hand check from the SQL text: GH.1 (739893.00, 6301812.00, 10.00). */
  karst_int_t g1 = find_label(&net, "GH.1");
  assert_true(g1 >= 0);
  assert_close(net.xyz[3 * g1], 739893.00, 1e-9);
  assert_close(net.xyz[3 * g1 + 1], 6301812.00, 1e-9);
  assert_close(net.xyz[3 * g1 + 2], 10.00, 1e-9);
  for (karst_int_t i = 0; i < net.n_nodes; i++)
    assert_string_not_equal(net.node_labels[i], ".");

  /* The Karstnet node/link pair of the same cave. */
  FILE *fn = fopen(DATA "Huttes_nodes.dat", "r"), *fl = fopen(DATA "Huttes_links.dat", "r");
  assert_non_null(fn);
  assert_non_null(fl);
  double dat[64][3];
  int nd = 0;
  while (nd < 64 && fscanf(fn, "%lf %lf %lf", &dat[nd][0], &dat[nd][1], &dat[nd][2]) == 3)
    nd++;
  assert_int_equal(nd, 41);
  karst_int_t map[64]; /* .dat node -> our node, by x, y to the centimetre */
  for (int i = 0; i < nd; i++) {
    map[i] = -1;
    for (karst_int_t k = 0; k < net.n_nodes; k++)
      if (llround(net.xyz[3 * k] * 100) == llround(dat[i][0] * 100) &&
          llround(net.xyz[3 * k + 1] * 100) == llround(dat[i][1] * 100)) {
        assert_int_equal(map[i], -1); /* unique */
        map[i] = k;
        assert_close(dat[i][2] - net.xyz[3 * k + 2], 700.0, 1e-6);
      }
    assert_true(map[i] >= 0);
  }
  int a, b, nl = 0;
  while (fscanf(fl, "%d %d", &a, &b) == 2) {
    assert_true(a >= 1 && a <= nd && b >= 1 && b <= nd);
    assert_true(has_edge(&net, map[a - 1], map[b - 1]));
    nl++;
  }
  assert_int_equal(nl, 41); /* 41 distinct links, all ours; we have 41 edges: same set */
  fclose(fn);
  fclose(fl);
  karst_network_destroy(&net);
}

/* A hand-written export: columns in a different order (read from "create
 * table"), flags srf/dpl/spl dropped and apx kept, splay stations "." and
 * "-", a quoted name with '', comments, two stations at one position (equated)
 * and a statement we do not read. Expected by hand: nodes A (0,0,0),
 * B (10,0,0) = B2, C (10,5,-1), D'x (10,5,-3); edges A-B, B2-C (= B-C), C-D'x
 * (apx); dropped: A-E srf, B-F dpl, C-G spl, A-"." and B-"-". */
static const char *SMALL =
    "-- hand-made Therion export\n"
    "create table STATION (NAME varchar(9), X real, Y real, ID integer, Z real, SURVEY_ID "
    "integer);\n"
    "create table SHOT (FROM_ID integer, ID integer, TO_ID integer, LENGTH real);\n"
    "create table SHOT_FLAG (SHOT_ID integer, FLAG char(3));\n"
    "begin transaction;\n"
    "insert into STATION values ('A', 0.00, 0.00, 1, 0.00, 1);\n"
    "insert into STATION values ('B', 10.00, 0.00, 2, 0.00, 1);\n"
    "insert into STATION values ('B2', 10.00, 0.00, 3, 0.00, 1);\n"
    "insert into STATION values ('C', 10.00, 5.00, 4, -1.00, 1);\n"
    "insert into STATION values ('D''x', 10.00, 5.00, 5, -3.00, 1);\n"
    "insert into STATION values ('E', 0, 9, 6, 0, 1);\n"
    "insert into STATION values ('F', 1, 9, 7, 0, 1);\n"
    "insert into STATION values ('G', 2, 9, 8, 0, 1);\n"
    "insert into STATION values ('.', 3, 9, 9, 0, 1);\n"
    "insert into STATION values ('-', 4, 9, 10, 0, 1);\n"
    "insert into SHOT values (1, 1, 2, 10.0);\n"
    "insert into SHOT values (3, 2, 4, 5.1);\n"
    "insert into SHOT values (4, 3, 5, 2.0);\n"
    "insert into SHOT values (1, 4, 6, 9.0);\n"
    "insert into SHOT values (2, 5, 7, 9.0);\n"
    "insert into SHOT values (4, 6, 8, 9.0);\n"
    "insert into SHOT values (1, 7, 9, 9.0);\n"
    "insert into SHOT values (2, 8, 10, 9.0);\n"
    "insert into SHOT_FLAG values(4, 'srf');\n"
    "insert into SHOT_FLAG values(5, 'dpl');\n"
    "insert into SHOT_FLAG values(6, 'spl');\n"
    "insert into SHOT_FLAG values(3, 'apx');\n"
    "commit;\n";

static void test_small(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err = read_text(&ctx, SMALL, &net);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 4);
  assert_int_equal(net.n_edges, 3);
  karst_int_t a = find_label(&net, "A"), b = find_label(&net, "B"), c = find_label(&net, "C"),
              d = find_label(&net, "D'x");
  assert_true(a >= 0 && b >= 0 && c >= 0 && d >= 0);
  assert_int_equal(find_label(&net, "B2"), -1); /* same position as B: one node */
  assert_close(net.xyz[3 * c + 2], -1.0, 1e-12);
  assert_close(net.xyz[3 * d + 2], -3.0, 1e-12);
  assert_true(has_edge(&net, a, b) && has_edge(&net, b, c) && has_edge(&net, c, d));
  assert_null(karst_network_attr_find(&net, KARST_ATTR_NODE, "lrud"));
  karst_network_destroy(&net);
}

/* Stations but no shots (a single point): an empty network, not an error. */
static void test_single_point(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(
      read_text(&ctx, "insert into STATION values (1, 'A', 1, 1.0, 2.0, 3.0);\n", &net),
      KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 0);
  assert_int_equal(net.n_edges, 0);
  karst_network_destroy(&net);
}

static void expect_fail(const char *text, karst_error_t code, const char *fragment) {
  karst_ctx_t ctx;
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err = read_text(&ctx, text, &net);
  if (err != code || !strstr(ctx.errmsg, fragment))
    print_error("got %s '%s', expected %s with '%s'\n", karst_error_name(err), ctx.errmsg,
                karst_error_name(code), fragment);
  assert_int_equal(err, code);
  assert_non_null(strstr(ctx.errmsg, fragment));
  assert_non_null(strstr(ctx.errmsg, tmp_path())); /* names the file */
  assert_int_equal(net.n_nodes, 0);
  assert_null(net.xyz);
}

#define ST1 "insert into STATION values (1, 'A', 1, 0.0, 0.0, 0.0);\n"
#define ST2 "insert into STATION values (2, 'B', 1, 1.0, 0.0, 0.0);\n"

static void test_errors(void **state) {
  (void)state;
  char path_line[512];
  expect_fail("", KARST_EPARSE, "no STATION rows");
  expect_fail("create table X (A integer);\n", KARST_EPARSE, "no STATION rows");
  /* Non-numeric coordinate, with FILE:LINE. */
  snprintf(path_line, sizeof path_line, "%s:2: STATION Y: expected a number, got 'north'",
           tmp_path());
  expect_fail(ST1 "insert into STATION values (2, 'B', 1, 1.0, 'north', 0.0);\n", KARST_EPARSE,
              path_line);
  expect_fail(ST1 "insert into STATION values (2, 'B', 1, 1.0, 2.0x, 0.0);\n", KARST_EPARSE,
              ":2: STATION Y: expected a number, got '2.0x'");
  expect_fail(ST1 "insert into STATION values (2, 'B', 1, NULL, 0, 0);\n", KARST_EPARSE,
              ":2: STATION X: expected a number, got NULL");
  expect_fail(ST1 "insert into STATION values (2, 'B', 1, 1e300, 0, 0);\n", KARST_ERANGE,
              ":2: STATION X");
  /* A shot naming a station that does not exist. */
  expect_fail(ST1 ST2 "insert into SHOT values (1, 1, 7, 25, 1.0);\n", KARST_EPARSE,
              ":3: SHOT 1: TO_ID 7 names no STATION");
  /* The same station ID twice. */
  expect_fail(ST1 "insert into STATION values (1, 'B', 1, 1.0, 0.0, 0.0);\n", KARST_EPARSE,
              ":2: STATION ID 1 already used on line 1");
  /* Syntax: unterminated string, missing parenthesis, too few values. */
  expect_fail(ST1 "insert into STATION values (2, 'B, 1, 1.0, 0.0, 0.0);\n", KARST_EPARSE,
              ":2: string opened here is never closed");
  expect_fail(ST1 "insert into SHOT values 1, 1, 2);\n", KARST_EPARSE, ":2: expected '('");
  /* A row too short for the layout says which layout: Therion's (no "create table"; here a
   * STATION row without SURVEY_ID), or the file's own "create table". */
  snprintf(path_line, sizeof path_line,
           "%s:2: insert into STATION: 5 values, expected at least 6: with no 'create table "
           "STATION' in the file, Therion's layout is assumed: ID, NAME, SURVEY_ID, X, Y, Z",
           tmp_path());
  expect_fail(ST1 "insert into STATION values (2, 'B', 1.0, 0.0, 0.0);\n", KARST_EPARSE, path_line);
  expect_fail(ST1 "insert into SHOT values (1, 1);\n", KARST_EPARSE,
              ":2: insert into SHOT: 2 values, expected at least 3: with no 'create table SHOT' "
              "in the file, Therion's layout is assumed: ID, FROM_ID, TO_ID, CENTRELINE_ID");
  expect_fail("create table STATION (NAME varchar(9), ID integer, X real, Y real, Z real);\n"
              "insert into STATION values ('A', 1, 0.0, 0.0, 0.0);\n"
              "insert into STATION values ('B', 2, 1.0, 0.0);\n",
              KARST_EPARSE,
              ":3: insert into STATION: 4 values, expected at least 5: 'create table STATION' on "
              "line 1 puts Z at value 5");
  expect_fail("create table STATION (ID integer, NAME varchar(9), X real);\n", KARST_EPARSE,
              ":1: table STATION has no column Y");
  /* Binary garbage. */
  expect_fail("\x01\x02\x00\x03", KARST_EPARSE, "no STATION rows");
  karst_ctx_t ctx;
  karst_network_t net;
  karst_network_init(&net);
  /* A NUL byte inside the text: a binary file, refused before parsing. */
  FILE *fp = fopen(tmp_path(), "wb");
  assert_non_null(fp);
  assert_int_equal(fwrite(ST1 "\0x", 1, sizeof ST1 + 1, fp), sizeof ST1 + 1);
  assert_int_equal(fclose(fp), 0);
  karst_ctx_init(&ctx);
  assert_int_equal(karst_read_therion_sql(&ctx, tmp_path(), &net), KARST_EPARSE);
  remove(tmp_path());
  assert_non_null(strstr(ctx.errmsg, "NUL byte"));
  assert_int_equal(net.n_nodes, 0);
  karst_ctx_init(&ctx);
  assert_int_equal(karst_read_therion_sql(&ctx, "no/such.sql", &net), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "no/such.sql: cannot open"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_huttes),
      cmocka_unit_test(test_small),
      cmocka_unit_test(test_single_point),
      cmocka_unit_test(test_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
