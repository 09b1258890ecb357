/* The PolyData files of include/karst/vtk.h (networks, samples, meshes, polygons), written by
 * vtp_write.c without VTK: the same files, byte for byte, as VTK 9.1's writer made from the same
 * data (tests/unit/test_vtp_write.c), the same checks and the same messages. Only the .vti
 * images, the .pvd collections and the reading of .vtp files still go through VTK
 * (src/io/vtk_shim.cpp, a plugin: io/vtk_api_internal.h). */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/vtp_write_internal.h"
#include "karst/arrays.h"
#include "karst/palette.h"
#include "karst/version.h"
#include "karst/vtk.h"

/* ------------------------------------------------------------------------ */
/* What a file holds besides its geometry                                    */
/* ------------------------------------------------------------------------ */

/* A file being assembled: its arrays and the memory they borrow. */
typedef struct {
  karst_i_vtp_array_t *field, *point, *cell;
  int n_field, n_point, n_cell, cap_field, cap_point, cap_cell;
  void **owned; /* freed with the file */
  int n_owned, cap_owned;
  int failed;
} file_t;

static void *own(file_t *f, void *p) {
  if (!p) {
    f->failed = 1;
    return NULL;
  }
  if (f->n_owned == f->cap_owned) {
    int cap = f->cap_owned ? 2 * f->cap_owned : 16;
    void **o = realloc(f->owned, (size_t)cap * sizeof *o);
    if (!o) {
      free(p);
      f->failed = 1;
      return NULL;
    }
    f->owned = o, f->cap_owned = cap;
  }
  f->owned[f->n_owned++] = p;
  return p;
}

static void file_free(file_t *f) {
  for (int i = 0; i < f->n_owned; i++)
    free(f->owned[i]);
  free(f->owned), free(f->field), free(f->point), free(f->cell);
  memset(f, 0, sizeof *f);
}

/* Append @p a to a list; an array of the same name is replaced where it stands, as
 * vtkFieldData::AddArray does. */
static void add(file_t *f, karst_i_vtp_array_t **list, int *n, int *cap, karst_i_vtp_array_t a) {
  for (int i = 0; i < *n; i++)
    if (strcmp((*list)[i].name, a.name) == 0) {
      (*list)[i] = a;
      return;
    }
  if (*n == *cap) {
    int c = *cap ? 2 * *cap : 16;
    karst_i_vtp_array_t *l = realloc(*list, (size_t)c * sizeof *l);
    if (!l) {
      f->failed = 1;
      return;
    }
    *list = l, *cap = c;
  }
  (*list)[(*n)++] = a;
}

static void add_field(file_t *f, karst_i_vtp_array_t a) {
  add(f, &f->field, &f->n_field, &f->cap_field, a);
}
static void add_point(file_t *f, karst_i_vtp_array_t a) {
  add(f, &f->point, &f->n_point, &f->cap_point, a);
}
static void add_cell(file_t *f, karst_i_vtp_array_t a) {
  add(f, &f->cell, &f->n_cell, &f->cap_cell, a);
}

static karst_i_vtp_array_t strings(const char *name, karst_int_t n, const char *const *values) {
  karst_i_vtp_array_t a = {name, KARST_I_VTP_STRING, 1, NULL, n, values, NULL};
  return a;
}

static karst_i_vtp_array_t int32s(const char *name, karst_int_t n, const int32_t *values) {
  karst_i_vtp_array_t a = {name, KARST_I_VTP_INT32, 1, NULL, n, values, NULL};
  return a;
}

/* The names of codes 0 .. n - 1 (owned by @p f), from the function that names one code. */
static const char *const *code_names(file_t *f, int n, const char *(*name)(int)) {
  const char **v = own(f, calloc((size_t)n + 1, sizeof *v));
  if (v)
    for (int i = 0; i < n; i++)
      v[i] = name(i);
  return v;
}

static const char *tunnel_type_name(int i) { return karst_tunnel_type_name((karst_tunnel_type_t)i); }
static const char *node_kind_name(int i) { return karst_node_kind_name((karst_node_kind_t)i); }
static const char *sample_source_name(int i) {
  return karst_sample_source_name((karst_sample_source_t)i);
}

/* Which tunnel type and node kind each code names (include/karst/vtk.h). */
static void add_lookup_tables(file_t *f) {
  add_field(f, strings("tunnel_type_names", KARST_TUNNEL_TYPE_COUNT,
                       code_names(f, KARST_TUNNEL_TYPE_COUNT, tunnel_type_name)));
  add_field(f, strings("node_kind_names", KARST_NODE_KIND_COUNT,
                       code_names(f, KARST_NODE_KIND_COUNT, node_kind_name)));
}

/* "versions": one "name version" string per component (karst_versions). */
static void add_versions(file_t *f) {
  karst_component_t c[KARST_COMPONENTS_MAX];
  const int n = karst_versions(c);
  char **v = own(f, calloc((size_t)n + 1, sizeof *v));
  if (!v) return;
  for (int i = 0; i < n; i++) {
    size_t len = strlen(c[i].name) + strlen(c[i].version) + 2;
    v[i] = own(f, malloc(len));
    if (!v[i]) return;
    snprintf(v[i], len, "%s %s", c[i].name, c[i].version);
  }
  add_field(f, strings("versions", n, (const char *const *)v));
}

static int has_field(const file_t *f, const char *name) {
  for (int i = 0; i < f->n_field; i++)
    if (strcmp(f->field[i].name, name) == 0) return 1;
  return 0;
}

/*
 * What every point and cell array means (include/karst/arrays.h): its unit as the information
 * key UNITS_LABEL of a numeric array, a row (array, unit, meaning) of the field-data table
 * "array_units" for every array, point arrays first, and for a categorical array the field-data
 * array naming its categories unless the file has it already. An array karst does not describe
 * gets the unit "unknown".
 */
static void describe_arrays(file_t *f, const char *role) {
  const int n = f->n_point + f->n_cell;
  const char **table = own(f, calloc(3 * (size_t)n + 1, sizeof *table));
  if (!table) return;
  for (int i = 0; i < n; i++) {
    karst_i_vtp_array_t *a = i < f->n_point ? &f->point[i] : &f->cell[i - f->n_point];
    const karst_array_info_t *info = karst_arrays_find_role(a->name, role);
    const char *unit = info ? info->unit : "unknown";
    table[3 * i] = a->name;
    table[3 * i + 1] = unit;
    table[3 * i + 2] = info ? info->meaning : "not described by karst (docs/arrays.md)";
    if (a->type != KARST_I_VTP_STRING) a->units = unit;
    const karst_palette_t *pal =
        info && info->names ? karst_palette_find_role(info->name, role) : NULL;
    if (!pal || has_field(f, info->names)) continue;
    int codes = 0; /* codes 0 .. codes - 1 */
    for (int k = 0; k < pal->n; k++)
      if (pal->categories[k].code >= codes) codes = pal->categories[k].code + 1;
    if (codes == 0) continue; /* only the file knows the names (springs ...) */
    const char **names = own(f, calloc((size_t)codes, sizeof *names));
    if (!names) return;
    for (int k = 0; k < pal->n; k++)
      if (pal->categories[k].code >= 0) names[pal->categories[k].code] = pal->categories[k].name;
    add_field(f, strings(info->names, codes, names));
  }
  static const char *const columns[3] = {"array", "unit", "meaning"};
  karst_i_vtp_array_t t = {"array_units", KARST_I_VTP_STRING, 3, columns, n, table, NULL};
  add_field(f, t);
}

/* ------------------------------------------------------------------------ */
/* Geometry                                                                  */
/* ------------------------------------------------------------------------ */

static karst_error_t check_path(karst_ctx_t *ctx, const char *path) {
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no output file name given");
  return KARST_SUCCESS;
}

/* Points, checked finite (stored as doubles: coordinates round-trip exactly). */
static karst_error_t check_points(karst_ctx_t *ctx, const char *path, const char *what,
                                  karst_int_t n, const double *xyz) {
  if (n > 0 && !xyz)
    return karst_set_error(ctx, KARST_EINVAL, "%s: %" PRId64 " %s but no coordinates", path,
                           (int64_t)n, what);
  for (karst_int_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: %s %" PRId64 " has a non-finite coordinate (%g, %g, %g)", path,
                             what, (int64_t)i, p[0], p[1], p[2]);
  }
  return KARST_SUCCESS;
}

/*
 * Fixed-size cells (vertices, lines or triangles) from an index list, every index checked
 * against the number of points; a NULL @p idx with size 1 means one vertex cell per point.
 * *conn and *ends are owned by @p f.
 */
static karst_error_t make_cells(karst_ctx_t *ctx, file_t *f, const char *path, const char *what,
                                int size, karst_int_t n_cells, const karst_int_t *idx,
                                karst_int_t n_points, const int64_t **conn, const int64_t **ends) {
  if (n_cells > 0 && !idx && size != 1)
    return karst_set_error(ctx, KARST_EINVAL, "%s: %" PRId64 " %ss but no indices", path,
                           (int64_t)n_cells, what);
  int64_t *c = own(f, malloc(((size_t)n_cells * (size_t)size + 1) * sizeof *c));
  int64_t *e = own(f, malloc(((size_t)n_cells + 1) * sizeof *e));
  if (!c || !e) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  for (karst_int_t k = 0; k < n_cells; k++) {
    for (int j = 0; j < size; j++) {
      karst_int_t v = idx ? idx[(size_t)k * (size_t)size + (size_t)j] : k;
      if (v < 0 || v >= n_points)
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: %s %" PRId64 " refers to point %" PRId64
                               ", outside [0, %" PRId64 ")",
                               path, what, (int64_t)k, (int64_t)v, (int64_t)n_points);
      c[(size_t)k * (size_t)size + (size_t)j] = v;
    }
    e[k] = (int64_t)(k + 1) * size;
  }
  *conn = c, *ends = e;
  return KARST_SUCCESS;
}

/* One karst attribute as an array: Int32 for integer attributes (each value checked), Float64
 * otherwise. */
static karst_error_t attr_array(karst_ctx_t *ctx, file_t *f, const char *path, const char *what,
                                const karst_attr_t *a, karst_int_t n, karst_i_vtp_array_t *out) {
  if (a->ncomp < 1 || a->name[0] == '\0' || (n > 0 && !a->data))
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: %s attribute '%s' is malformed (ncomp %d, data %s)", path, what,
                           a->name, a->ncomp, a->data ? "set" : "NULL");
  const karst_int_t nv = n * a->ncomp;
  karst_i_vtp_array_t r = {a->name, KARST_I_VTP_FLOAT64, a->ncomp, NULL, n, a->data, NULL};
  if (a->integer) {
    int32_t *d = own(f, malloc(((size_t)nv + 1) * sizeof *d));
    if (!d) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
    for (karst_int_t i = 0; i < nv; i++) {
      double v = a->data[i];
      if (!(v >= INT32_MIN && v <= INT32_MAX) || v != floor(v))
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: %s attribute '%s' is marked integer but %s %" PRId64
                               " has the value %g (not a 32-bit integer)",
                               path, what, a->name, what, (int64_t)(i / a->ncomp), v);
      d[i] = (int32_t)v;
    }
    r.type = KARST_I_VTP_INT32;
    r.data = d;
  }
  *out = r;
  return KARST_SUCCESS;
}

static karst_error_t finish(karst_ctx_t *ctx, const char *path, file_t *f,
                            karst_i_vtp_polydata_t *pd, const char *role) {
  add_versions(f);
  describe_arrays(f, role);
  if (f->failed) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  pd->field = f->field, pd->n_field = f->n_field;
  pd->point = f->point, pd->n_point = f->n_point;
  pd->cell = f->cell, pd->n_cell = f->n_cell;
  return karst_i_vtp_write(ctx, path, pd);
}

/* ------------------------------------------------------------------------ */
/* The writers of include/karst/vtk.h                                        */
/* ------------------------------------------------------------------------ */

static karst_error_t write_network(karst_ctx_t *ctx, const char *path, const karst_network_t *net,
                                   file_t *f) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!net) return karst_set_error(ctx, KARST_EINVAL, "%s: no network given", path);
  if (net->n_nodes < 0 || net->n_edges < 0)
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: negative size (%" PRId64 " nodes, %" PRId64 " edges)", path,
                           (int64_t)net->n_nodes, (int64_t)net->n_edges);
  karst_i_vtp_polydata_t pd = {0};
  if ((err = check_points(ctx, path, "node", net->n_nodes, net->xyz))) return err;
  pd.n_points = net->n_nodes, pd.xyz = net->xyz;
  if ((err = make_cells(ctx, f, path, "edge", 2, net->n_edges, net->edges, net->n_nodes,
                        &pd.conn[KARST_I_VTP_LINES], &pd.ends[KARST_I_VTP_LINES])))
    return err;
  pd.n_cells[KARST_I_VTP_LINES] = net->n_edges;
  for (int i = 0; i < net->n_node_attrs; i++) {
    const karst_attr_t *a = &net->node_attrs[i];
    if (net->node_labels && strcmp(a->name, "label") == 0)
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: node attribute 'label' clashes with the node labels", path);
    karst_i_vtp_array_t arr;
    if ((err = attr_array(ctx, f, path, "node", a, net->n_nodes, &arr))) return err;
    add_point(f, arr);
  }
  for (int i = 0; i < net->n_edge_attrs; i++) {
    karst_i_vtp_array_t arr;
    if ((err = attr_array(ctx, f, path, "edge", &net->edge_attrs[i], net->n_edges, &arr)))
      return err;
    add_cell(f, arr);
  }
  /* ParaView colours by the active scalars when a file is opened. */
  if (karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type")) pd.cell_scalars = "tunnel_type";
  if (net->node_labels) add_point(f, strings("label", net->n_nodes, (const char *const *)net->node_labels));
  if (net->crs) add_field(f, strings("crs", 1, (const char *const *)&net->crs));
  for (int i = 0; i < net->n_strings; i++)
    add_field(f, strings(net->strings[i].name, net->strings[i].n,
                         (const char *const *)net->strings[i].values));
  if (net->title) add_field(f, strings("title", 1, (const char *const *)&net->title));
  add_lookup_tables(f);
  return finish(ctx, path, f, &pd, "network");
}

/**
 * Write a network as VTK XML PolyData (.vtp) for ParaView: one 2-point line cell per edge, in
 * edge order (cell data maps 1:1 to edges); node coordinates as Float64 points (exact round
 * trip); node attributes as point data and edge attributes as cell data, Int32 when marked
 * integer, Float64 otherwise, with their ncomp components; node labels as the point string
 * array "label" (NULL labels written as ""); crs and title as one-value field-data string
 * arrays; the field-data string arrays "tunnel_type_names" and "node_kind_names", whose value
 * i names tunnel type / node kind i (Paris et al. 2021, §5.3); "tunnel_type", when present,
 * the active cell scalars.
 * @return KARST_SUCCESS; KARST_EINVAL for non-finite coordinates, edges outside the node range,
 *         integer attributes holding non-integers; KARST_ENOMEM; KARST_EIO when the file cannot
 *         be written (nothing is left behind).
 * Time complexity: O(n_nodes + n_edges) times the number of attribute components.
 * Format: VTK File Formats, XML PolyData (VTK User's Guide, 11th ed., §19.3).
 */
karst_error_t karst_vtk_write_network(karst_ctx_t *ctx, const char *path,
                                      const karst_network_t *net) {
  file_t f = {0};
  karst_error_t err = write_network(ctx, path, net, &f);
  file_free(&f);
  return err;
}

static karst_error_t write_samples(karst_ctx_t *ctx, const char *path, const karst_samples_t *s,
                                   file_t *f) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!s) return karst_set_error(ctx, KARST_EINVAL, "%s: no samples given", path);
  if (s->n < 0)
    return karst_set_error(ctx, KARST_EINVAL, "%s: negative sample count %" PRId64, path,
                           (int64_t)s->n);
  if (s->n > 0 && !s->source)
    return karst_set_error(ctx, KARST_EINVAL, "%s: %" PRId64 " samples but no source tags", path,
                           (int64_t)s->n);
  karst_i_vtp_polydata_t pd = {0};
  if ((err = check_points(ctx, path, "sample", s->n, s->xyz))) return err;
  pd.n_points = s->n, pd.xyz = s->xyz;
  /* One vertex cell per sample, so that ParaView draws them without a glyph filter. */
  if ((err = make_cells(ctx, f, path, "vertex", 1, s->n, NULL, s->n, &pd.conn[KARST_I_VTP_VERTS],
                        &pd.ends[KARST_I_VTP_VERTS])))
    return err;
  pd.n_cells[KARST_I_VTP_VERTS] = s->n;
  int32_t *src = own(f, malloc(((size_t)s->n + 1) * sizeof *src));
  if (!src) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  for (karst_int_t i = 0; i < s->n; i++) {
    if (s->source[i] >= KARST_SAMPLE_SOURCE_COUNT)
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: sample %" PRId64 " has source %d, outside [0, %d)", path,
                             (int64_t)i, (int)s->source[i], (int)KARST_SAMPLE_SOURCE_COUNT);
    src[i] = s->source[i];
  }
  add_point(f, int32s("source", s->n, src));
  pd.point_scalars = "source";
  add_field(f, strings("source_names", KARST_SAMPLE_SOURCE_COUNT,
                       code_names(f, KARST_SAMPLE_SOURCE_COUNT, sample_source_name)));
  int64_t *nkey = own(f, malloc(sizeof *nkey));
  if (!nkey) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  *nkey = s->n_key_points;
  karst_i_vtp_array_t nk = {"n_key_points", KARST_I_VTP_INT64, 1, NULL, 1, nkey, NULL};
  add_field(f, nk);
  if (s->crs) add_field(f, strings("crs", 1, (const char *const *)&s->crs));
  return finish(ctx, path, f, &pd, "samples");
}

/**
 * Write a sample cloud as .vtp: one vertex cell per sample, the Int32 point array "source"
 * (karst_sample_source_t), the field-data string array "source_names" (value i names source i)
 * and the Int64 field value "n_key_points".
 * @return KARST_SUCCESS, KARST_EINVAL (bad coordinates or source tags), KARST_ENOMEM or
 *         KARST_EIO. Time complexity: O(n).
 */
karst_error_t karst_vtk_write_samples(karst_ctx_t *ctx, const char *path,
                                      const karst_samples_t *s) {
  file_t f = {0};
  karst_error_t err = write_samples(ctx, path, s, &f);
  file_free(&f);
  return err;
}

static karst_error_t write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m,
                                int n_extra, const char *const *extra_names,
                                const int *const *extra, file_t *f) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!m) return karst_set_error(ctx, KARST_EINVAL, "%s: no mesh given", path);
  if (m->n_vertices < 0 || m->n_triangles < 0)
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: negative size (%" PRId64 " vertices, %" PRId64 " triangles)", path,
                           (int64_t)m->n_vertices, (int64_t)m->n_triangles);
  karst_i_vtp_polydata_t pd = {0};
  if ((err = check_points(ctx, path, "vertex", m->n_vertices, m->xyz))) return err;
  pd.n_points = m->n_vertices, pd.xyz = m->xyz;
  if ((err = make_cells(ctx, f, path, "triangle", 3, m->n_triangles, m->tri, m->n_vertices,
                        &pd.conn[KARST_I_VTP_POLYS], &pd.ends[KARST_I_VTP_POLYS])))
    return err;
  pd.n_cells[KARST_I_VTP_POLYS] = m->n_triangles;
  /* int and int32_t are the same type on every machine karst builds on (checked below) */
  if (m->tri_label) {
    const char *name = m->tri_label_name && *m->tri_label_name ? m->tri_label_name : "label";
    add_cell(f, int32s(name, m->n_triangles, (const int32_t *)m->tri_label));
    pd.cell_scalars = name;
  }
  if (m->tri_feature) add_cell(f, int32s("feature", m->n_triangles, (const int32_t *)m->tri_feature));
  for (int k = 0; k < n_extra; k++) {
    if (!extra_names || !extra_names[k] || !*extra_names[k] || !extra || !extra[k])
      return karst_set_error(ctx, KARST_EINVAL, "%s: cell array %d has no name or no values", path,
                             k);
    add_cell(f, int32s(extra_names[k], m->n_triangles, (const int32_t *)extra[k]));
    if (!m->tri_label && k == 0) pd.cell_scalars = extra_names[k];
  }
  return finish(ctx, path, f, &pd, "mesh");
}
_Static_assert(sizeof(int) == sizeof(int32_t), "int must be 32 bits");

/**
 * Write a triangle mesh as .vtp polygons, with the Int32 cell array tri_label_name ("label"
 * when NULL) when tri_label is set, which is then the active cell scalars, and the Int32 cell
 * array "feature" when tri_feature is set.
 * @return KARST_SUCCESS, KARST_EINVAL (bad coordinates or indices), KARST_ENOMEM or KARST_EIO.
 * Time complexity: O(n_vertices + n_triangles).
 */
karst_error_t karst_vtk_write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  file_t f = {0};
  karst_error_t err = write_mesh(ctx, path, m, 0, NULL, NULL, &f);
  file_free(&f);
  return err;
}

/**
 * karst_vtk_write_mesh with @p n_arrays further Int32 cell arrays (e.g. block_id and
 * block_type), m->n_triangles values each.
 * @return KARST_SUCCESS, KARST_EINVAL (a nameless or missing array), KARST_ENOMEM, KARST_EIO.
 * Time complexity: O(vertices + triangles × arrays).
 */
karst_error_t karst_vtk_write_mesh_arrays(karst_ctx_t *ctx, const char *path,
                                          const karst_mesh_t *m, int n_arrays,
                                          const char *const *names, const int *const *arrays) {
  file_t f = {0};
  karst_error_t err = write_mesh(ctx, path, m, n_arrays, names, arrays, &f);
  file_free(&f);
  return err;
}

static karst_error_t write_polydata(karst_ctx_t *ctx, const char *path, const karst_polydata_t *m,
                                    file_t *f) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!m || m->n_points < 0 || m->n_polys < 0 || (m->n_polys > 0 && (!m->offsets || !m->conn)))
    return karst_set_error(ctx, KARST_EINVAL, "%s: no polygons given", path);
  karst_i_vtp_polydata_t pd = {0};
  if ((err = check_points(ctx, path, "point", m->n_points, m->xyz))) return err;
  pd.n_points = m->n_points, pd.xyz = m->xyz;
  int64_t *ends = own(f, malloc(((size_t)m->n_polys + 1) * sizeof *ends));
  if (!ends) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  karst_int_t n_conn = 0;
  for (karst_int_t c = 0; c < m->n_polys; c++) {
    karst_int_t b = m->offsets[c], e = m->offsets[c + 1];
    if (b < 0 || e < b + 3)
      return karst_set_error(ctx, KARST_EINVAL, "%s: polygon %" PRId64 " has fewer than 3 points",
                             path, (int64_t)c);
    n_conn += e - b;
    ends[c] = n_conn;
  }
  int64_t *conn = own(f, malloc(((size_t)n_conn + 1) * sizeof *conn));
  if (!conn) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  for (karst_int_t c = 0, k = 0; c < m->n_polys; c++)
    for (karst_int_t i = m->offsets[c]; i < m->offsets[c + 1]; i++, k++) {
      if (m->conn[i] < 0 || m->conn[i] >= m->n_points)
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: polygon %" PRId64 " refers to point %" PRId64 " of %" PRId64,
                               path, (int64_t)c, (int64_t)m->conn[i], (int64_t)m->n_points);
      conn[k] = m->conn[i];
    }
  pd.n_cells[KARST_I_VTP_POLYS] = m->n_polys;
  pd.ends[KARST_I_VTP_POLYS] = ends, pd.conn[KARST_I_VTP_POLYS] = conn;
  for (int a = 0; a < m->n_cell_arrays; a++) {
    add_cell(f, int32s(m->cell_array_names[a], m->n_polys, (const int32_t *)m->cell_arrays[a]));
    if (a == 0) pd.cell_scalars = m->cell_array_names[a];
  }
  for (int i = 0; i < m->n_strings; i++)
    add_field(f, strings(m->strings[i].name, m->strings[i].n,
                         (const char *const *)m->strings[i].values));
  return finish(ctx, path, f, &pd, m->role);
}

/**
 * Write polygons (any number of points each) as .vtp, with integer cell arrays (the first is
 * the active scalars) and field-data string lists, atomically.
 * @return KARST_SUCCESS, KARST_EINVAL (a polygon of fewer than 3 points or referring to a point
 *         that does not exist, non-finite coordinates), KARST_ENOMEM or KARST_EIO.
 * Time complexity: O(points + polygon vertices + arrays x polygons).
 */
karst_error_t karst_vtk_write_polydata(karst_ctx_t *ctx, const char *path,
                                       const karst_polydata_t *pd) {
  file_t f = {0};
  karst_error_t err = write_polydata(ctx, path, pd, &f);
  file_free(&f);
  return err;
}
