/*
 * The PolyData files karst writes without VTK (src/io/write_vtp.c) against the files VTK 9.1's
 * own writer makes from the same data (src/io/vtk_shim.cpp, io/vtk_reference_internal.h): the
 * same bytes for networks, samples, meshes and polygons, large and empty, with every kind of
 * array and awkward values in the ranges VTK prints; the same error codes and messages for bad
 * input, with no file left behind; and the shortest round-trip number format against strtod.
 * VTK is the independent method here: its writer is the reference the format is defined by.
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

#include "io/vtk_reference_internal.h"
#include "io/vtp_write_internal.h"
#include "karst.h"
#include "test_util.h"

static char dir[64];

static int setup(void **state) {
  (void)state;
  strcpy(dir, "/tmp/karst_test_vtp_write_XXXXXX");
  return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  return system(cmd) == 0 ? 0 : -1;
}

static long file_size(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return -1;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fclose(fp);
  return n;
}

/* Both files exist and hold the same bytes; on a difference, the first differing line. */
static void assert_same_file(const char *ours, const char *vtk) {
  char *a = test_util_read_file(ours), *b = test_util_read_file(vtk);
  assert_non_null(a);
  assert_non_null(b);
  long na = file_size(ours), nb = file_size(vtk);
  if (na != nb || memcmp(a, b, (size_t)na) != 0) {
    long i = 0, line = 1, start = 0;
    while (i < na && i < nb && a[i] == b[i]) {
      if (a[i] == '\n') line++, start = i + 1;
      i++;
    }
    print_error("%s (%ld bytes) and VTK's %s (%ld bytes) differ at line %ld:\n  ours: %.200s\n"
                "  VTK:  %.200s\n",
                ours, na, vtk, nb, line, a + start, b + start);
    free(a), free(b);
    fail();
  }
  free(a), free(b);
}

/* karst's writer karst_vtk_write_WHAT and VTK's karst_i_vtkref_write_WHAT on the same data
 * (the arguments after the path), into NAME.vtp and NAME.vtk.vtp: both succeed, same bytes. */
#define COMPARE_WRITERS(name, what, ...)                                                           \
  do {                                                                                             \
    char o_[256], v_[256];                                                                         \
    snprintf(o_, sizeof o_, "%s/%s.vtp", dir, name);                                               \
    snprintf(v_, sizeof v_, "%s/%s.vtk.vtp", dir, name);                                           \
    assert_int_equal(karst_vtk_write_##what(NULL, o_, __VA_ARGS__), KARST_SUCCESS);                \
    assert_int_equal(karst_i_vtkref_write_##what(NULL, v_, __VA_ARGS__), KARST_SUCCESS);           \
    assert_same_file(o_, v_);                                                                      \
  } while (0)

/* Write @p net with both writers; same result code, same message, same bytes. */
static void compare_network(const char *name, const karst_network_t *net) {
  char ours[256], vtk[256];
  snprintf(ours, sizeof ours, "%s/%s.vtp", dir, name);
  snprintf(vtk, sizeof vtk, "%s/%s.vtk.vtp", dir, name);
  karst_ctx_t c1, c2;
  karst_ctx_init(&c1);
  karst_ctx_init(&c2);
  karst_error_t e1 = karst_vtk_write_network(&c1, ours, net);
  /* on an error, VTK's writer is given the same name, so that the messages can be compared */
  karst_error_t e2 = karst_i_vtkref_write_network(&c2, e1 ? ours : vtk, net);
  if (e1 != e2 || strcmp(c1.errmsg, c2.errmsg) != 0) {
    print_error("%s: ours %d \"%s\", VTK %d \"%s\"\n", name, e1, c1.errmsg, e2, c2.errmsg);
    fail();
  }
  if (e1 == KARST_SUCCESS)
    assert_same_file(ours, vtk);
  else
    assert_int_equal(access(ours, F_OK), -1); /* neither left a file behind */
}

/* A network like karst generate's: the attributes it writes (units, palettes), labels, strings. */
static void make_network(karst_network_t *net, karst_rng_t *r, int n_nodes, int n_edges,
                         const double *specials, int n_specials) {
  karst_network_init(net);
  for (int i = 0; i < n_nodes; i++)
    assert_int_equal(karst_network_add_node(net, 1000 * karst_rng_uniform(r) - 300,
                                            2e6 + 500 * karst_rng_uniform(r),
                                            -50 + 100 * karst_rng_uniform(r), NULL),
                     KARST_SUCCESS);
  for (int e = 0; e < n_edges; e++) {
    karst_int_t u = (karst_int_t)(karst_rng_u64(r) % (uint64_t)n_nodes);
    karst_int_t v = (karst_int_t)(karst_rng_u64(r) % (uint64_t)n_nodes);
    assert_int_equal(karst_network_add_edge(net, u, v, NULL), KARST_SUCCESS);
  }
  static const struct {
    int domain, integer;
    const char *name;
  } attrs[] = {{KARST_ATTR_NODE, 1, "kind"},       {KARST_ATTR_NODE, 0, "water_table_distance"},
               {KARST_ATTR_NODE, 1, "spring"},     {KARST_ATTR_EDGE, 0, "cost"},
               {KARST_ATTR_EDGE, 1, "tunnel_type"}, {KARST_ATTR_EDGE, 0, "radius"},
               {KARST_ATTR_EDGE, 1, "vadose"},     {KARST_ATTR_EDGE, 1, "zone"},
               {KARST_ATTR_EDGE, 0, "not_a_karst_array"}};
  for (size_t k = 0; k < sizeof attrs / sizeof attrs[0]; k++) {
    double *d;
    assert_int_equal(karst_network_attr_add(net, (karst_attr_domain_t)attrs[k].domain,
                                            attrs[k].name, 1, attrs[k].integer, &d),
                     KARST_SUCCESS);
    karst_int_t n = attrs[k].domain == KARST_ATTR_NODE ? n_nodes : n_edges;
    for (karst_int_t i = 0; i < n; i++) {
      if (attrs[k].integer)
        d[i] = (double)(int)(karst_rng_u64(r) % 7) - (k == 7 ? 3 : 0);
      else if (n_specials > 0 && karst_rng_uniform(r) < 0.3)
        d[i] = specials[karst_rng_u64(r) % (uint64_t)n_specials];
      else
        d[i] = ldexp(karst_rng_uniform(r) - 0.3, (int)(karst_rng_u64(r) % 40) - 20);
    }
  }
  for (int i = 0; i < n_nodes; i += 3) {
    char lab[32];
    snprintf(lab, sizeof lab, "st%d", i);
    if (i % 9 != 0) assert_int_equal(karst_network_set_label(net, i, lab), KARST_SUCCESS);
  }
  const char *springs[] = {"Source de l'Orbe", "sp2 <&>"};
  assert_int_equal(karst_network_set_strings(net, "spring_names", 2, springs), KARST_SUCCESS);
  assert_int_equal(karst_network_set_crs(net, "EPSG:2056"), KARST_SUCCESS);
}

static void test_networks(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 20261206, 0);
  /* values whose printing in RangeMin / RangeMax is awkward: exponents at the switch to
   * exponential notation (1e-7, 1e21), powers of two, subnormals, signed zeros, infinities,
   * NaN (skipped by VTK's ranges) */
  const double specials[] = {1e-7,    1e-6,     9.999999e-7, 1e21,    9.99e20, 1e20,  -1e21,
                             0x1p-1022, 0x1p-1074, 0x1p60,   0x1p-3,  -0.0,  0.0,     INFINITY,
                             -INFINITY, NAN,     123456789012345678.0, 5e-324, 0.1, 1.0 / 3,
                             -2.5e-8,   4.35,    0x1p1023, 1.7976931348623157e308};
  const int sizes[][2] = {{0, 0}, {1, 0}, {2, 1}, {40, 60}, {2662, 2676}, {4096, 8192}, {9000, 20000}};
  for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
    for (int sp = 0; sp < 2; sp++) {
      karst_network_t net;
      make_network(&net, &r, sizes[s][0], sizes[s][1], specials,
                   sp ? (int)(sizeof specials / sizeof specials[0]) : 0);
      if (s == 3) net.title = strdup("a title");
      char name[64];
      snprintf(name, sizeof name, "net_%zu_%d", s, sp);
      compare_network(name, &net);
      karst_network_destroy(&net);
    }
  }
  /* a 3-component attribute: its range is of the tuples' norms, and VTK adds the information
   * key L2_NORM_RANGE after UNITS_LABEL */
  for (int ints = 0; ints < 2; ints++) {
    karst_network_t net;
    make_network(&net, &r, 50, 70, NULL, 0);
    double *d;
    assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_NODE, "direction", 3, ints, &d),
                     KARST_SUCCESS);
    for (int i = 0; i < 3 * 50; i++)
      d[i] = ints ? (double)(int)(karst_rng_u64(&r) % 2001) - 1000 : karst_rng_gaussian(&r);
    compare_network(ints ? "vector_int" : "vector", &net);
    karst_network_destroy(&net);
  }
  /* one value per special, alone: its range printed on its own */
  for (size_t k = 0; k < sizeof specials / sizeof specials[0]; k++) {
    karst_network_t net;
    karst_network_init(&net);
    double *d;
    assert_int_equal(karst_network_add_node(&net, specials[k] == specials[k] && isfinite(specials[k]) ? specials[k] : 1, 0, 0, NULL), KARST_SUCCESS);
    assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_NODE, "value", 1, 0, &d),
                     KARST_SUCCESS);
    d[0] = specials[k];
    char name[64];
    snprintf(name, sizeof name, "special_%zu", k);
    compare_network(name, &net);
    karst_network_destroy(&net);
  }
}

/* Shortest digits of random doubles: they read back exactly, and no shorter string does. */
static void test_shortest(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 7, 1);
  char buf[40];
  for (int i = 0; i < 300000; i++) {
    double v;
    uint64_t bits = karst_rng_u64(&r);
    if (i % 3 == 0)
      memcpy(&v, &bits, sizeof v);
    else if (i % 3 == 1)
      v = ldexp(1.0, (int)(bits % 2000) - 1000) * (i % 2 ? 1 : -1); /* powers of two */
    else
      v = round(karst_rng_uniform(&r) * 1e6) / 1000;
    if (!isfinite(v)) continue;
    karst_i_vtp_format_shortest(v, buf);
    double back = strtod(buf, NULL);
    if (!(back == v)) {
      print_error("%.17g printed as %s, read back as %.17g\n", v, buf, back);
      fail();
    }
    /* no string of fewer significant digits reads back as v: count the significant digits
     * (without sign, point, leading and trailing zeros), then try the nearest shorter one */
    char sig[40];
    int digits = 0;
    for (const char *c = buf; *c && *c != 'e'; c++)
      if (*c >= '0' && *c <= '9' && (digits > 0 || *c != '0')) sig[digits++] = *c;
    while (digits > 0 && sig[digits - 1] == '0')
      digits--;
    if (digits > 1 && v != 0) {
      char shorter[40];
      snprintf(shorter, sizeof shorter, "%.*e", digits - 2, v);
      if (strtod(shorter, NULL) == v) {
        print_error("%.17g printed as %s but %s reads back too\n", v, buf, shorter);
        fail();
      }
    }
  }
  const struct {
    double v;
    const char *s;
  } fixed[] = {{0.5, "0.5"},         {78, "78"},          {-0.0, "0"},
               {1e299, "1e+299"},    {-1e299, "-1e+299"}, {1e-7, "1e-7"},
               {1e-6, "0.000001"},   {1e21, "1e+21"},     {1e20, "100000000000000000000"},
               {INFINITY, "Infinity"}, {0.1, "0.1"},      {123.456, "123.456"},
               {5e-324, "5e-324"},   {1.5e300, "1.5e+300"}};
  for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; k++) {
    karst_i_vtp_format_shortest(fixed[k].v, buf);
    assert_string_equal(buf, fixed[k].s);
  }
}

static void test_samples(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 3, 0);
  const int sizes[] = {0, 1, 500, 20000};
  for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
    karst_samples_t smp;
    karst_samples_init(&smp);
    for (int i = 0; i < sizes[s]; i++) {
      double p[3] = {karst_rng_uniform(&r) * 100, karst_rng_uniform(&r) * 100,
                     karst_rng_uniform(&r) * 10};
      assert_int_equal(karst_samples_add(&smp, p, (karst_sample_source_t)(karst_rng_u64(&r) %
                                                                         KARST_SAMPLE_SOURCE_COUNT)),
                       KARST_SUCCESS);
    }
    smp.n_key_points = sizes[s] / 10;
    smp.crs = s % 2 ? "EPSG:2154" : NULL;
    char name[64];
    snprintf(name, sizeof name, "samples_%zu", s);
    COMPARE_WRITERS(name, samples, &smp);
    karst_samples_destroy(&smp);
  }
}

/* A mesh of @p nv vertices and @p nt triangles, its arrays, both writers: the same bytes. Large
 * ones make the writer flush its buffer many times and fill in array headers already written
 * out to the file. */
static void compare_meshes(int nv, int nt) {
  karst_rng_t r;
  karst_rng_init(&r, 5, (uint64_t)nt);
  double *xyz = malloc(3 * (size_t)nv * sizeof *xyz);
  karst_int_t *tri = malloc(3 * (size_t)nt * sizeof *tri);
  int *label = malloc((size_t)nt * sizeof *label), *feat = malloc((size_t)nt * sizeof *feat);
  int *id = malloc((size_t)nt * sizeof *id);
  assert_true(xyz && tri && label && feat && id);
  for (int i = 0; i < 3 * nv; i++)
    xyz[i] = karst_rng_uniform(&r) * 50 - 10;
  for (int t = 0; t < nt; t++) {
    for (int k = 0; k < 3; k++)
      tri[3 * t + k] = (karst_int_t)(karst_rng_u64(&r) % nv);
    label[t] = (int)(karst_rng_u64(&r) % 6);
    feat[t] = (int)(karst_rng_u64(&r) % 3) - 1;
    id[t] = t;
  }
  const char *names[] = {"block_id", "block_type"};
  const int *arrays[] = {id, label};
  for (int v = 0; v < 5; v++) {
    if (nt > 100000 && v != 4) continue;
    karst_mesh_t m = {nv, nt, xyz, tri, v >= 1 ? label : NULL, v == 2 ? "tunnel_type" : NULL,
                      v >= 3 ? feat : NULL};
    char name[64];
    snprintf(name, sizeof name, "mesh_%d_%d", nt, v);
    if (v == 4) {
      m.tri_label = NULL;
      COMPARE_WRITERS(name, mesh_arrays, &m, 2, names, arrays);
    } else {
      COMPARE_WRITERS(name, mesh, &m);
    }
  }
  /* polygons of 3 to 6 points, as the geology's surfaces */
  karst_int_t *off = malloc(((size_t)nt + 1) * sizeof *off), *conn = malloc(6 * (size_t)nt * sizeof *conn);
  assert_true(off && conn);
  off[0] = 0;
  for (int c = 0; c < nt; c++) {
    int k = 3 + (int)(karst_rng_u64(&r) % 4);
    for (int j = 0; j < k; j++)
      conn[off[c] + j] = (karst_int_t)(karst_rng_u64(&r) % nv);
    off[c + 1] = off[c] + k;
  }
  char *fv[] = {"wall", "horizon 1"};
  karst_strings_t strs[2] = {{"feature_names", 2, fv}, {"stratum_names", 0, NULL}};
  const char *cnames[] = {"feature", "feature_id"};
  const int *carr[] = {feat, id};
  karst_polydata_t pd = {nv, xyz, nt, off, conn, 2, cnames, carr, 2, strs, "geology"};
  char name[64];
  snprintf(name, sizeof name, "poly_%d", nt);
  COMPARE_WRITERS(name, polydata, &pd);
  free(xyz), free(tri), free(label), free(feat), free(id), free(off), free(conn);
}

static void test_meshes(void **state) {
  (void)state;
  compare_meshes(3000, 5000);
  compare_meshes(200000, 400000); /* a 20 MB file: about 20 flushes of the 1 MiB buffer */
}

/* Bad input: the same code and message from both writers, and no file. */
static void test_errors(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 11, 0);
  karst_network_t net;
  make_network(&net, &r, 10, 12, NULL, 0);
  net.xyz[3 * 4 + 1] = NAN;
  compare_network("bad_coordinate", &net);
  net.xyz[3 * 4 + 1] = 0;
  net.edges[5] = 10;
  compare_network("bad_edge", &net);
  net.edges[5] = 0;
  karst_attr_t *k = karst_network_attr_find(&net, KARST_ATTR_NODE, "kind");
  k->data[3] = 0.5;
  compare_network("bad_integer", &net);
  k->data[3] = 3e9;
  compare_network("big_integer", &net);
  k->data[3] = 1;
  double *d;
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_NODE, "label", 1, 0, &d), KARST_SUCCESS);
  compare_network("label_clash", &net);
  karst_network_destroy(&net);
  compare_network("null", NULL);
  karst_ctx_t c;
  karst_ctx_init(&c);
  char path[256];
  snprintf(path, sizeof path, "%s/no/such/dir/n.vtp", dir);
  make_network(&net, &r, 3, 2, NULL, 0);
  assert_int_equal(karst_vtk_write_network(&c, path, &net), KARST_EIO);
  assert_non_null(strstr(c.errmsg, path));
  assert_int_equal(karst_vtk_write_network(&c, "", &net), KARST_EINVAL);
  karst_network_destroy(&net);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_shortest), cmocka_unit_test(test_networks),
      cmocka_unit_test(test_samples),  cmocka_unit_test(test_meshes),
      cmocka_unit_test(test_errors),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
