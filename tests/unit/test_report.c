/*
 * The HTML report on an ensemble built with a fake generator: every plot is
 * present, each <svg> is well-formed XML (Python's parser), there is no script
 * and no external reference, and headless Chromium renders it without a
 * console error, every bar visible and no two texts overlapping (the layout
 * check, which is shown to fail on pages broken on purpose).
 */
#include <inttypes.h>
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

static const char *const fake_names[] = {"nodes", "total_length", "aspl", "undefined"};

/* A member: a random chain of 4..9 nodes with tunnel types, from the member seed only. */
static karst_error_t fake_realise(karst_ctx_t *ctx, void *user, uint64_t seed, karst_int_t index,
                                  karst_network_t *net) {
  (void)ctx, (void)user, (void)index;
  karst_rng_t r;
  karst_rng_init(&r, seed, 0);
  int n = 4 + (int)karst_rng_below(&r, 6);
  for (int i = 0; i < n; i++)
    karst_network_add_node(net, karst_rng_uniform_range(&r, 0, 400),
                           karst_rng_uniform_range(&r, 0, 600), karst_rng_uniform_range(&r, 0, 100),
                           NULL);
  for (int i = 1; i < n; i++)
    karst_network_add_edge(net, i - 1, i, NULL);
  double *type = NULL;
  karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &type);
  for (karst_int_t e = 0; e < net->n_edges; e++)
    type[e] = (double)karst_rng_below(&r, KARST_TUNNEL_TYPE_COUNT);
  return KARST_SUCCESS;
}

static karst_error_t fake_write(karst_ctx_t *ctx, void *user, const char *dir,
                                const karst_network_t *net) {
  (void)user;
  char path[1024];
  snprintf(path, sizeof path, "%s/network.vtp", dir);
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  karst_attr_t *type = karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
  fprintf(f.fp, "%" PRId64 " %" PRId64 "\n", net->n_nodes, net->n_edges);
  for (karst_int_t i = 0; i < net->n_nodes; i++)
    fprintf(f.fp, "%.17g %.17g %.17g\n", net->xyz[3 * i], net->xyz[3 * i + 1], net->xyz[3 * i + 2]);
  for (karst_int_t e = 0; e < net->n_edges; e++)
    fprintf(f.fp, "%" PRId64 " %" PRId64 " %d\n", net->edges[2 * e], net->edges[2 * e + 1],
            (int)type->data[e]);
  return karst_atomic_commit(ctx, &f);
}

/* Reads what fake_write wrote (stands in for karst_read_network on a .vtp). */
static karst_error_t fake_read(karst_ctx_t *ctx, void *user, const char *path,
                               karst_network_t *net) {
  (void)user;
  FILE *fp = fopen(path, "r");
  if (!fp) return karst_set_error(ctx, KARST_EIO, "%s: cannot read", path);
  long long n = 0, m = 0;
  karst_error_t err = KARST_SUCCESS;
  if (fscanf(fp, "%lld %lld", &n, &m) != 2) err = karst_set_error(ctx, KARST_EPARSE, "%s:1", path);
  for (long long i = 0; !err && i < n; i++) {
    double x, y, z;
    if (fscanf(fp, "%lf %lf %lf", &x, &y, &z) != 3)
      err = karst_set_error(ctx, KARST_EPARSE, "%s: node", path);
    else
      karst_network_add_node(net, x, y, z, NULL);
  }
  double *type = NULL;
  for (long long e = 0; !err && e < m; e++) {
    long long a, b;
    int t;
    if (fscanf(fp, "%lld %lld %d", &a, &b, &t) != 3) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s: edge", path);
      break;
    }
    karst_network_add_edge(net, a, b, NULL);
    karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &type);
    type[e] = t;
  }
  fclose(fp);
  return err;
}

static karst_error_t fake_measure(karst_ctx_t *ctx, void *user, const karst_network_t *net,
                                  double *v) {
  (void)ctx, (void)user;
  double len = 0;
  for (karst_int_t e = 0; e < net->n_edges; e++)
    len += karst_network_edge_length(net, e);
  v[0] = (double)net->n_nodes;
  v[1] = len;
  v[2] = (double)(net->n_nodes + 1) / 3.0;
  v[3] = NAN;
  return KARST_SUCCESS;
}

static char *ens_dir;

/* Key points of the test scenario, as many as branchwork has. */
#define REPORT_TEST_KEY_POINTS 17

static int setup(void **state) {
  (void)state;
  char tmpl[] = "/tmp/karst_test_report_XXXXXX";
  ens_dir = strdup(mkdtemp(tmpl));
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  opt.n = 20;
  opt.seed = 2021;
  opt.nthreads = 2;
  opt.scenario_path = "datasets/scenarios/branchwork <test>.yaml";
  opt.scenario_hash = "00112233aabbccdd";
  /* Nested objects and arrays over several lines, as karst_generate_write_parameters writes
   * them, and a string longer than any fixed buffer: the report must show all of it.
   * Arrays of same-keyed objects (17 key points as in branchwork, fracture families with
   * their members in another order, one lens with an escaped name and a nested object) are
   * shown as one table each; arrays whose elements differ in names ("mixed") are not. */
  static char params[8192];
  char longtext[301];
  for (int i = 0; i < 300; i++)
    longtext[i] = (char)('a' + i % 26);
  longtext[300] = '\0';
  char keypoints[4096] = "";
  for (int i = 2; i < REPORT_TEST_KEY_POINTS; i++) {
    size_t len = strlen(keypoints);
    snprintf(keypoints + len, sizeof keypoints - len,
             ",\n      {\"name\": \"waypoint %d\", \"type\": \"waypoint\", "
             "\"position\": [%d, %d.5, -%de1]}",
             i, 10 * i, i, i);
  }
  snprintf(params, sizeof params,
           "    \"name\": \"branchwork & co\",\n    \"skeleton.gamma\": 2,\n"
           "    \"domain_min\": [0, -0.5e2, 1e-3],\n"
           "    \"key_points\": [\n      {\"name\": \"sink <A>\", \"type\": \"sink\", "
           "\"position\": [1, 2, 3]},\n      {\"name\": \"spring\", \"type\": \"spring\", "
           "\"position\": [4, 5, 6]}%s],\n"
           "    \"fractures\": [{\"dip_direction\": 120, \"dip\": 80, \"weight\": 1}, "
           "{\"weight\": 0.5, \"dip\": 60, \"dip_direction\": 30}],\n"
           "    \"lenses\": [{\"z<0 & \\\"q\\\"\": 1, \"shape\": {\"r\": 2, \"h\": [1, 2]}}],\n"
           "    \"mixed\": [{\"a\": 1}, {\"b\": 2}],\n"
           "    \"permeability\": {\"background\": 1, \"tree\": null},\n"
           "    \"horizons\": [],\n    \"terrain\": {},\n"
           "    \"flags\": [true, false, null, \"x\"],\n"
           "    \"long\": \"%s\"\n",
           keypoints, longtext);
  opt.parameters_json = params;
  karst_ensemble_hooks_t h = {fake_realise, fake_write, fake_measure, NULL, 4, fake_names, NULL};
  return karst_ensemble_run(&ctx, ens_dir, &opt, &h, NULL) == KARST_SUCCESS ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  char cmd[1200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", ens_dir);
  int rc = system(cmd);
  free(ens_dir);
  return rc;
}

static int count(const char *s, const char *what) {
  int n = 0;
  for (const char *p = strstr(s, what); p; p = strstr(p + 1, what))
    n++;
  return n;
}

/* Plots the report of @p dir must hold (counted independently of the report's code): a
 * histogram per metric column of metrics.csv whose defined values are not all equal, the rose,
 * the stereonet and the degree distribution, four views (plan, two sections, oblique) per
 * member drawn, and four more for the survey when the page says it has its own frame. */
static int expected_plots(const char *dir, const char *html, int members) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_table_t t;
  karst_ensemble_table_init(&t);
  char path[1200];
  snprintf(path, sizeof path, "%s/metrics.csv", dir);
  assert_int_equal(karst_ensemble_table_read(&ctx, path, &t), KARST_SUCCESS);
  int vary = 0;
  for (int c = 0; c < t.n_cols; c++) {
    double first = NAN;
    int differs = 0;
    for (karst_int_t r = 0; r < t.n_rows; r++) {
      double v = t.values[r * t.n_cols + c];
      if (isnan(v)) continue;
      if (isnan(first)) first = v;
      differs |= v != first;
    }
    vary += differs;
  }
  karst_ensemble_table_destroy(&t);
  return vary + 3 + 4 * members + (strstr(html, "its own row of views") ? 4 : 0);
}

static void make_survey(karst_report_survey_t *s) {
  karst_report_survey_init(s);
  s->label = strdup("Grotte <survey>.3d");
  s->n_values = 3;
  s->names[0] = "aspl";
  s->names[1] = "nodes";
  s->names[2] = "total_length";
  s->values[0] = 0.5; /* below every member (aspl of members >= 5/3): outside the band */
  s->values[1] = 6;
  s->values[2] = NAN;
  /* A north–south survey: its rose has one petal at 0°. */
  karst_network_add_node(&s->net, 0, 0, 0, NULL);
  karst_network_add_node(&s->net, 0, 50, 0, NULL);
  karst_network_add_node(&s->net, 0, 80, -10, NULL);
  karst_network_add_edge(&s->net, 0, 1, NULL);
  karst_network_add_edge(&s->net, 1, 2, NULL);
}

static void test_report_content(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_report_survey_t sv;
  make_survey(&sv);
  karst_report_options_t opt;
  karst_report_options_init(&opt);
  opt.surveys = &sv;
  opt.n_surveys = 1;
  opt.published_path = KARST_SOURCE_DIR "/datasets/published_metrics.csv";
  opt.members_drawn = 3;
  opt.read_network = fake_read;
  char out[1200];
  snprintf(out, sizeof out, "%s/report.html", ens_dir);
  assert_int_equal(karst_report_write(&ctx, ens_dir, out, &opt), KARST_SUCCESS);
  char *html = test_util_read_file(out);
  assert_non_null(html);
  /* 3 histograms ("undefined" is a row of the table of values) + rose, stereonet and degrees
   * + 3 members × 4 views (+ 4 for the survey in its own frame). */
  const int plots = expected_plots(ens_dir, html, 3);
  assert_int_equal(count(html, "<svg "), plots);
  assert_true(plots == 18 || plots == 22);
  assert_int_equal(count(html, "</svg>"), plots);
  assert_int_equal(count(html, "<script"), 0);
  assert_int_equal(count(html, "src="), 0);
  assert_int_equal(count(html, "href="), 0);
  /* The only URL is the SVG namespace (a name, never fetched). */
  assert_int_equal(count(html, "http"), count(html, "http://www.w3.org/2000/svg"));
  /* Scenario summary, seed, escaped names. */
  assert_non_null(strstr(html, "branchwork &amp; co"));
  assert_non_null(strstr(html, "branchwork &lt;test&gt;.yaml"));
  assert_non_null(strstr(html, "<td class=\"l\">2021</td>"));
  assert_non_null(strstr(html, "00112233aabbccdd"));
  /* Every parameter in full, nested objects and arrays as nested tables (arrays of
   * same-keyed objects as one table each: test_report_parameter_rows). */
  assert_non_null(strstr(html, "<tr><th class=\"l\">key_points</th><td class=\"l\"><table "
                               "class=\"json rows\"><tr><th class=\"l\">name</th><th "
                               "class=\"l\">type</th><th class=\"l\">position</th></tr><tr><td "
                               "class=\"l\">sink &lt;A&gt;</td><td class=\"l\">sink</td><td "
                               "class=\"l\">[1, 2, 3]</td></tr>"));
  assert_non_null(strstr(html, "<th class=\"l\">domain_min</th><td class=\"l\">[0, -0.5e2, 1e-3]"));
  assert_non_null(strstr(html, "<th class=\"l\">tree</th><td class=\"l\">null</td>"));
  assert_non_null(strstr(html, "<th class=\"l\">horizons</th><td class=\"l\">[ ]</td>"));
  assert_non_null(strstr(html, "<th class=\"l\">terrain</th><td class=\"l\">{ }</td>"));
  assert_non_null(strstr(html, "[true, false, null, &quot;x&quot;]"));
  assert_non_null(strstr(html, "xyzabcdefghijklmn</td>")); /* characters 284-300 of "long" */
  {
    /* Independent reading: Python's json and html.parser agree value by value. */
    char pcmd[2600];
    snprintf(pcmd, sizeof pcmd,
             "/usr/bin/python3 '%s/tests/python/check_report_parameters.py' '%s' '%s'",
             KARST_SOURCE_DIR, out, ens_dir);
    assert_int_equal(system(pcmd), 0);
  }
  /* The comparison: aspl flagged, its 34-cave range (ASPL, published table) shown. */
  assert_non_null(strstr(html, "Grotte &lt;survey&gt;.3d"));
  assert_int_equal(count(html, "outside the 5–95 % band"), 1);
  assert_non_null(strstr(html, "<td>55.72</td>"));
  assert_non_null(strstr(html, "34 caves: 2.321 – 55.72"));
  /* Survey value line in the aspl and nodes histograms (total_length undefined). */
  assert_int_equal(count(html, "stroke-dasharray=\"5 3\""), 2);
  assert_non_null(strstr(html, "<td>undefined for every member</td>"));
  /* Maps coloured by tunnel type: at least one path in a palette colour (tube's). */
  assert_non_null(strstr(html, "<path class=\"network\" fill=\"none\" stroke=\"#0072B2\""));
  /* The stereonet with the two fracture families of the parameters as great circles. */
  assert_int_equal(count(html, "<polyline class=\"structure\""), 2);
  assert_non_null(strstr(html, "fracture family 1: 120° / 80° (dip direction / dip)"));
  assert_non_null(strstr(html, "fracture family 2: 030° / 60° (dip direction / dip)"));
  /* Every axis of a metric names its quantity and unit. */
  assert_non_null(strstr(html, "nodes of the full graph (count)"));
  assert_non_null(strstr(html, "average shortest path length on Gs (edges)"));
  assert_non_null(strstr(html, "member 0000 (seed "));
  assert_non_null(strstr(html, "VTK 9.1"));
  assert_non_null(strstr(html, "FLANN 1.9"));
  assert_null(strstr(html, "igraph")); /* not a library karst uses: tests only */
  assert_non_null(strstr(html, "Published ranges: 34 caves"));

  /* Each <svg> block parses as XML (Python's parser, independent of our writer). */
  char cmd[2048];
  snprintf(cmd, sizeof cmd,
           "/usr/bin/python3 -c \"import re,sys,xml.etree.ElementTree as E; "
           "h=open('%s',encoding='utf-8').read(); b=re.findall(r'<svg .*?</svg>', h, re.S); "
           "[E.fromstring(x) for x in b]; sys.exit(0 if len(b)==%d else 1)\"",
           out, plots);
  assert_int_equal(system(cmd), 0);
  free(html);
  karst_report_survey_destroy(&sv);
}

/* The table that follows @p label in @p html, up to its first "</table>" (the whole table when
 * no other table is nested in it), as a new string; NULL when there is none. */
static char *table_after(const char *html, const char *label) {
  const char *p = strstr(html, label);
  if (!p) return NULL;
  p += strlen(label);
  const char *end = strstr(p, "</table>");
  if (strncmp(p, "<table", 6) != 0 || !end) return NULL;
  size_t n = (size_t)(end - p) + strlen("</table>");
  char *t = malloc(n + 1);
  memcpy(t, p, n);
  t[n] = '\0';
  return t;
}

/* An array of objects that all have the same member names is ONE table: a header row with
 * the names in the first element's order, then one row per element (cells in header order
 * even when an element lists its members in another order), nested values inside the cells;
 * an array whose elements differ in names keeps one table per element. */
static void test_report_parameter_rows(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_report_options_t opt;
  karst_report_options_init(&opt);
  opt.published_path = KARST_SOURCE_DIR "/datasets/published_metrics.csv";
  opt.read_network = fake_read;
  char out[1200];
  snprintf(out, sizeof out, "%s/rows.html", ens_dir);
  assert_int_equal(karst_report_write(&ctx, ens_dir, out, &opt), KARST_SUCCESS);
  char *html = test_util_read_file(out);
  assert_non_null(html);
  /* key_points, fractures and lenses; not mixed. */
  assert_int_equal(count(html, "<table class=\"json rows\">"), 3);

  char *kp = table_after(html, "<th class=\"l\">key_points</th><td class=\"l\">");
  assert_non_null(kp);
  assert_true(strncmp(kp,
                      "<table class=\"json rows\"><tr><th class=\"l\">name</th><th "
                      "class=\"l\">type</th><th class=\"l\">position</th></tr><tr><td",
                      strlen("<table class=\"json rows\"><tr><th class=\"l\">name</th><th "
                             "class=\"l\">type</th><th class=\"l\">position</th></tr><tr><td")) ==
              0);
  assert_int_equal(count(kp, "<table"), 1); /* no table per element */
  assert_int_equal(count(kp, "<tr>"), 1 + REPORT_TEST_KEY_POINTS);
  assert_int_equal(count(kp, "<th "), 3);
  assert_int_equal(count(kp, "<td "), 3 * REPORT_TEST_KEY_POINTS);
  assert_non_null(strstr(kp, "<tr><td class=\"l\">spring</td><td class=\"l\">spring</td><td "
                             "class=\"l\">[4, 5, 6]</td></tr>"));
  assert_non_null(strstr(kp, "<tr><td class=\"l\">waypoint 16</td><td class=\"l\">waypoint</td>"
                             "<td class=\"l\">[160, 16.5, -16e1]</td></tr></table>"));
  free(kp);

  char *fr = table_after(html, "<th class=\"l\">fractures</th><td class=\"l\">");
  assert_non_null(fr);
  assert_string_equal(fr, "<table class=\"json rows\"><tr><th class=\"l\">dip_direction</th>"
                          "<th class=\"l\">dip</th><th class=\"l\">weight</th></tr>"
                          "<tr><td class=\"l\">120</td><td class=\"l\">80</td>"
                          "<td class=\"l\">1</td></tr>"
                          "<tr><td class=\"l\">30</td><td class=\"l\">60</td>"
                          "<td class=\"l\">0.5</td></tr></table>");
  free(fr);

  /* One element: a one-row table; its name escaped, a nested object inside its cell. */
  assert_non_null(strstr(html, "<th class=\"l\">lenses</th><td class=\"l\"><table class=\"json "
                               "rows\"><tr><th class=\"l\">z&lt;0 &amp; &quot;q&quot;</th><th "
                               "class=\"l\">shape</th></tr><tr><td class=\"l\">1</td><td "
                               "class=\"l\"><table class=\"json\"><tr><th class=\"l\">r</th><td "
                               "class=\"l\">2</td></tr><tr><th class=\"l\">h</th><td "
                               "class=\"l\">[1, 2]</td></tr></table></td></tr></table>"));
  /* Elements with different names: one table per element, as before. */
  assert_non_null(strstr(html, "<th class=\"l\">mixed</th><td class=\"l\"><table class=\"json\">"
                               "<tr><th class=\"l\">[0]</th><td class=\"l\"><table "
                               "class=\"json\"><tr><th class=\"l\">a</th><td "
                               "class=\"l\">1</td></tr></table></td></tr><tr><th "
                               "class=\"l\">[1]</th>"));
  assert_int_equal(count(html, "<script"), 0);

  /* The independent check reads the rows tables value by value, and fails on a changed value
   * in a row or on an array of same-keyed objects shown as one table per element. */
  char pcmd[4096];
  snprintf(pcmd, sizeof pcmd,
           "/usr/bin/python3 '%s/tests/python/check_report_parameters.py' '%s' '%s'",
           KARST_SOURCE_DIR, out, ens_dir);
  assert_int_equal(system(pcmd), 0);
  const char *mutations[] = {"s.replace('[160, 16.5, -16e1]', '[160, 16.5, -16e2]')",
                             "s.replace('<td class=\\\"l\\\">30</td>', "
                             "'<td class=\\\"l\\\">31</td>')",
                             "s.replace('json rows', 'json', 1)"};
  for (int m = 0; m < 3; m++) {
    snprintf(pcmd, sizeof pcmd,
             "/usr/bin/python3 -c \"import sys; s=open(sys.argv[1],encoding='utf-8').read(); "
             "t=%s; assert t != s; open(sys.argv[2],'w',encoding='utf-8').write(t)\" '%s' "
             "'%s.bad' && ! /usr/bin/python3 '%s/tests/python/check_report_parameters.py' "
             "'%s.bad' '%s' >/dev/null",
             mutations[m], out, out, KARST_SOURCE_DIR, out, ens_dir);
    assert_int_equal(system(pcmd), 0);
  }
  free(html);
}

/* Unreadable members are listed; the page is still written. No survey: statistics only. */
static void test_report_degraded(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_report_options_t opt;
  karst_report_options_init(&opt);
  opt.published_path = KARST_SOURCE_DIR "/datasets/published_metrics.csv";
  opt.members_pooled = 2;
  char out[1200];
  snprintf(out, sizeof out, "%s/report_default_reader.html", ens_dir);
  /* The default reader (karst_read_network) cannot read the fake's text "network.vtp". */
  assert_int_equal(karst_report_write(&ctx, ens_dir, out, &opt), KARST_SUCCESS);
  char *html = test_util_read_file(out);
  assert_non_null(strstr(html, "Members that could not be read"));
  assert_non_null(strstr(html, "ensemble statistics (no survey given)"));
  assert_non_null(strstr(html, "no horizontal conduits"));
  free(html);
  /* A missing ensemble: error names the file, no output written. */
  snprintf(out, sizeof out, "%s/nothing.html", ens_dir);
  assert_int_equal(karst_report_write(&ctx, "/nonexistent/ens", out, &opt), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/nonexistent/ens/ensemble.json"));
  assert_int_not_equal(access(out, F_OK), 0);
}

static karst_error_t seed_only_realise(karst_ctx_t *ctx, void *user, uint64_t seed,
                                       karst_int_t index, karst_network_t *net) {
  (void)user;
  return fake_realise(ctx, NULL, seed, index, net);
}

/* The real files: members written by the VTK writer and read back by karst_read_network,
 * every metric of karst_metric_fields, and Monachou (GOCAD PLine) loaded as the survey. */
static void test_report_real_files(void **state) {
  (void)state;
  char tmpl[] = "/tmp/karst_test_report_real_XXXXXX";
  char *dir = mkdtemp(tmpl);
  assert_non_null(dir);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_ensemble_hooks_t h;
  karst_ensemble_pipeline_t pipe;
  assert_int_equal(karst_ensemble_hooks_pipeline(&ctx, &h, &pipe, &sc), KARST_SUCCESS);
  h.realise = seed_only_realise;
  karst_ensemble_options_t eo;
  karst_ensemble_options_init(&eo);
  eo.n = 8;
  eo.nthreads = 2;
  assert_int_equal(karst_ensemble_run(&ctx, dir, &eo, &h, NULL), KARST_SUCCESS);
  karst_report_survey_t sv;
  assert_int_equal(karst_report_survey_load(
                       &ctx, KARST_SOURCE_DIR "/datasets/surveys/karstnet/Monachou.pl", &sv),
                   KARST_SUCCESS);
  karst_report_options_t opt;
  karst_report_options_init(&opt);
  opt.surveys = &sv;
  opt.n_surveys = 1;
  opt.published_path = KARST_SOURCE_DIR "/datasets/published_metrics.csv";
  char out[1200];
  snprintf(out, sizeof out, "%s/report.html", dir);
  assert_int_equal(karst_report_write(&ctx, dir, out, &opt), KARST_SUCCESS);
  char *html = test_util_read_file(out);
  assert_non_null(html);
  assert_null(strstr(html, "could not be read"));
  /* histograms of the metrics that vary + rose, stereonet, degrees + 4 members x 4 views */
  assert_int_equal(count(html, "<svg "), expected_plots(dir, html, 4));
  /* Monachou's aspl (docs: 7.5810126582278485) appears as the survey value, 4 digits. */
  assert_non_null(strstr(html, "<td>7.581</td>"));
  free(html);
  karst_report_survey_destroy(&sv);
  karst_scenario_destroy(&sc);
  char cmd[1200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  assert_int_equal(system(cmd), 0);
}

/* Headless Chromium renders the page: no console error, every plot in the DOM. */
static void test_report_chromium(void **state) {
  (void)state;
  if (system("command -v chromium >/dev/null 2>&1") != 0) {
    print_error("chromium not installed: run scripts/install-deps\n");
    fail();
  }
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_report_survey_t sv;
  make_survey(&sv);
  karst_report_options_t opt;
  karst_report_options_init(&opt);
  opt.surveys = &sv;
  opt.n_surveys = 1;
  opt.published_path = KARST_SOURCE_DIR "/datasets/published_metrics.csv";
  opt.read_network = fake_read;
  char out[1200];
  snprintf(out, sizeof out, "%s/chromium.html", ens_dir);
  assert_int_equal(karst_report_write(&ctx, ens_dir, out, &opt), KARST_SUCCESS);
  karst_report_survey_destroy(&sv);
  char *html = test_util_read_file(out);
  assert_non_null(html);
  const int plots = expected_plots(ens_dir, html, 4);
  free(html);
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "bash '%s/tests/cli/test_report_chromium.sh' --check '%s' %d",
           KARST_SOURCE_DIR, out, plots);
  assert_int_equal(system(cmd), 0);
  /* The layout check measures: a page with a bar made 0.3 px wide, a note moved onto the one
   * above it, a note moved into the bars, an axis without its unit, a text pushed past the
   * plot's edge each fail it. */
  const char *mutations[] = {
      "re.sub(r'(<rect class=\\\"bar\\\" x=\\\"[0-9.]+\\\" y=\\\"[0-9.]+\\\" "
      "width=\\\")[0-9.]+', r'\\g<1>0.3', s, count=1)",
      "s.replace('y=\\\"41.00\\\" text-anchor', 'y=\\\"30.00\\\" text-anchor', 1)",
      "s.replace('y=\\\"41.00\\\" text-anchor', 'y=\\\"175.00\\\" text-anchor', 1)",
      "s.replace('nodes of the full graph (count)', 'nodes of the full graph', 1)",
      "s.replace('<text x=\\\"4.00\\\" y=\\\"13.00\\\"', '<text x=\\\"300.00\\\" "
      "y=\\\"13.00\\\"', 1)",
  };
  for (size_t m = 0; m < sizeof mutations / sizeof mutations[0]; m++) {
    snprintf(cmd, sizeof cmd,
             "/usr/bin/python3 -c \"import re, sys; s=open(sys.argv[1],encoding='utf-8').read(); "
             "t=%s; assert t != s; open(sys.argv[2],'w',encoding='utf-8').write(t)\" '%s' "
             "'%s.bad.html' && ! bash '%s/tests/cli/test_report_chromium.sh' --check "
             "'%s.bad.html' %d >/dev/null",
             mutations[m], out, out, KARST_SOURCE_DIR, out, plots);
    if (system(cmd) != 0) fail_msg("the layout check passed a page with mutation %zu", m);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_report_content),  cmocka_unit_test(test_report_parameter_rows),
      cmocka_unit_test(test_report_degraded), cmocka_unit_test(test_report_real_files),
      cmocka_unit_test(test_report_chromium),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
