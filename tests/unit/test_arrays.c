/*
 * The dictionary of arrays (include/karst/arrays.h): every entry is complete, categorical
 * entries have their palette and names array, colour-bar titles give the unit, docs/arrays.md
 * has exactly one row per entry saying the same (name, where, unit, meaning, categories), and
 * the VTK writer states each array's unit in the file (UNITS_LABEL and "array_units", read
 * back with python3-vtk9, independent of karst's reader).
 */
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

/* The row docs/arrays.md must have for entry @p a. */
static void expected_row(const karst_array_info_t *a, char *out, size_t size) {
  int n = snprintf(out, size, "| `%s` | %s | %s | %s | ", a->name, a->where, a->unit, a->meaning);
  const karst_palette_t *p = karst_palette_find(a->name);
  if (a->colouring == KARST_PALETTE_CATEGORICAL && p) {
    n += snprintf(out + n, size - (size_t)n, "categories (`%s`):", a->names);
    for (int k = 0; k < p->n; k++)
      n += snprintf(out + n, size - (size_t)n, "%s %d %s %s", k ? "," : "", p->categories[k].code,
                    p->categories[k].name, p->categories[k].hex);
  } else if (a->colouring == KARST_PALETTE_CATEGORICAL) {
    n += snprintf(out + n, size - (size_t)n, "text");
  } else {
    n += snprintf(out + n, size - (size_t)n, "%s ramp (%s)",
                  a->colouring == KARST_PALETTE_DIVERGING ? "diverging" : "sequential",
                  karst_palette_ramp(a->colouring)->name);
  }
  snprintf(out + n, size - (size_t)n, " |");
}

static char *read_all(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  size_t got = fread(s, 1, (size_t)n, fp);
  s[got] = '\0';
  fclose(fp);
  return s;
}

static void test_entries(void **state) {
  (void)state;
  int n = 0;
  const karst_array_info_t *a = karst_arrays_list(&n);
  assert_true(n >= 18);
  for (int i = 0; i < n; i++) {
    assert_ptr_equal(karst_arrays_find(a[i].name), &a[i]);
    assert_true(a[i].where && *a[i].where && a[i].unit && *a[i].unit && a[i].title && *a[i].title &&
                a[i].meaning && *a[i].meaning);
    for (int j = 0; j < i; j++)
      assert_string_not_equal(a[i].name, a[j].name);
    if (strcmp(a[i].unit, KARST_ARRAYS_UNIT_TEXT) == 0) continue;
    if (a[i].colouring == KARST_PALETTE_CATEGORICAL) {
      /* categories from the palette, named in the file by a "*_names" array */
      const karst_palette_t *p = karst_palette_find(a[i].name);
      if (!p) fail_msg("categorical array %s has no palette entry", a[i].name);
      assert_int_equal(p->kind, KARST_PALETTE_CATEGORICAL);
      assert_non_null(a[i].names);
      assert_string_equal(a[i].unit, KARST_ARRAYS_UNIT_CATEGORY);
    } else {
      /* a colour-bar title names the unit in parentheses ("1" as "dimensionless") */
      const char *u = strcmp(a[i].unit, "1") == 0 ? "dimensionless" : a[i].unit;
      const char *open = strchr(a[i].title, '(');
      if (!open || !strstr(open, u))
        fail_msg("%s: title '%s' lacks its unit %s", a[i].name, a[i].title, u);
      assert_null(a[i].names);
    }
  }
  assert_null(karst_arrays_find("no such array"));
  assert_null(karst_arrays_find(NULL));
  /* Every categorical palette entry is an array of the dictionary. */
  int np = 0;
  const karst_palette_t *p = karst_palette_list(&np);
  for (int k = 0; k < np; k++)
    assert_non_null(karst_arrays_find(p[k].array));
}

/* docs/arrays.md: one row per entry, identical to what the dictionary says, and no other. */
static void test_docs_agree(void **state) {
  (void)state;
  char *md = read_all(KARST_SOURCE_DIR "/docs/arrays.md");
  assert_non_null(md);
  int n = 0, bad = 0;
  const karst_array_info_t *a = karst_arrays_list(&n);
  char row[2048];
  for (int i = 0; i < n; i++) {
    expected_row(&a[i], row, sizeof row);
    if (!strstr(md, row)) {
      print_error("docs/arrays.md lacks the row\n%s\n", row);
      bad = 1;
    }
  }
  int rows = 0;
  for (const char *p = strstr(md, "\n| `"); p; p = strstr(p + 1, "\n| `"))
    rows++;
  if (rows != n) {
    print_error("docs/arrays.md has %d array rows, the dictionary %d entries\n", rows, n);
    bad = 1;
  }
  free(md);
  if (bad) fail();
}

/* The writer states the units in the file; read back by VTK's own reader (python3-vtk9). */
static void test_units_in_files(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_test_arrays_XXXXXX";
  assert_non_null(mkdtemp(dir));
  karst_network_t net;
  karst_network_init(&net);
  double *d;
  assert_int_equal(karst_network_add_node(&net, 0, 0, 0, NULL), KARST_SUCCESS);
  assert_int_equal(karst_network_add_node(&net, 10, 0, -5, NULL), KARST_SUCCESS);
  assert_int_equal(karst_network_add_edge(&net, 0, 1, NULL), KARST_SUCCESS);
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &d), 0);
  d[0] = 1.5;
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_EDGE, "vadose", 1, 1, &d), 0);
  d[0] = 1;
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_NODE, "water_table_distance", 1, 0, &d),
                   0);
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_EDGE, "mystery", 1, 0, &d), 0);
  char path[256];
  snprintf(path, sizeof path, "%s/n.vtp", dir);
  assert_int_equal(karst_vtk_write_network(&ctx, path, &net), KARST_SUCCESS);
  karst_network_destroy(&net);
  char cmd[2048];
  snprintf(
      cmd, sizeof cmd,
      "/usr/bin/python3 -c \"import vtk; r=vtk.vtkXMLPolyDataReader(); r.SetFileName('%s'); "
      "r.Update(); o=r.GetOutput(); fd=o.GetFieldData(); t=fd.GetAbstractArray('array_units'); "
      "rows={t.GetValue(3*i):(t.GetValue(3*i+1),t.GetValue(3*i+2)) for i in "
      "range(t.GetNumberOfTuples())}; "
      "assert t.GetNumberOfComponents()==3 and t.GetComponentName(1)=='unit', 'table'; "
      "assert rows['radius'][0]=='m' and rows['water_table_distance'][0]=='m', rows; "
      "assert 'positive above' in rows['water_table_distance'][1], rows; "
      "assert rows['vadose'][0]=='category' and rows['mystery'][0]=='unknown', rows; "
      "u=vtk.vtkDataArray.UNITS_LABEL(); "
      "assert o.GetCellData().GetArray('radius').GetInformation().Get(u)=='m'; "
      "assert o.GetPointData().GetArray('water_table_distance').GetInformation().Get(u)=='m'; "
      "n=fd.GetAbstractArray('vadose_names'); "
      "assert [n.GetValue(i) for i in range(2)]==['below the water table','above the water "
      "table']\"",
      path);
  int rc = system(cmd);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  assert_int_equal(system(cmd), 0);
  assert_int_equal(rc, 0);
}

int main(int argc, char **argv) {
  if (argc > 1 && strcmp(argv[1], "--rows") == 0) { /* print the rows docs/arrays.md needs */
    int n = 0;
    const karst_array_info_t *a = karst_arrays_list(&n);
    char row[2048];
    for (int i = 0; i < n; i++) {
      expected_row(&a[i], row, sizeof row);
      puts(row);
    }
    return 0;
  }
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_entries),
      cmocka_unit_test(test_docs_agree),
      cmocka_unit_test(test_units_in_files),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
