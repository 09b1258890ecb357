/* geology.vtp: the geological model as polygons for ParaView (karst_geology_write_vtp). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geology/geology_internal.h"
#include "karst/surface.h"
#include "karst/vtk.h"

/** Most grid intervals along x or y of a surface drawn in geology.vtp. */
#define GEOLOGY_VTP_MAX_INTERVALS 100
/** A plane this far (m) below the terrain's lowest point is drawn whole, as two triangles. */
#define GEOLOGY_VTP_PLANE_MARGIN 1e-6
/** Sides of the polygon that draws a disc (a fault disc or a fracture of a network). */
#define GEOLOGY_VTP_DISC_SIDES 24

typedef struct {
  double *xyz;
  karst_int_t np, cap_p;
  karst_int_t *off, *conn;
  karst_int_t nc, cap_c, nconn, cap_conn;
  int *feature, *id;
  int failed;
} polys_t;

static karst_int_t add_point(polys_t *P, double x, double y, double z) {
  if (P->np == P->cap_p) {
    karst_int_t cap = P->cap_p ? 2 * P->cap_p : 1024;
    double *n = realloc(P->xyz, (size_t)cap * 3 * sizeof *n);
    if (!n) return P->failed = 1, 0;
    P->xyz = n, P->cap_p = cap;
  }
  P->xyz[3 * P->np] = x, P->xyz[3 * P->np + 1] = y, P->xyz[3 * P->np + 2] = z;
  return P->np++;
}

/* Append a polygon of @p k points (indices), tagged (feature, id). */
static void add_poly(polys_t *P, const karst_int_t *v, int k, int feature, int id) {
  if (P->failed) return;
  if (P->nc + 1 >= P->cap_c) {
    karst_int_t cap = P->cap_c ? 2 * P->cap_c : 1024;
    karst_int_t *o = realloc(P->off, (size_t)(cap + 1) * sizeof *o);
    int *f = o ? realloc(P->feature, (size_t)cap * sizeof *f) : NULL;
    if (f) P->feature = f;
    int *d = f ? realloc(P->id, (size_t)cap * sizeof *d) : NULL;
    if (o) P->off = o;
    if (!o || !f || !d) {
      P->failed = 1;
      return;
    }
    P->id = d, P->cap_c = cap;
  }
  if (P->nconn + k > P->cap_conn) {
    karst_int_t cap = P->cap_conn ? 2 * P->cap_conn + k : 4096 + k;
    karst_int_t *c = realloc(P->conn, (size_t)cap * sizeof *c);
    if (!c) {
      P->failed = 1;
      return;
    }
    P->conn = c, P->cap_conn = cap;
  }
  if (P->nc == 0) P->off[0] = 0;
  memcpy(P->conn + P->nconn, v, (size_t)k * sizeof *v);
  P->nconn += k;
  P->feature[P->nc] = feature, P->id[P->nc] = id;
  P->off[++P->nc] = P->nconn;
}

/* Whether a triangle (point indices) lies wholly above the terrain. */
static int above_terrain(const polys_t *P, const karst_geology_t *g, const karst_int_t tri[3]) {
  for (int k = 0; k < 3; k++) {
    const double *p = P->xyz + 3 * tri[k];
    if (!(p[2] > karst_i_surf_z(&g->terrain, p[0], p[1]))) return 0;
  }
  return 1;
}

/* A triangulated surface by its own triangles, cut to the domain's x-y extent
 * (karst_surface_triangulate). */
static void add_tin(polys_t *P, const karst_geology_t *g, const karst_surface_t *surf, int feature,
                    int id, int clip_to_terrain) {
  const karst_scenario_t *sc = g->sc;
  double *xyz = NULL;
  karst_int_t *tri = NULL, nv = 0, nt = 0;
  karst_ctx_t quiet;
  karst_ctx_init(&quiet);
  if (karst_surface_triangulate(&quiet, surf, sc->domain_min, sc->domain_max, INFINITY, &xyz, &nv,
                                &tri, &nt) != KARST_SUCCESS) {
    P->failed = 1;
    return;
  }
  karst_int_t base = P->np;
  for (karst_int_t v = 0; v < nv; v++)
    add_point(P, xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
  for (karst_int_t t = 0; t < nt && !P->failed; t++) {
    karst_int_t q[3] = {base + tri[3 * t], base + tri[3 * t + 1], base + tri[3 * t + 2]};
    if (!clip_to_terrain || !above_terrain(P, g, q)) add_poly(P, q, 3, feature, id);
  }
  free(xyz);
  free(tri);
}

/* Whether plane s lies below the terrain by more than GEOLOGY_VTP_PLANE_MARGIN over the whole
 * domain: its highest corner below the terrain's lowest point there. */
static int plane_under_terrain(const karst_geology_t *g, const karst_i_surf_t *s) {
  const karst_scenario_t *sc = g->sc;
  double x0 = sc->domain_min[0], x1 = sc->domain_max[0], y0 = sc->domain_min[1],
         y1 = sc->domain_max[1], plo, phi, tlo, thi;
  karst_i_surf_range(s, x0, x1, y0, y1, &plo, &phi);
  karst_i_surf_range(&g->terrain, x0, x1, y0, y1, &tlo, &thi);
  return phi < tlo - GEOLOGY_VTP_PLANE_MARGIN; /* false for NAN */
}

/* A surface over the domain's x-y extent on a regular grid, triangles entirely above the
 * terrain left out (they are not in the rock); NAN vertices (outside a file surface) skip their
 * triangles. A plane the terrain does not cut (or the terrain itself, when a plane) is the
 * domain's rectangle, two triangles: the grid's triangles would all be kept, in that plane. */
static void add_surface(polys_t *P, const karst_geology_t *g, const karst_i_surf_t *s, int feature,
                        int id, int clip_to_terrain) {
  const karst_scenario_t *sc = g->sc;
  if (s->kind == KARST_I_SURF_FILE && s->file && karst_surface_kind(s->file) == KARST_SURFACE_TIN) {
    add_tin(P, g, s->file, feature, id, clip_to_terrain);
    return;
  }
  double ex = sc->domain_max[0] - sc->domain_min[0], ey = sc->domain_max[1] - sc->domain_min[1];
  double step = fmax(ex, ey) / GEOLOGY_VTP_MAX_INTERVALS;
  int nx = (int)fmax(1.0, ceil(ex / step)), ny = (int)fmax(1.0, ceil(ey / step));
  if (s->kind == KARST_I_SURF_PLANE && (!clip_to_terrain || plane_under_terrain(g, s)))
    nx = ny = 1;
  karst_int_t base = P->np;
  for (int j = 0; j <= ny; j++)
    for (int i = 0; i <= nx; i++) {
      double x = sc->domain_min[0] + ex * i / nx, y = sc->domain_min[1] + ey * j / ny;
      add_point(P, x, y, karst_i_surf_z(s, x, y));
    }
  if (P->failed) return;
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++) {
      karst_int_t q[4] = {base + j * (nx + 1) + i, base + j * (nx + 1) + i + 1,
                          base + (j + 1) * (nx + 1) + i + 1, base + (j + 1) * (nx + 1) + i};
      for (int t = 0; t < 2; t++) {
        karst_int_t tri[3] = {q[0], q[1 + t], q[2 + t]};
        int above = clip_to_terrain, defined = 1;
        for (int k = 0; k < 3; k++) {
          const double *p = P->xyz + 3 * tri[k];
          defined &= isfinite(p[2]);
          if (above && !(p[2] > karst_i_surf_z(&g->terrain, p[0], p[1]))) above = 0;
        }
        if (defined && !above) add_poly(P, tri, 3, feature, id);
      }
    }
}

/* A disc of centre c, unit normal n and radius r as a polygon. */
static void add_disc(polys_t *P, const double c[3], const double n[3], double r, int feature,
                     int id) {
  double a[3] = {1, 0, 0}, u[3], v[3];
  if (fabs(n[0]) > 0.9) a[0] = 0, a[1] = 1;
  double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
  for (int k = 0; k < 3; k++)
    u[k] = a[k] - d * n[k];
  double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int k = 0; k < 3; k++)
    u[k] /= l;
  v[0] = n[1] * u[2] - n[2] * u[1], v[1] = n[2] * u[0] - n[0] * u[2],
  v[2] = n[0] * u[1] - n[1] * u[0];
  karst_int_t ids[GEOLOGY_VTP_DISC_SIDES];
  for (int i = 0; i < GEOLOGY_VTP_DISC_SIDES; i++) {
    double t = 2 * M_PI * i / GEOLOGY_VTP_DISC_SIDES, p[3];
    for (int k = 0; k < 3; k++)
      p[k] = c[k] + r * (cos(t) * u[k] + sin(t) * v[k]);
    ids[i] = add_point(P, p[0], p[1], p[2]);
  }
  add_poly(P, ids, GEOLOGY_VTP_DISC_SIDES, feature, id);
}

static int cmp_angle(const void *x, const void *y) {
  double a = ((const double *)x)[3], b = ((const double *)y)[3];
  return (a > b) - (a < b);
}

/* The polygon where an unbounded plane (point c, unit normal n) cuts the domain box: its
 * crossings with the 12 box edges, in angular order about their centroid. */
static void add_plane_in_box(polys_t *P, const karst_scenario_t *sc, const double c[3],
                             const double n[3], int feature, int id) {
  double pts[12][4];
  int m = 0;
  const double *lo = sc->domain_min, *hi = sc->domain_max;
  for (int axis = 0; axis < 3; axis++)
    for (int e = 0; e < 4; e++) {
      int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      double p[3];
      p[a1] = e & 1 ? hi[a1] : lo[a1];
      p[a2] = e & 2 ? hi[a2] : lo[a2];
      /* n·(p − c) = 0 along the edge: solve for p[axis]. */
      if (n[axis] == 0) continue;
      double s = n[a1] * (p[a1] - c[a1]) + n[a2] * (p[a2] - c[a2]);
      p[axis] = c[axis] - s / n[axis];
      if (!(p[axis] >= lo[axis] && p[axis] <= hi[axis])) continue;
      memcpy(pts[m], p, sizeof p);
      m++;
    }
  if (m < 3) return;
  double g[3] = {0, 0, 0}, u[3], v[3], a[3] = {1, 0, 0};
  for (int i = 0; i < m; i++)
    for (int k = 0; k < 3; k++)
      g[k] += pts[i][k] / m;
  if (fabs(n[0]) > 0.9) a[0] = 0, a[1] = 1;
  double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
  for (int k = 0; k < 3; k++)
    u[k] = a[k] - d * n[k];
  v[0] = n[1] * u[2] - n[2] * u[1], v[1] = n[2] * u[0] - n[0] * u[2],
  v[2] = n[0] * u[1] - n[1] * u[0];
  for (int i = 0; i < m; i++) {
    double q[3] = {pts[i][0] - g[0], pts[i][1] - g[1], pts[i][2] - g[2]};
    pts[i][3] =
        atan2(q[0] * v[0] + q[1] * v[1] + q[2] * v[2], q[0] * u[0] + q[1] * u[1] + q[2] * u[2]);
  }
  qsort(pts, (size_t)m, sizeof pts[0], cmp_angle);
  karst_int_t ids[12];
  int k = 0;
  for (int i = 0; i < m; i++) { /* a crossing at a box corner comes once per edge: keep one */
    if (i > 0 && fabs(pts[i][0] - pts[i - 1][0]) + fabs(pts[i][1] - pts[i - 1][1]) +
                         fabs(pts[i][2] - pts[i - 1][2]) <
                     1e-9)
      continue;
    ids[k++] = add_point(P, pts[i][0], pts[i][1], pts[i][2]);
  }
  if (k >= 3) add_poly(P, ids, k, feature, id);
}

static void add_box(polys_t *P, const double lo[3], const double hi[3], int feature, int id) {
  karst_int_t c[8];
  for (int i = 0; i < 8; i++)
    c[i] = add_point(P, i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
  static const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6; f++) {
    karst_int_t q[4] = {c[faces[f][0]], c[faces[f][1]], c[faces[f][2]], c[faces[f][3]]};
    add_poly(P, q, 4, feature, id);
  }
}

static void add_sphere(polys_t *P, const double c[3], double r, int feature, int id) {
  enum { NU = 24, NV = 12 };
  karst_int_t top = add_point(P, c[0], c[1], c[2] + r), bot = add_point(P, c[0], c[1], c[2] - r);
  karst_int_t ring[NV - 1][NU];
  for (int j = 1; j < NV; j++)
    for (int i = 0; i < NU; i++) {
      double th = M_PI * j / NV, ph = 2 * M_PI * i / NU;
      ring[j - 1][i] = add_point(P, c[0] + r * sin(th) * cos(ph), c[1] + r * sin(th) * sin(ph),
                                 c[2] + r * cos(th));
    }
  for (int i = 0; i < NU; i++) {
    int i1 = (i + 1) % NU;
    karst_int_t t1[3] = {top, ring[0][i], ring[0][i1]},
                t2[3] = {bot, ring[NV - 2][i1], ring[NV - 2][i]};
    add_poly(P, t1, 3, feature, id);
    add_poly(P, t2, 3, feature, id);
    for (int j = 0; j + 1 < NV - 1; j++) {
      karst_int_t q[4] = {ring[j][i], ring[j + 1][i], ring[j + 1][i1], ring[j][i1]};
      add_poly(P, q, 4, feature, id);
    }
  }
}

static void add_prism(polys_t *P, const karst_exclusion_t *e, int feature, int id) {
  int n = e->n_vertices;
  karst_int_t *b = malloc(sizeof *b * (size_t)n), *t = malloc(sizeof *t * (size_t)n);
  if (!b || !t) {
    free(b), free(t);
    P->failed = 1;
    return;
  }
  for (int i = 0; i < n; i++) {
    b[i] = add_point(P, e->polygon[2 * i], e->polygon[2 * i + 1], e->bottom);
    t[i] = add_point(P, e->polygon[2 * i], e->polygon[2 * i + 1], e->top);
  }
  add_poly(P, b, n, feature, id);
  add_poly(P, t, n, feature, id);
  for (int i = 0; i < n; i++) {
    int i1 = (i + 1) % n;
    karst_int_t q[4] = {b[i], b[i1], t[i1], t[i]};
    add_poly(P, q, 4, feature, id);
  }
  free(b), free(t);
}

/**
 * Write the geological model as polygons (see geology.h): the terrain, each horizon, each
 * distinct water table (feature_id = spring index), stratum boundaries (feature_id = stratum
 * index) over the domain's x-y extent on a grid of at most GEOLOGY_VTP_MAX_INTERVALS intervals
 * a side (triangles wholly above the terrain left out), faults (discs, or a plane cut to the
 * domain box), the discs of the fracture networks (feature_id = family) and the exclusion zones.
 * Field data: "feature_names" and the names of the springs, strata and faults.
 * Time complexity: O(surfaces × grid + discs + exclusions).
 */
karst_error_t karst_geology_write_vtp(karst_ctx_t *ctx, const karst_geology_t *g,
                                      const char *path) {
  const karst_scenario_t *sc = g->sc;
  polys_t P;
  memset(&P, 0, sizeof P);
  karst_error_t err = KARST_SUCCESS;
  add_surface(&P, g, &g->terrain, KARST_FEATURE_TERRAIN, 0, 0);
  for (int h = 0; h < g->n_horizons; h++)
    add_surface(&P, g, &g->horizon[h], KARST_FEATURE_HORIZON, h, 1);
  for (int w = 0; w < g->n_springs; w++) {
    int seen = 0;
    for (int v = 0; v < w && !seen; v++)
      seen = karst_i_surf_equal(&g->water_table[v], &g->water_table[w]);
    if (!seen) add_surface(&P, g, &g->water_table[w], KARST_FEATURE_WATER_TABLE, w, 1);
  }
  for (int i = 0; i < g->n_strata; i++) {
    if (g->stratum_top[i].kind) add_surface(&P, g, &g->stratum_top[i], KARST_FEATURE_STRATUM, i, 1);
    if (g->stratum_bottom[i].kind)
      add_surface(&P, g, &g->stratum_bottom[i], KARST_FEATURE_STRATUM, i, 1);
  }
  for (int f = 0; f < sc->n_faults; f++) {
    const karst_fault_t *F = &sc->faults[f];
    if (isfinite(F->radius))
      add_disc(&P, F->center, g->fault_normal + 3 * f, F->radius, KARST_FEATURE_FAULT, f);
    else
      add_plane_in_box(&P, sc, F->center, g->fault_normal + 3 * f, KARST_FEATURE_FAULT, f);
  }
  for (karst_int_t i = 0; i < g->n_discs; i++)
    add_disc(&P, g->discs[i].c, g->discs[i].n, g->discs[i].r, KARST_FEATURE_FRACTURE,
             g->discs[i].family);
  for (int i = 0; i < sc->n_exclusions; i++) {
    const karst_exclusion_t *e = &sc->exclusions[i];
    if (e->kind == KARST_EXCLUSION_BOX)
      add_box(&P, e->min, e->max, KARST_FEATURE_EXCLUSION, i);
    else if (e->kind == KARST_EXCLUSION_SPHERE)
      add_sphere(&P, e->center, e->radius, KARST_FEATURE_EXCLUSION, i);
    else
      add_prism(&P, e, KARST_FEATURE_EXCLUSION, i);
  }
  if (P.failed) {
    err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for the geology's polygons", path);
    goto cleanup;
  }
  {
    const char *fnames[KARST_GEOLOGY_FEATURE_COUNT];
    for (int i = 0; i < KARST_GEOLOGY_FEATURE_COUNT; i++)
      fnames[i] = karst_geology_feature_name(i);
    int ns = g->n_springs, nst = sc->n_strata, nf = sc->n_faults;
    const char **springs = malloc(sizeof(char *) * (size_t)(ns + 1));
    const char **strata = malloc(sizeof(char *) * (size_t)(nst + 1));
    const char **faults = malloc(sizeof(char *) * (size_t)(nf + 1));
    karst_strings_t lists[5];
    memset(lists, 0, sizeof lists);
    if (!springs || !strata || !faults) {
      free(springs), free(strata), free(faults);
      err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
      goto cleanup;
    }
    for (int i = 0; i < ns; i++)
      springs[i] = sc->key_points[g->spring_key[i]].name;
    for (int i = 0; i < nst; i++)
      strata[i] = sc->strata[i].name;
    for (int i = 0; i < nf; i++)
      faults[i] = sc->faults[i].name;
    strcpy(lists[0].name, "feature_names"), lists[0].n = KARST_GEOLOGY_FEATURE_COUNT,
                                            lists[0].values = (char **)fnames;
    strcpy(lists[1].name, "spring_names"), lists[1].n = ns, lists[1].values = (char **)springs;
    strcpy(lists[2].name, "stratum_names"), lists[2].n = nst, lists[2].values = (char **)strata;
    strcpy(lists[3].name, "fault_names"), lists[3].n = nf, lists[3].values = (char **)faults;
    /* The scenario's coordinate system, as in network.vtp (docs/scenario.md, "Coordinates"). */
    char *crs = sc->crs;
    strcpy(lists[4].name, "crs"), lists[4].n = 1, lists[4].values = &crs;
    const char *names[2] = {"feature", "feature_id"};
    const int *arrays[2] = {P.feature, P.id};
    karst_polydata_t pd = {P.np,   P.xyz,           P.nc,  P.off,    P.conn, 2, names,
                           arrays, sc->crs ? 5 : 4, lists, "geology"};
    err = karst_vtk_write_polydata(ctx, path, &pd);
    free(springs), free(strata), free(faults);
  }
cleanup:
  free(P.xyz), free(P.off), free(P.conn), free(P.feature), free(P.id);
  return err;
}
