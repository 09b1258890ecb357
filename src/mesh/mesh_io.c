/* Mesh writers (.vtp, binary little-endian .ply, binary .stl, chosen by
 * extension, written atomically), the divergence-theorem volume and the
 * combinatorial closed/oriented check. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "karst/io.h"
#include "karst/mesh.h"
#include "karst/version.h"
#include "mesh/mesh_internal.h"

static karst_error_t check_mesh_arrays(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  if (!m || m->n_vertices < 0 || m->n_triangles < 0 || (m->n_vertices > 0 && !m->xyz) ||
      (m->n_triangles > 0 && !m->tri))
    return karst_set_error(ctx, KARST_EINVAL, "%s: the mesh is not valid", path);
  for (karst_int_t i = 0; i < 3 * m->n_triangles; i++)
    if (m->tri[i] < 0 || m->tri[i] >= m->n_vertices)
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: triangle %lld refers to vertex %lld (mesh has %lld)", path,
                             (long long)(i / 3), (long long)m->tri[i], (long long)m->n_vertices);
  return KARST_SUCCESS;
}

/* Little-endian encoders (portable whatever the host byte order). */
static void le32(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; i++)
    b[i] = (unsigned char)(v >> (8 * i));
}
static void le64(unsigned char *b, uint64_t v) {
  for (int i = 0; i < 8; i++)
    b[i] = (unsigned char)(v >> (8 * i));
}
static void lef32(unsigned char *b, float f) {
  uint32_t v;
  memcpy(&v, &f, 4);
  le32(b, v);
}
static void lef64(unsigned char *b, double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  le64(b, v);
}

/**
 * Binary little-endian PLY (vertices as double x, y, z; faces as a uchar
 * count and int indices, plus an int "tunnel_type" per face when labelled),
 * with a header comment per component of karst_versions(), written atomically.
 * @return KARST_SUCCESS; KARST_EINVAL (bad mesh); KARST_ERANGE (more than
 *         2^31-1 vertices); KARST_EIO. Time complexity: O(V + T).
 */
karst_error_t karst_mesh_write_ply(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  karst_error_t err = check_mesh_arrays(ctx, path, m);
  if (err) return err;
  if (m->n_vertices > INT32_MAX)
    return karst_set_error(ctx, KARST_ERANGE, "%s: %lld vertices do not fit PLY int indices", path,
                           (long long)m->n_vertices);
  karst_atomic_file_t f;
  if ((err = karst_atomic_open(ctx, &f, path, "wb"))) return err;
  /* One comment per component of karst_versions(), "karst VERSION" first. */
  karst_component_t comp[KARST_COMPONENTS_MAX];
  int n_comp = karst_versions(comp);
  fprintf(f.fp, "ply\nformat binary_little_endian 1.0\n");
  for (int i = 0; i < n_comp; i++)
    fprintf(f.fp, "comment %s %s\n", comp[i].name, comp[i].version);
  fprintf(f.fp,
          "element vertex %lld\n"
          "property double x\nproperty double y\nproperty double z\nelement face %lld\n"
          "property list uchar int vertex_indices\n",
          (long long)m->n_vertices, (long long)m->n_triangles);
  if (m->tri_label)
    fprintf(f.fp, "property int %s\n", m->tri_label_name ? m->tri_label_name : "label");
  fprintf(f.fp, "end_header\n");
  unsigned char b[24];
  for (karst_int_t i = 0; i < m->n_vertices; i++) {
    for (int c = 0; c < 3; c++)
      lef64(b + 8 * c, m->xyz[3 * i + c]);
    fwrite(b, 1, 24, f.fp);
  }
  for (karst_int_t i = 0; i < m->n_triangles; i++) {
    unsigned char t[17];
    t[0] = 3;
    for (int c = 0; c < 3; c++)
      le32(t + 1 + 4 * c, (uint32_t)(int32_t)m->tri[3 * i + c]);
    size_t n = 13;
    if (m->tri_label) {
      le32(t + 13, (uint32_t)(int32_t)m->tri_label[i]);
      n = 17;
    }
    fwrite(t, 1, n, f.fp);
  }
  return karst_atomic_commit(ctx, &f);
}

/**
 * Origin subtracted from the coordinates of a binary STL (see mesh.h): per
 * axis, 0 when every coordinate lies within ±KARST_MESH_STL_SMALL, else the
 * smallest coordinate rounded down to a multiple of
 * KARST_MESH_STL_ORIGIN_STEP. Time complexity: O(V).
 */
void karst_mesh_stl_origin(const karst_mesh_t *m, double origin[3]) {
  origin[0] = origin[1] = origin[2] = 0;
  if (!m || m->n_vertices <= 0 || !m->xyz) return;
  for (int c = 0; c < 3; c++) {
    double lo = m->xyz[c], hi = m->xyz[c];
    for (karst_int_t i = 1; i < m->n_vertices; i++) {
      double x = m->xyz[3 * i + c];
      if (x < lo) lo = x;
      if (x > hi) hi = x;
    }
    if (!isfinite(lo) || !isfinite(hi)) continue;
    if (fmax(fabs(lo), fabs(hi)) <= KARST_MESH_STL_SMALL) continue;
    origin[c] = floor(lo / KARST_MESH_STL_ORIGIN_STEP) * KARST_MESH_STL_ORIGIN_STEP;
  }
}

/**
 * Binary STL: 80-byte header, uint32 count, per triangle the unit normal, the
 * three vertices (float32, the format's only type) and a zero attribute.
 * Far from the origin (UTM: 6e5 m, where float32 steps are 6 cm) the
 * vertices are written relative to karst_mesh_stl_origin, so they keep
 * float32's relative precision over the mesh's own extent; the origin is
 * the header's first words, "karst origin x=600000 y=5123400 z=0", for the
 * reader to add back. Written atomically.
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ERANGE (more than 2^32-1
 *         triangles), KARST_EIO. Time complexity: O(V + T).
 */
karst_error_t karst_mesh_write_stl(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  karst_error_t err = check_mesh_arrays(ctx, path, m);
  if (err) return err;
  if (m->n_triangles > (karst_int_t)UINT32_MAX)
    return karst_set_error(ctx, KARST_ERANGE, "%s: %lld triangles exceed the STL limit", path,
                           (long long)m->n_triangles);
  karst_atomic_file_t f;
  if ((err = karst_atomic_open(ctx, &f, path, "wb"))) return err;
  double o[3];
  karst_mesh_stl_origin(m, o);
  unsigned char head[84];
  memset(head, 0, sizeof head);
  /* the origin first, so that it survives the 80-byte limit; multiples of
   * 100 m print exactly with %.0f */
  char text[128];
  snprintf(text, sizeof text, "karst origin x=%.0f y=%.0f z=%.0f; karst %s binary STL", o[0], o[1],
           o[2], karst_version());
  memcpy(head, text, strlen(text) < 80 ? strlen(text) : 80);
  le32(head + 80, (uint32_t)m->n_triangles);
  fwrite(head, 1, 84, f.fp);
  for (karst_int_t i = 0; i < m->n_triangles; i++) {
    const double *p[3];
    for (int k = 0; k < 3; k++)
      p[k] = m->xyz + 3 * m->tri[3 * i + k];
    double u[3], v[3], n[3];
    for (int c = 0; c < 3; c++)
      u[c] = p[1][c] - p[0][c], v[c] = p[2][c] - p[0][c];
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    unsigned char r[50];
    memset(r, 0, sizeof r);
    for (int c = 0; c < 3; c++)
      lef32(r + 4 * c, (float)(l > 0 ? n[c] / l : 0));
    for (int k = 0; k < 3; k++)
      for (int c = 0; c < 3; c++)
        lef32(r + 12 + 12 * k + 4 * c, (float)(p[k][c] - o[c]));
    fwrite(r, 1, 50, f.fp);
  }
  return karst_atomic_commit(ctx, &f);
}

static const char *extension(const char *path) {
  const char *slash = strrchr(path, '/');
  const char *dot = strrchr(path, '.');
  return dot && (!slash || dot > slash) ? dot : "";
}

/**
 * Write a mesh, the format chosen by the extension: .vtp (VTK PolyData with
 * the label as cell data), .ply, .stl. @return KARST_EINVAL for any other
 * extension, else the writer's code. Time complexity: O(V + T).
 */
karst_error_t karst_mesh_write(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  if (!path) return karst_set_error(ctx, KARST_EINVAL, "mesh output: no path given");
  const char *ext = extension(path);
  if (strcasecmp(ext, ".vtp") == 0) {
    karst_error_t err = check_mesh_arrays(ctx, path, m);
    return err ? err : karst_vtk_write_mesh(ctx, path, m);
  }
  if (strcasecmp(ext, ".ply") == 0) return karst_mesh_write_ply(ctx, path, m);
  if (strcasecmp(ext, ".stl") == 0) return karst_mesh_write_stl(ctx, path, m);
  return karst_set_error(ctx, KARST_EINVAL,
                         "%s: unknown mesh format '%s' (expected .vtp, .ply or .stl)", path, ext);
}

/**
 * Enclosed volume by the divergence theorem, Σ p0.(p1 x p2)/6 over the
 * triangles, relative to the first vertex to limit cancellation far from
 * the origin. Exact for a closed, consistently oriented mesh; positive when
 * the triangles face outwards. Time complexity: O(T).
 */
double karst_mesh_volume(const karst_mesh_t *m) {
  if (!m || m->n_vertices == 0) return 0;
  const double *o = m->xyz;
  double v = 0;
  for (karst_int_t i = 0; i < m->n_triangles; i++) {
    double p[3][3];
    for (int k = 0; k < 3; k++)
      for (int c = 0; c < 3; c++)
        p[k][c] = m->xyz[3 * m->tri[3 * i + k] + c] - o[c];
    v += p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
         p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
         p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
  }
  return v / 6.0;
}

/**
 * Combinatorial closed / oriented / edge-manifold check (see mesh.h): every
 * directed edge (a, b) must be used by exactly one triangle and (b, a) by
 * exactly one other. Time complexity: O(T) expected (hash map).
 */
karst_error_t karst_mesh_check(karst_ctx_t *ctx, const karst_mesh_t *m, karst_mesh_check_t *res) {
  memset(res, 0, sizeof *res);
  karst_error_t err = check_mesh_arrays(ctx, "mesh check", m);
  if (err) return err;
  karst_i_hmap_t h;
  if (karst_i_hmap_init(&h, 3 * m->n_triangles))
    return karst_set_error(ctx, KARST_ENOMEM, "mesh check: out of memory");
  /* key = a * V + b; value = number of uses */
  karst_int_t V = m->n_vertices;
  for (karst_int_t i = 0; i < m->n_triangles && !err; i++) {
    const karst_int_t *t = m->tri + 3 * i;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) res->degenerate++;
    for (int k = 0; k < 3; k++) {
      karst_int_t key = t[k] * V + t[(k + 1) % 3], got;
      int r = karst_i_hmap_find_or_insert(&h, key, 1, &got);
      if (r < 0) {
        err = karst_set_error(ctx, KARST_ENOMEM, "mesh check: out of memory");
        break;
      }
      if (r == 0) {
        res->nonmanifold_edges++;
      }
    }
  }
  for (karst_int_t i = 0; i < h.cap && !err; i++) {
    if (h.keys[i] < 0) continue;
    karst_int_t a = h.keys[i] / V, b = h.keys[i] % V;
    if (!karst_i_hmap_find(&h, b * V + a)) res->boundary_edges++;
  }
  karst_i_hmap_destroy(&h);
  return err;
}
