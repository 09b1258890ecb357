/*
 * ParaView scripts (include/karst/view.h): names beside outputs, the script's data part read
 * back by Python (its files relative to the script, even for hostile names; its palette and
 * ramps equal to include/karst/palette.h; its titles those of include/karst/arrays.h), the
 * whole script compiled by Python, atomic writes and errors, and finding a script again.
 * ParaView itself runs the scripts in tests/cli/test_paraview.sh.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"

static char root[64];

static int setup(void **state) {
  (void)state;
  snprintf(root, sizeof root, "/tmp/karst_test_view_XXXXXX");
  if (!mkdtemp(root)) return -1;
  char p[256];
  snprintf(p, sizeof p, "%s/out", root);
  if (mkdir(p, 0777) != 0) return -1;
  snprintf(p, sizeof p, "%s/other", root);
  return mkdir(p, 0777);
}

static int teardown(void **state) {
  (void)state;
  char cmd[256];
  snprintf(cmd, sizeof cmd, "chmod -R u+w '%s'; rm -rf '%s'", root, root);
  return system(cmd);
}

static void expect_script_path(const char *in, const char *want) {
  char *s = karst_view_script_path(in);
  assert_non_null(s);
  assert_string_equal(s, want);
  free(s);
}

static void test_script_path(void **state) {
  (void)state;
  expect_script_path("out/network.vtp", "out/network.paraview.py");
  expect_script_path("cave", "cave.paraview.py");
  expect_script_path("a.b/cave", "a.b/cave.paraview.py"); /* a dot of a directory is no extension */
  expect_script_path(".hidden", ".hidden.paraview.py");
  expect_script_path("/x/ensemble.pvd", "/x/ensemble.paraview.py");
  expect_script_path("m.tar.vtp", "m.tar.paraview.py");
}

/* Run Python on the data part of @p script (up to the fixed part's first line) and then on the
 * checks in @p code (variables FILES, ARRAYS, RAMPS ... in scope); 0 when they pass. */
static int python_check(const char *script, const char *code) {
  char path[256];
  snprintf(path, sizeof path, "%s/check.py", root);
  FILE *fp = fopen(path, "w");
  if (!fp) return -1;
  fprintf(fp,
          "import os, sys\n"
          "text = open(sys.argv[1], encoding='utf-8').read()\n"
          "compile(text, sys.argv[1], 'exec')  # the whole script is valid Python\n"
          "head = text.split('# ----------', 1)[0]\n"
          "assert 'def main(argv)' in text and 'paraview.simple' in text\n"
          "env = {}\n"
          "exec(compile(head, sys.argv[1], 'exec'), env)\n"
          "globals().update(env)\n"
          "%s\n",
          code);
  fclose(fp);
  char cmd[1024];
  snprintf(cmd, sizeof cmd, "/usr/bin/python3 '%s' '%s'", path, script);
  return system(cmd);
}

static void test_write_and_read_back(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char script[256], vtp[256], vti[256], odd[256];
  snprintf(script, sizeof script, "%s/out/cave.paraview.py", root);
  snprintf(vtp, sizeof vtp, "%s/out/cave.vtp", root);
  snprintf(vti, sizeof vti, "%s/other/../other/cave's \\ \xe9t\xe9.vti", root); /* Latin-1 bytes */
  snprintf(odd, sizeof odd, "%s/out/./x.pvd", root);
  karst_view_item_t items[3] = {{vtp, KARST_VIEW_MESH, NULL},
                                {vti, KARST_VIEW_FIELD, NULL},
                                {odd, KARST_VIEW_COLLECTION, "radius"}};
  assert_int_equal(karst_view_write_script(&ctx, script, script, items, 3), KARST_SUCCESS);
  /* The files relative to the script's directory, byte for byte (os.fsencode). */
  assert_int_equal(
      python_check(script, "assert [os.fsencode(f['file']) for f in FILES] == [b'cave.vtp', "
                           "b\"../other/cave's \\\\ \\xe9t\\xe9.vti\", b'x.pvd'], FILES\n"
                           "assert [f['role'] for f in FILES] == ['mesh', 'field', 'collection']\n"
                           "assert [f['colour_by'] for f in FILES] == ['tunnel_type', 'sdf', 'radius']\n"
                           "assert BACKGROUND == (1, 1, 1) and FOREGROUND == (0, 0, 0)\n"),
      0);

  /* The palette and the dictionary, as include/karst/palette.h and arrays.h give them. */
  static char code[32768];
  int m = snprintf(code, sizeof code,
                   "def near(a, b): assert all(abs(x - y) < 5e-6 for x, y in "
                   "zip(a, b)), (a, b)\n");
  int na = 0;
  const karst_array_info_t *a = karst_arrays_list(&na);
  int plain = 0;
  for (int i = 0; i < na; i++)
    plain += !a[i].role;
  m += snprintf(code + m, sizeof code - (size_t)m,
                "assert len(ARRAYS) == %d and sum(map(len, ROLE_ARRAYS.values())) == %d\n", plain,
                na - plain);
  for (int i = 0; i < na; i++) {
    char spec[96];
    if (a[i].role)
      snprintf(spec, sizeof spec, "ROLE_ARRAYS['%s']['%s']", a[i].role, a[i].name);
    else
      snprintf(spec, sizeof spec, "ARRAYS['%s']", a[i].name);
    m += snprintf(code + m, sizeof code - (size_t)m,
                  "assert %s['title'] == '%s' and %s['unit'] == '%s'\n", spec, a[i].title, spec,
                  a[i].unit);
    const karst_palette_t *p = karst_palette_find_role(a[i].name, a[i].role);
    if (!p || p->kind != KARST_PALETTE_CATEGORICAL) continue;
    m += snprintf(code + m, sizeof code - (size_t)m, "c = %s['categories']\nassert len(c) == %d\n",
                  spec, p->n);
    for (int k = 0; k < p->n; k++) {
      double rgb[3];
      karst_palette_hex_rgb(p->categories[k].hex, rgb);
      m += snprintf(code + m, sizeof code - (size_t)m,
                    "assert c[%d][:2] == (%d, '%s'); near(c[%d][2], (%.9f, %.9f, %.9f))\n", k,
                    p->categories[k].code, p->categories[k].name, k, rgb[0], rgb[1], rgb[2]);
    }
  }
  const karst_palette_ramp_t *r = karst_palette_ramp(KARST_PALETTE_DIVERGING);
  m += snprintf(code + m, sizeof code - (size_t)m,
                "assert len(RAMPS['diverging']) == %d; near(RAMPS['diverging'][%d], "
                "(%.9f, %.9f, %.9f, %.9f))\n",
                r->n, r->n / 2, r->points[r->n / 2][0], r->points[r->n / 2][1],
                r->points[r->n / 2][2], r->points[r->n / 2][3]);
  for (int k = 0; k < 7; k++) {
    double rgb[3];
    karst_palette_hex_rgb(karst_palette_cycle(k), rgb);
    m += snprintf(code + m, sizeof code - (size_t)m, "near(CYCLE[%d], (%.9f, %.9f, %.9f))\n", k,
                  rgb[0], rgb[1], rgb[2]);
  }
  assert_true(m < (int)sizeof code);
  assert_int_equal(python_check(script, code), 0);
}

static int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

static void test_errors(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char script[256], vtp[256];
  snprintf(script, sizeof script, "%s/out/bad.paraview.py", root);
  snprintf(vtp, sizeof vtp, "%s/out/bad.vtp", root);
  karst_view_item_t item = {vtp, (karst_view_role_t)99, NULL};
  assert_int_equal(karst_view_write_script(&ctx, script, script, &item, 1), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "unknown role (99)"));
  assert_int_equal(karst_view_write_script(&ctx, script, script, &item, 0), KARST_EINVAL);
  item.role = KARST_VIEW_NETWORK;
  item.path = "/no/such/dir/n.vtp"; /* its directory cannot be resolved */
  assert_int_equal(karst_view_write_script(&ctx, script, script, &item, 1), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/no/such/dir/n.vtp"));
  assert_false(exists(script));
  /* A read-only directory (unless root, who may write anyway): no script, no temporary. */
  char ro[128], rs[256];
  snprintf(ro, sizeof ro, "%s/ro", root);
  assert_int_equal(mkdir(ro, 0555), 0);
  snprintf(rs, sizeof rs, "%s/n.paraview.py", ro);
  item.path = vtp;
  if (geteuid() != 0) {
    assert_int_equal(karst_view_write_script(&ctx, rs, rs, &item, 1), KARST_EIO);
    assert_false(exists(rs));
  }
}

static void touch(const char *dir, const char *name) {
  char p[512];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *fp = fopen(p, "w");
  assert_non_null(fp);
  fclose(fp);
}

static void test_find(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[256], p[300], *out = NULL;
  snprintf(dir, sizeof dir, "%s/find", root);
  assert_int_equal(mkdir(dir, 0777), 0);
  touch(dir, "network.vtp");
  touch(dir, ".network.paraview.py.tmp.1.2"); /* a temporary is no script */
  assert_int_equal(karst_view_find_script(&ctx, dir, &out), KARST_ENOTFOUND);
  assert_non_null(strstr(ctx.errmsg, "no ParaView script"));
  touch(dir, "network.paraview.py");
  assert_int_equal(karst_view_find_script(&ctx, dir, &out), KARST_SUCCESS);
  snprintf(p, sizeof p, "%s/network.paraview.py", dir);
  assert_string_equal(out, p);
  free(out);
  snprintf(p, sizeof p, "%s/network.vtp", dir); /* a data file: the script beside it */
  assert_int_equal(karst_view_find_script(&ctx, p, &out), KARST_SUCCESS);
  assert_non_null(strstr(out, "/find/network.paraview.py"));
  free(out);
  touch(dir, "cave.vtp");
  snprintf(p, sizeof p, "%s/cave.vtp", dir);
  assert_int_equal(karst_view_find_script(&ctx, p, &out), KARST_ENOTFOUND);
  assert_non_null(strstr(ctx.errmsg, "cave.paraview.py"));
  touch(dir, "cave.paraview.py");
  assert_int_equal(karst_view_find_script(&ctx, dir, &out), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "2 ParaView scripts (cave.paraview.py, network.paraview.py)"));
  snprintf(p, sizeof p, "%s/cave.paraview.py", dir); /* a script itself */
  assert_int_equal(karst_view_find_script(&ctx, p, &out), KARST_SUCCESS);
  assert_string_equal(out, p);
  free(out);
  assert_int_equal(karst_view_find_script(&ctx, "/no/such/thing", &out), KARST_ENOTFOUND);
  assert_int_equal(karst_view_find_script(&ctx, "", &out), KARST_EINVAL);
  assert_null(out);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_script_path),
      cmocka_unit_test(test_write_and_read_back),
      cmocka_unit_test(test_errors),
      cmocka_unit_test(test_find),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
