/* ParaView scripts beside karst's outputs (include/karst/view.h). */
#include "karst/view.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "karst/arrays.h"
#include "karst/io.h"
#include "karst/palette.h"

/* The fixed part of every script, src/view/paraview_script.py, embedded by CMake as bytes. */
#include "view/paraview_script.h"

static const char *const role_names[KARST_VIEW_ROLE_COUNT] = {"network", "samples",    "mesh",
                                                              "field",   "collection", "geology"};
/* What each role colours by at start (NULL: its first categorical array, else a plain
 * surface). */
/* A mesh is coloured by tunnel_type when it has one (a conduit mesh also carries the
 * categorical "feature", wall or speleothem), else by its first categorical array. */
static const char *const role_default[KARST_VIEW_ROLE_COUNT] = {
    "tunnel_type", "source", "tunnel_type", "sdf", "tunnel_type", NULL};

/** Colours of unlisted categories written into a script (codes 0 .. KARST_VIEW_CYCLE - 1;
 *  beyond, the script cycles through them: karst_palette_cycle does the same). */
#define KARST_VIEW_CYCLE 7

/* Page background and text: the report's white page and black text. */
static const double background[3] = {1, 1, 1}, foreground[3] = {0, 0, 0};

/**
 * "DIR/STEM" KARST_VIEW_SCRIPT_SUFFIX for output @p path "DIR/STEM.EXT" (the extension is
 * the last dot of the last component, if any and not its first character).
 * Time complexity: O(length of @p path).
 */
char *karst_view_script_path(const char *path) {
  const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  size_t stem = dot && dot > base ? (size_t)(dot - path) : strlen(path);
  size_t n = stem + strlen(KARST_VIEW_SCRIPT_SUFFIX) + 1;
  char *out = malloc(n);
  if (out) snprintf(out, n, "%.*s%s", (int)stem, path, KARST_VIEW_SCRIPT_SUFFIX);
  return out;
}

/* The bytes of @p s inside a Python string literal: quotes and backslashes escaped, control
 * and non-ASCII bytes as \xNN. */
static void py_escaped(FILE *fp, const char *s) {
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '\\' || *p == '\'')
      fprintf(fp, "\\%c", *p);
    else if (*p < 0x20 || *p >= 0x7f)
      fprintf(fp, "\\x%02x", *p);
    else
      fputc(*p, fp);
  }
}

/* A Python str literal of ASCII text (names and sentences of karst's own tables). */
static void py_str(FILE *fp, const char *s) {
  fputc('\'', fp);
  py_escaped(fp, s);
  fputc('\'', fp);
}

/* A file name as Python sees it from the bytes karst wrote: os.fsdecode of a bytes literal,
 * so that any byte (not only UTF-8) names the same file. */
static void py_path(FILE *fp, const char *s) {
  fputs("os.fsdecode(b'", fp);
  py_escaped(fp, s);
  fputs("')", fp);
}

static void py_rgb(FILE *fp, const double rgb[3]) {
  fprintf(fp, "(%.6g, %.6g, %.6g)", rgb[0], rgb[1], rgb[2]);
}

static void py_hex(FILE *fp, const char *hex) {
  double rgb[3] = {0.5, 0.5, 0.5};
  karst_palette_hex_rgb(hex, rgb);
  py_rgb(fp, rgb);
}

static const char *colouring_name(karst_palette_kind_t k) {
  return k == KARST_PALETTE_CATEGORICAL ? "categorical"
         : k == KARST_PALETTE_DIVERGING ? "diverging"
                                        : "sequential";
}

/* One entry of the dictionary with its palette, as a Python dict item. */
static void py_array(FILE *fp, const karst_array_info_t *a) {
  fputs("    ", fp);
  py_str(fp, a->name);
  fputs(": {'title': ", fp);
  py_str(fp, a->title);
  fputs(", 'unit': ", fp);
  py_str(fp, a->unit);
  fputs(", 'colouring': ", fp);
  py_str(fp, colouring_name(a->colouring));
  if (a->names) {
    fputs(", 'names': ", fp);
    py_str(fp, a->names);
  }
  const karst_palette_t *p = karst_palette_find_role(a->name, a->role);
  if (p && p->kind == KARST_PALETTE_CATEGORICAL) {
    fputs(",\n        'categories': [", fp);
    for (int k = 0; k < p->n; k++) {
      fprintf(fp, "\n            (%d, ", p->categories[k].code);
      py_str(fp, p->categories[k].name);
      fputs(", ", fp);
      py_hex(fp, p->categories[k].hex);
      fprintf(fp, "),  # %s", p->categories[k].hex);
    }
    fputs("\n        ]", fp);
  }
  fputs("},\n", fp);
}

/* The data part: version, files, colours, the dictionary of arrays with their palettes, and
 * the ramps. */
static void write_data(FILE *fp, const char *script_name, char *const *rel,
                       const karst_view_item_t *items, int n) {
  fprintf(fp,
          "# ParaView script written by karst %s: it shows the files listed in FILES (paths\n"
          "# relative to this script) with karst's colours, category names and units.\n"
          "#   paraview --script=%s      (run in this directory; or: karst view DIR)\n"
          "#   pvbatch %s --screenshot view.png\n"
          "# Units and sign conventions: docs/arrays.md, and the field data \"array_units\" of\n"
          "# each file.\n",
          karst_version(), script_name, script_name);
  fputs("import os\n\nKARST_VERSION = ", fp);
  py_str(fp, karst_version());
  fputs("\nFILES = [\n", fp);
  for (int i = 0; i < n; i++) {
    const char *by = items[i].colour_by ? items[i].colour_by : role_default[items[i].role];
    fputs("    {'file': ", fp);
    py_path(fp, rel[i]);
    fputs(", 'role': ", fp);
    py_str(fp, role_names[items[i].role]);
    fputs(", 'colour_by': ", fp);
    if (by)
      py_str(fp, by);
    else
      fputs("None", fp);
    fputs("},\n", fp);
  }
  fputs("]\nBACKGROUND = ", fp);
  py_rgb(fp, background);
  fputs("\nFOREGROUND = ", fp);
  py_rgb(fp, foreground);
  fputs("\nNEUTRAL = ", fp);
  py_hex(fp, karst_palette_role(KARST_PALETTE_ROLE_NONE));
  fputs("\nWALL = ", fp);
  py_hex(fp, karst_palette_role(KARST_PALETTE_ROLE_SURFACE));
  fputs("\n# Every array karst writes (include/karst/arrays.h) with its palette "
        "(include/karst/palette.h).\nARRAYS = {\n",
        fp);
  int na = 0;
  const karst_array_info_t *a = karst_arrays_list(&na);
  for (int i = 0; i < na; i++)
    if (!a[i].role) py_array(fp, &a[i]);
  fputs("}\n# Arrays whose name means something else in another kind of file (as \"feature\").\n"
        "ROLE_ARRAYS = {\n",
        fp);
  for (int r = 0; r < KARST_VIEW_ROLE_COUNT; r++) {
    int any = 0;
    for (int i = 0; i < na; i++) {
      if (!a[i].role || strcmp(a[i].role, role_names[r]) != 0) continue;
      if (!any) fprintf(fp, "  '%s': {\n", role_names[r]);
      any = 1;
      py_array(fp, &a[i]);
    }
    if (any) fputs("  },\n", fp);
  }
  fputs("}\n# Colours of categories a palette entry does not list (springs, strata ...), by code.\n"
        "CYCLE = [",
        fp);
  for (int k = 0; k < KARST_VIEW_CYCLE; k++) {
    fputs(k ? ", " : "", fp);
    py_hex(fp, karst_palette_cycle(k));
  }
  fputs("]\nRAMPS = {\n", fp);
  const karst_palette_kind_t kinds[2] = {KARST_PALETTE_SEQUENTIAL, KARST_PALETTE_DIVERGING};
  for (int r = 0; r < 2; r++) {
    const karst_palette_ramp_t *ramp = karst_palette_ramp(kinds[r]);
    fprintf(fp, "    '%s': [  # %s\n        ", colouring_name(kinds[r]), ramp->name);
    for (int k = 0; k < ramp->n; k++)
      fprintf(fp, "(%.6g, %.6g, %.6g, %.6g),%s", ramp->points[k][0], ramp->points[k][1],
              ramp->points[k][2], ramp->points[k][3], k + 1 < ramp->n ? "\n        " : "");
    fputs("],\n", fp);
  }
  fputs("}\n\n", fp);
}

/**
 * Write the ParaView script for @p n files (see view.h): a data part (karst's version, the
 * files relative to the directory of @p final_path, the palette and the dictionary of
 * arrays), then the fixed part src/view/paraview_script.py. Written to @p script atomically.
 * @return KARST_SUCCESS; KARST_EINVAL (no file, or an unknown role); KARST_EIO (a file's
 *         directory cannot be resolved, or the script cannot be written); KARST_ENOMEM.
 * Time complexity: O(n + number of arrays and categories).
 */
karst_error_t karst_view_write_script(karst_ctx_t *ctx, const char *script, const char *final_path,
                                      const karst_view_item_t *items, int n) {
  if (!script || !final_path || (n > 0 && !items) || n < 1)
    return karst_set_error(ctx, KARST_EINVAL, "ParaView script: no file to show");
  karst_error_t err = KARST_SUCCESS;
  char **rel = calloc((size_t)n, sizeof *rel);
  char *dir = strdup(final_path);
  if (!rel || !dir) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  char *slash = strrchr(dir, '/');
  if (slash)
    slash[slash == dir ? 1 : 0] = '\0';
  else
    strcpy(dir, ".");
  for (int i = 0; i < n; i++) {
    if ((int)items[i].role < 0 || items[i].role >= KARST_VIEW_ROLE_COUNT || !items[i].path) {
      err = karst_set_error(ctx, KARST_EINVAL, "%s: file %d has no path or an unknown role (%d)",
                            final_path, i, (int)items[i].role);
      goto cleanup;
    }
    if ((err = karst_path_relative(ctx, dir, items[i].path, &rel[i]))) goto cleanup;
  }
  const char *name = strrchr(final_path, '/');
  name = name ? name + 1 : final_path;
  karst_atomic_file_t f;
  if ((err = karst_atomic_open(ctx, &f, script, "w"))) goto cleanup;
  write_data(f.fp, name, rel, items, n);
  fwrite(karst_i_paraview_script, 1, sizeof karst_i_paraview_script - 1, f.fp);
  err = karst_atomic_commit(ctx, &f);
cleanup:
  if (rel)
    for (int i = 0; i < n; i++)
      free(rel[i]);
  free(rel);
  free(dir);
  return err;
}

static int has_suffix(const char *s, const char *suffix) {
  size_t a = strlen(s), b = strlen(suffix);
  return a > b && strcmp(s + a - b, suffix) == 0;
}

static int cmp_str(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The one script in directory @p dir (see karst_view_find_script). */
static karst_error_t script_in_dir(karst_ctx_t *ctx, const char *dir, char **out) {
  DIR *d = opendir(dir);
  if (!d) return karst_set_error(ctx, KARST_EIO, "%s: cannot list: %s", dir, strerror(errno));
  char **names = NULL;
  int n = 0, cap = 0;
  karst_error_t err = KARST_SUCCESS;
  for (struct dirent *e; (e = readdir(d));) {
    if (e->d_name[0] == '.' || !has_suffix(e->d_name, KARST_VIEW_SCRIPT_SUFFIX)) continue;
    if (n == cap) {
      int c = cap ? 2 * cap : 8;
      char **t = realloc(names, (size_t)c * sizeof *t);
      if (!t) {
        err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
        goto cleanup;
      }
      names = t, cap = c;
    }
    if (!(names[n] = strdup(e->d_name))) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    n++;
  }
  if (n == 0) {
    err = karst_set_error(ctx, KARST_ENOTFOUND,
                          "%s: no ParaView script (*%s) here; karst generate, ensemble and mesh "
                          "write one beside their outputs",
                          dir, KARST_VIEW_SCRIPT_SUFFIX);
    goto cleanup;
  }
  qsort(names, (size_t)n, sizeof *names, cmp_str);
  if (n > 1) {
    char list[1024] = "";
    for (int i = 0; i < n; i++)
      snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", names[i]);
    err = karst_set_error(ctx, KARST_EINVAL, "%s holds %d ParaView scripts (%s); name one of them",
                          dir, n, list);
    goto cleanup;
  }
  size_t len = strlen(dir) + strlen(names[0]) + 2;
  if (!(*out = malloc(len))) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  snprintf(*out, len, "%s/%s", dir, names[0]);
cleanup:
  for (int i = 0; i < n; i++)
    free(names[i]);
  free(names);
  closedir(d);
  return err;
}

/**
 * The script to open for @p path (see view.h): @p path itself when it names a script, the
 * only script of a directory, or the script beside a data file.
 * Time complexity: O(entries of the directory).
 */
karst_error_t karst_view_find_script(karst_ctx_t *ctx, const char *path, char **out) {
  *out = NULL;
  struct stat st;
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no file or directory given");
  if (stat(path, &st) != 0)
    return karst_set_error(ctx, KARST_ENOTFOUND, "%s: %s", path, strerror(errno));
  if (S_ISDIR(st.st_mode)) return script_in_dir(ctx, path, out);
  if (has_suffix(path, KARST_VIEW_SCRIPT_SUFFIX)) {
    *out = strdup(path);
    return *out ? KARST_SUCCESS : karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  }
  char *s = karst_view_script_path(path);
  if (!s) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  if (stat(s, &st) != 0) {
    karst_error_t err = karst_set_error(ctx, KARST_ENOTFOUND,
                                        "%s: no ParaView script beside it (expected %s)", path, s);
    free(s);
    return err;
  }
  *out = s;
  return KARST_SUCCESS;
}
