/* Readers of src/io/: Karstnet node/link pairs, GOCAD PLine, the format dispatcher, the
 * Karstnet writer, and the published-metrics table of --observed. Counts of the shipped files
 * were checked independently with wc/grep (Sakany 1716 node lines, 1784 link lines;
 * Monachou 251 VRTX and 258 SEG lines). */
#include <glob.h>
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

#include "io/format_internal.h"
#include "karst.h"
#include "test_util.h"

#define DATA KARST_SOURCE_DIR "/datasets/surveys/karstnet/"
#define TMP KARST_BINARY_DIR "/tests/read_karstnet_tmp"

static void write_file(const char *path, const char *text) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
}

/* Write a Karstnet pair TMP/NAME_nodes.dat + _links.dat and read it through @p which. */
static karst_error_t read_pair(karst_ctx_t *ctx, const char *name, const char *nodes,
                               const char *links, karst_network_t *net) {
  char p[512];
  if (nodes) {
    snprintf(p, sizeof p, TMP "/%s_nodes.dat", name);
    write_file(p, nodes);
  }
  if (links) {
    snprintf(p, sizeof p, TMP "/%s_links.dat", name);
    write_file(p, links);
  }
  snprintf(p, sizeof p, TMP "/%s_%s.dat", name, nodes ? "nodes" : "links");
  return karst_read_karstnet(ctx, p, net);
}

static int setup(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  return karst_mkdir_p(&ctx, TMP) == KARST_SUCCESS ? 0 : -1;
}

static void test_shipped_pairs(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const char *names[] = {DATA "Sakany_nodes.dat", DATA "Sakany_links.dat", DATA "Sakany"};
  for (int i = 0; i < 3; i++) {
    karst_network_t net;
    karst_network_init(&net);
    assert_int_equal(karst_read_karstnet(&ctx, names[i], &net), KARST_SUCCESS);
    assert_int_equal(net.n_nodes, 1716);
    assert_int_equal(net.n_edges, 1784);
    /* first node line "-47.9375 24 -12.238778114318848", first link "1 2" */
    assert_close(net.xyz[0], -47.9375, 0.0);
    assert_close(net.xyz[1], 24.0, 0.0);
    assert_close(net.xyz[2], -12.238778114318848, 0.0);
    assert_int_equal(net.edges[0], 0);
    assert_int_equal(net.edges[1], 1);
    assert_string_equal(net.title, "Sakany");
    karst_network_destroy(&net);
  }
  karst_network_t h;
  karst_network_init(&h);
  assert_int_equal(karst_read_karstnet(&ctx, DATA "Huttes_links.dat", &h), KARST_SUCCESS);
  assert_int_equal(h.n_nodes, 41);
  assert_int_equal(h.n_edges, 41);
  karst_network_destroy(&h);
}

static void test_karstnet_features(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  /* comments, blank lines, 2-D coordinates (z = 0 as in Karstnet), CRLF */
  assert_int_equal(
      read_pair(&ctx, "flat", "# x y\n0 0\r\n\n3 4 # a comment\n", "1 2\n2.0 1\n", &net),
      KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 2);
  assert_int_equal(net.n_edges, 2);
  assert_close(net.xyz[5], 0.0, 0.0);
  assert_close(net.xyz[3], 3.0, 0.0);
  karst_network_destroy(&net);
  /* columns after z are properties */
  assert_int_equal(read_pair(&ctx, "props", "0 0 0 7 8\n1 1 1 9 10\n", "1 2\n", &net),
                   KARST_SUCCESS);
  karst_attr_t *a = karst_network_attr_find(&net, KARST_ATTR_NODE, "properties");
  assert_non_null(a);
  assert_int_equal(a->ncomp, 2);
  assert_close(a->data[3], 10.0, 0.0);
  karst_network_destroy(&net);
}

/* Each malformed case: the error code and "FILE:LINE" (or FILE) in the message. */
static void expect_pair_error(const char *name, const char *nodes, const char *links,
                              karst_error_t code, const char *where, const char *what) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err = read_pair(&ctx, name, nodes, links, &net);
  if (err != code || !strstr(ctx.errmsg, where) || !strstr(ctx.errmsg, what))
    print_error("case %s: got %s '%s'\n", name, karst_error_name(err), ctx.errmsg);
  assert_int_equal(err, code);
  assert_non_null(strstr(ctx.errmsg, where));
  assert_non_null(strstr(ctx.errmsg, what));
  assert_int_equal(net.n_nodes, 0); /* nothing half-built */
  karst_network_destroy(&net);
}

static void test_karstnet_errors(void **state) {
  (void)state;
  expect_pair_error("past", "0 0 0\n1 1 1\n", "1 2\n2 3\n", KARST_ERANGE,
                    "past_links.dat:2:", "past the node list");
  expect_pair_error("zero", "0 0 0\n1 1 1\n", "0 1\n", KARST_ERANGE,
                    "zero_links.dat:1:", "1-based");
  expect_pair_error("nonnum", "0 0 0\n1 x 1\n", "1 2\n", KARST_EPARSE,
                    "nonnum_nodes.dat:2:", "'x' is not a finite number");
  expect_pair_error("nanc", "0 0 0\n1 nan 1\n", "1 2\n", KARST_EPARSE,
                    "nanc_nodes.dat:2:", "not a finite number");
  expect_pair_error("emptyn", "\n# nothing\n", "1 2\n", KARST_EPARSE, "emptyn_nodes.dat",
                    "empty file");
  expect_pair_error("emptyl", "0 0 0\n1 1 1\n", "", KARST_EPARSE, "emptyl_links.dat", "empty file");
  expect_pair_error("cols", "0 0 0\n1 1\n", "1 2\n", KARST_EPARSE,
                    "cols_nodes.dat:2:", "expected 3 columns as on line 1, got 2");
  expect_pair_error("onecol", "5\n", "1 2\n", KARST_EPARSE, "onecol_nodes.dat:1:", "1 column");
  expect_pair_error("lcols", "0 0 0\n1 1 1\n", "1 2 3\n", KARST_EPARSE,
                    "lcols_links.dat:1:", "got 3 columns");
  expect_pair_error("frac", "0 0 0\n1 1 1\n", "1 1.5\n", KARST_EPARSE,
                    "frac_links.dat:1:", "'1.5' is not a node number");
  /* the other file of the pair is missing */
  expect_pair_error("alone", "0 0 0\n", NULL, KARST_ENOTFOUND, "alone_links.dat", "cannot open");
}

static void test_pline(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_read_pline(&ctx, DATA "Monachou.pl", &net), KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 251);
  assert_int_equal(net.n_edges, 258);
  assert_string_equal(net.title, "Monachou.pl");
  /* line 16 "VRTX 1 -1.135427474975586 -40.027496337890625 -12.05058765411377" */
  assert_close(net.xyz[0], -1.135427474975586, 0.0);
  /* the second ILINE starts "ATOM 3 1" then "SEG 3 4": vertex 1 (node 0) to vertex 4 (node 2) */
  assert_int_equal(net.edges[2], 0);
  assert_int_equal(net.edges[3], 2);
  karst_network_destroy(&net);

  /* PVRTX with properties, ATOM of an ATOM, several ILINE parts and a second object */
  const char *text =
      "GOCAD PLine 1\nHEADER {\nname:small\n}\nILINE\nPVRTX 10 0 0 0 5.5\n"
      "PVRTX 11 1 0 0 6\nSEG 10 11\nILINE\nATOM 12 11\nATOM 13 12\nVRTX 14 1 1 0\n"
      "SEG 13 14\nEND\nGOCAD PLine 1\nILINE\nVRTX 1 5 5 5\nVRTX 2 6 5 5\nSEG 1 2\nEND\n";
  write_file(TMP "/small.pl", text);
  assert_int_equal(karst_read_pline(&ctx, TMP "/small.pl", &net), KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 5);
  assert_int_equal(net.n_edges, 3);
  assert_string_equal(net.title, "small");
  assert_int_equal(net.edges[2], 1); /* ATOM 13 -> ATOM 12 -> vertex 11 = node 1 */
  assert_int_equal(net.edges[3], 2);
  assert_int_equal(net.edges[4], 3); /* ids of the second object start again */
  assert_int_equal(net.edges[5], 4);
  karst_network_destroy(&net);
}

static void expect_pline_error(const char *name, const char *text, const char *where,
                               const char *what) {
  char path[512];
  snprintf(path, sizeof path, TMP "/%s.pl", name);
  write_file(path, text);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  karst_error_t err = karst_read_pline(&ctx, path, &net);
  if (err != KARST_EPARSE || !strstr(ctx.errmsg, where) || !strstr(ctx.errmsg, what))
    print_error("case %s: got %s '%s'\n", name, karst_error_name(err), ctx.errmsg);
  assert_int_equal(err, KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, where));
  assert_non_null(strstr(ctx.errmsg, what));
  assert_int_equal(net.n_nodes, 0);
  karst_network_destroy(&net);
}

static void test_pline_errors(void **state) {
  (void)state;
  expect_pline_error("empty", "", "empty.pl", "empty file");
  /* Another GOCAD object type is named, where it starts (first or later object). */
  expect_pline_error("tsurf", "GOCAD TSurf 1\nHEADER {\nname:s\n}\nVRTX 1 0 0 0\nTRGL 1 1 1\n",
                     "tsurf.pl:1: ", "GOCAD TSurf object: only GOCAD PLine objects are read");
  expect_pline_error("mixed",
                     "GOCAD PLine 1\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nSEG 1 2\nEND\nGOCAD VSet 1\n",
                     "mixed.pl:6: ", "GOCAD VSet object: only GOCAD PLine objects are read");
  expect_pline_error("magic", "VRTX 1 0 0 0\n",
                     "magic.pl:1:", "not a GOCAD PLine file: expected 'GOCAD PLine', got 'VRTX'");
  expect_pline_error("seg", "GOCAD PLine 1\nVRTX 1 0 0 0\nSEG 1 2\n",
                     "seg.pl:3:", "vertex 2 is not defined");
  expect_pline_error("atom", "GOCAD PLine 1\nVRTX 1 0 0 0\nATOM 2 7\n",
                     "atom.pl:3:", "repeats vertex 7");
  expect_pline_error("coord", "GOCAD PLine 1\nVRTX 1 0 abc 0\n",
                     "coord.pl:2:", "coordinate y: 'abc'");
  expect_pline_error("short", "GOCAD PLine 1\nVRTX 1 0 0\n",
                     "short.pl:2:", "needs an id and x y z");
  expect_pline_error("dup", "GOCAD PLine 1\nVRTX 1 0 0 0\nVRTX 1 1 0 0\n",
                     "dup.pl:3:", "already used");
  expect_pline_error("novrtx", "GOCAD PLine 1\nILINE\nEND\n", "novrtx.pl", "no VRTX");
}

/* The dispatcher picks the reader from the extension, else from the first bytes. */
static void test_dispatch(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_read_network(&ctx, DATA "Monachou.pl", KARST_FORMAT_AUTO, &net),
                   KARST_SUCCESS);
  assert_int_equal(net.n_edges, 258);
  karst_network_destroy(&net);
  assert_int_equal(karst_read_network(&ctx, DATA "Huttes_nodes.dat", KARST_FORMAT_AUTO, &net),
                   KARST_SUCCESS);
  assert_int_equal(net.n_edges, 41);
  karst_network_destroy(&net);
  write_file(TMP "/noext", "GOCAD PLine 1\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nSEG 1 2\n");
  assert_int_equal(karst_read_network(&ctx, TMP "/noext", KARST_FORMAT_AUTO, &net), KARST_SUCCESS);
  assert_int_equal(net.n_edges, 1);
  karst_network_destroy(&net);
  write_file(TMP "/what.txt", "hello\n");
  assert_int_equal(karst_read_network(&ctx, TMP "/what.txt", KARST_FORMAT_AUTO, &net),
                   KARST_EUNSUPPORTED);
  assert_non_null(strstr(ctx.errmsg, "unknown network format"));
  assert_int_equal(karst_read_network(&ctx, TMP "/missing.pl", KARST_FORMAT_AUTO, &net), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "missing.pl"));
}

/* Write then read: the same bits (%.17g) and the same metrics. */
static void test_write_roundtrip(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t a, b;
  karst_network_init(&a);
  karst_network_init(&b);
  assert_int_equal(karst_read_pline(&ctx, DATA "Monachou.pl", &a), KARST_SUCCESS);
  assert_int_equal(karst_write_karstnet(&ctx, TMP "/mona", &a), KARST_SUCCESS);
  assert_int_equal(karst_read_karstnet(&ctx, TMP "/mona_links.dat", &b), KARST_SUCCESS);
  assert_int_equal(a.n_nodes, b.n_nodes);
  assert_int_equal(a.n_edges, b.n_edges);
  assert_memory_equal(a.xyz, b.xyz, (size_t)a.n_nodes * 3 * sizeof(double));
  assert_memory_equal(a.edges, b.edges, (size_t)a.n_edges * 2 * sizeof(karst_int_t));
  karst_metrics_t ma, mb;
  assert_int_equal(karst_metrics_compute(&ctx, &a, NULL, &ma), KARST_SUCCESS);
  assert_int_equal(karst_metrics_compute(&ctx, &b, NULL, &mb), KARST_SUCCESS);
  assert_memory_equal(&ma, &mb, sizeof ma);
  /* both files in place, no temporary file left beside them */
  assert_int_equal(access(TMP "/mona_nodes.dat", R_OK), 0);
  glob_t gl;
  assert_int_equal(glob(TMP "/.mona_*.tmp.*", 0, NULL, &gl), GLOB_NOMATCH);
  /* an unwritable place fails cleanly */
  assert_int_equal(karst_write_karstnet(&ctx, TMP "/no/such/dir/x", &a), KARST_EIO);
  karst_network_destroy(&a);
  karst_network_destroy(&b);
}

/* --observed: the published table (34 caves of Collon et al. 2017; the three Karstnet-only
 * rows are left out). Bounds read off the CSV: mean branch length min 8.464115573
 * (Monachou), cycles max 779; a small hand-made table with quotes and comments. */
static void test_observed(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_metrics_observed_t obs;
  assert_int_equal(
      karst_metrics_observed_load(&ctx, KARST_SOURCE_DIR "/datasets/published_metrics.csv", &obs),
      KARST_SUCCESS);
  assert_int_equal(obs.n_caves, 34);
  int n;
  const karst_metric_field_t *f = karst_metric_fields(&n);
  int kml = -1, kcy = -1, kex = -1;
  for (int k = 0; k < n; k++) {
    if (strcmp(f[k].key, "mean_length") == 0) kml = k;
    if (strcmp(f[k].key, "cycles") == 0) kcy = k;
    if (strcmp(f[k].key, "extremities") == 0) kex = k;
  }
  assert_close(obs.min[kml], 8.464115573, 0.0);
  assert_close(obs.max[kcy], 779.0, 0.0);
  assert_true(isnan(obs.min[kex])); /* not in the table */
  /* Monachou's own value is inside despite the rounding of the table; 8.46 is not */
  assert_false(karst_metrics_observed_outside(&obs, kml, 8.464115572807527));
  assert_true(karst_metrics_observed_outside(&obs, kml, 8.46));
  assert_false(karst_metrics_observed_outside(&obs, kml, NAN));

  write_file(TMP "/t.csv", "# comment\ncave,note,ASPL,source\n"
                           "A,\"has, a comma and \"\"quotes\"\"\",2.5,Collon 2017\n"
                           "B,\"multi\nline\",7,Collon 2017\nC,,100,other\n\n");
  assert_int_equal(karst_metrics_observed_load(&ctx, TMP "/t.csv", &obs), KARST_SUCCESS);
  int ka = -1;
  for (int k = 0; k < n; k++)
    if (strcmp(f[k].key, "aspl") == 0) ka = k;
  assert_int_equal(obs.n_caves, 2);
  assert_close(obs.min[ka], 2.5, 0.0);
  assert_close(obs.max[ka], 7.0, 0.0);
  write_file(TMP "/bad.csv", "cave,ASPL\nA,1\nB,x\n");
  assert_int_equal(karst_metrics_observed_load(&ctx, TMP "/bad.csv", &obs), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "bad.csv:3: column ASPL: 'x'"));
  write_file(TMP "/quote.csv", "cave,ASPL\n\"A,1\n");
  assert_int_equal(karst_metrics_observed_load(&ctx, TMP "/quote.csv", &obs), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "quote.csv:2: unterminated"));
}

/* karst_i_format_g17 against snprintf's "%.17g", string for string (src/io/format_internal.h):
 * special values, powers of ten and their neighbours, then 600 000 rounds of a random bit
 * pattern, a random significand at a random decimal scale (both signs), a random integer, a value
 * rounded to millimetres and a multiple of 1/8 (exact ties of the 18th digit come from these). */
static void check_g17(double v, int *compared) {
  char want[64], got[KARST_I_G17_SIZE];
  snprintf(want, sizeof want, "%.17g", v);
  size_t n = karst_i_format_g17(v, got);
  if (strcmp(want, got) != 0)
    fail_msg("%a: %%.17g gives '%s', karst_i_format_g17 '%s'", v, want, got);
  assert_int_equal(n, strlen(want));
  (*compared)++;
}

static void test_format_g17(void **state) {
  (void)state;
  int compared = 0;
  const double special[] = {0.0,
                            -0.0,
                            1.0,
                            -1.0,
                            0.1,
                            0.5,
                            1e-6,
                            9.9999999999999995e-7,
                            1e16,
                            1e17,
                            1e22,
                            1e23,
                            40.0,
                            2.5,
                            9.5,
                            0.30000000000000004,
                            1e300,
                            1e-300,
                            5e-324,
                            INFINITY,
                            -INFINITY,
                            NAN,
                            0x1p127,
                            0x1.fffffffffffffp126,
                            99999999999999999.0,
                            123456789012345678.0};
  for (size_t i = 0; i < sizeof special / sizeof special[0]; i++)
    check_g17(special[i], &compared);
  for (int k = -30; k < 40; k++) {
    double p = pow(10.0, k);
    check_g17(p, &compared), check_g17(nextafter(p, 0.0), &compared);
    check_g17(nextafter(p, INFINITY), &compared);
  }
  karst_rng_t rng;
  karst_rng_init(&rng, 17, 17);
  for (int i = 0; i < 600000; i++) {
    uint64_t u = karst_rng_u64(&rng);
    double v;
    memcpy(&v, &u, sizeof v);
    check_g17(v, &compared);
    double w = ldexp((double)(karst_rng_u64(&rng) >> 11), -53) *
               pow(10.0, (int)(karst_rng_u64(&rng) % 50) - 20);
    check_g17(w, &compared), check_g17(-w, &compared);
    check_g17((double)(int64_t)(karst_rng_u64(&rng) >> (karst_rng_u64(&rng) % 64)), &compared);
    check_g17(round(w * 1000.0) / 1000.0, &compared);
    check_g17((double)(karst_rng_u64(&rng) % 100000) / 8.0, &compared);
  }
  assert_true(compared > 3600000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_shipped_pairs),   cmocka_unit_test(test_karstnet_features),
      cmocka_unit_test(test_karstnet_errors), cmocka_unit_test(test_pline),
      cmocka_unit_test(test_pline_errors),    cmocka_unit_test(test_dispatch),
      cmocka_unit_test(test_write_roundtrip), cmocka_unit_test(test_observed),
      cmocka_unit_test(test_format_g17),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
