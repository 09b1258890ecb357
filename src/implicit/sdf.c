/* The construction tree of signed-distance bounds (Paris et al. 2021, §6):
 * primitives, operators, the bounding-volume hierarchy of unions, and
 * evaluation. Conventions are in include/karst/implicit.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "implicit/implicit_internal.h"
#include "karst/geology.h"

/* min / max without the NaN rules of fmin / fmax, which the compiler cannot
 * inline (the fields never see NaN: inputs are checked when nodes are made). */
static inline double mn(double a, double b) {
  return a < b ? a : b;
}
static inline double mx(double a, double b) {
  return a > b ? a : b;
}

/* ---------------------------------------------------------------------- */
/* Storage.                                                                */
/* ---------------------------------------------------------------------- */

static int grow(void **p, karst_int_t *cap, karst_int_t need, size_t size) {
  if (need <= *cap) return 0;
  karst_int_t c = *cap ? *cap : 16;
  while (c < need)
    c *= 2;
  void *q = realloc(*p, (size_t)c * size);
  if (!q) return -1;
  *p = q;
  *cap = c;
  return 0;
}

/**
 * Allocate an empty construction tree.
 * @param ctx error context
 * @param out the new tree (free with karst_sdf_free)
 * @return KARST_SUCCESS or KARST_ENOMEM. Time complexity: O(1).
 */
karst_error_t karst_sdf_create(karst_ctx_t *ctx, karst_sdf_t **out) {
  *out = calloc(1, sizeof **out);
  if (!*out) return karst_set_error(ctx, KARST_ENOMEM, "construction tree: out of memory");
  (*out)->root = -1;
  return KARST_SUCCESS;
}

/** Release a tree and everything it holds (NULL allowed). O(terrains). */
void karst_sdf_free(karst_sdf_t *t) {
  if (!t) return;
  for (int i = 0; i < t->n_terrains; i++) {
    free(t->terrains[i].z);
    free(t->terrains[i].path);
  }
  free(t->terrains);
  free(t->nodes);
  free(t->kids);
  free(t->bvh);
  free(t->sections);
  free(t->coords);
  for (karst_int_t i = 0; i < t->n_images; i++)
    free(t->images[i].v);
  free(t->images);
  free(t->warps);
  free(t->morphs);
  free(t->mix_areas);
  for (karst_int_t i = 0; i < t->n_details; i++)
    karst_i_details_free(&t->details[i]);
  free(t->details);
  free(t);
}

void karst_i_sdf_clear(karst_sdf_t *t) {
  for (int i = 0; i < t->n_terrains; i++) {
    free(t->terrains[i].z);
    free(t->terrains[i].path);
  }
  t->n_terrains = 0;
  t->n_nodes = t->n_kids = t->n_bvh = 0;
  t->n_sections = 0;
  t->n_coords = 0;
  for (karst_int_t i = 0; i < t->n_images; i++)
    free(t->images[i].v);
  t->n_images = t->n_warps = 0;
  t->n_morphs = t->n_mix_areas = 0;
  for (karst_int_t i = 0; i < t->n_details; i++)
    karst_i_details_free(&t->details[i]);
  t->n_details = 0;
  t->root = -1;
}

static karst_error_t new_node(karst_ctx_t *ctx, karst_sdf_t *t, karst_sdf_kind_t kind,
                              karst_i_node_t **nd, karst_int_t *id) {
  if (grow((void **)&t->nodes, &t->cap_nodes, t->n_nodes + 1, sizeof *t->nodes))
    return karst_set_error(ctx, KARST_ENOMEM, "construction tree: out of memory at %lld nodes",
                           (long long)t->n_nodes);
  *id = t->n_nodes++;
  *nd = &t->nodes[*id];
  memset(*nd, 0, sizeof **nd);
  (*nd)->kind = kind;
  (*nd)->label = KARST_SDF_NO_LABEL;
  return KARST_SUCCESS;
}

karst_error_t karst_i_sdf_new_node(karst_ctx_t *ctx, karst_sdf_t *t, karst_sdf_kind_t kind,
                                   karst_i_node_t **nd, karst_int_t *id) {
  return new_node(ctx, t, kind, nd, id);
}

int karst_i_grow(void **p, karst_int_t *cap, karst_int_t need, size_t size) {
  return grow(p, cap, need, size);
}

static void pad_box(double box[6]);
void karst_i_pad_box(double box[6]) {
  pad_box(box);
}

static void pad_box(double box[6]) {
  for (int a = 0; a < 3; a++) {
    double m = mx(fabs(box[a]), fabs(box[a + 3]));
    double pad = KARST_I_BOX_PAD_ABS + KARST_I_BOX_PAD_REL * m;
    box[a] -= pad;
    box[a + 3] += pad;
  }
}

static int finite3(const double *p) {
  return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

static karst_error_t check_node(karst_ctx_t *ctx, const karst_sdf_t *t, karst_int_t id,
                                const char *what) {
  if (id < 0 || id >= t->n_nodes)
    return karst_set_error(ctx, KARST_EINVAL, "%s: node %lld does not exist (tree has %lld)", what,
                           (long long)id, (long long)t->n_nodes);
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* Primitives.                                                             */
/* ---------------------------------------------------------------------- */

/**
 * Sphere primitive: exact signed distance |p - c| - r.
 * @param c centre, @param r radius > 0, @param label tunnel type (or -1)
 * @param node index of the new node
 * @return KARST_SUCCESS, KARST_EINVAL for a non-finite centre or r <= 0, KARST_ENOMEM.
 * Time complexity: O(1) amortised.
 */
karst_error_t karst_sdf_sphere(karst_ctx_t *ctx, karst_sdf_t *t, const double c[3], double r,
                               int label, karst_int_t *node) {
  if (!finite3(c))
    return karst_set_error(ctx, KARST_EINVAL, "sphere: centre (%g, %g, %g) is not finite", c[0],
                           c[1], c[2]);
  if (!(r > 0) || !isfinite(r))
    return karst_set_error(ctx, KARST_EINVAL, "sphere: radius %g must be > 0 and finite", r);
  karst_i_node_t *nd = NULL;
  karst_error_t err = new_node(ctx, t, KARST_SDF_SPHERE, &nd, node);
  if (err) return err;
  memcpy(nd->u.sphere.c, c, sizeof nd->u.sphere.c);
  nd->u.sphere.r = r;
  nd->label = label;
  nd->finite = 1;
  for (int a = 0; a < 3; a++) {
    nd->box[a] = c[a] - r;
    nd->box[a + 3] = c[a] + r;
  }
  pad_box(nd->box);
  return KARST_SUCCESS;
}

/**
 * Ellipsoid primitive with the 1-Lipschitz bound f = (|D^-1 R (p - c)| - 1) r_min:
 * the gradient of |D^-1 q| has norm at most 1/r_min, so scaling by r_min (the
 * "min-radius scaling") makes it 1-Lipschitz, and it vanishes exactly on the
 * ellipsoid. (The naive scaled sphere (|D^-1 q| - 1) r_max is not a bound.)
 * @param c centre; @param axes orthonormal axes (rows); @param radii semi-axes > 0
 * @return KARST_SUCCESS, KARST_EINVAL (non-finite, non-positive radii, axes not
 *         orthonormal within 1e-6), KARST_ENOMEM. Time complexity: O(1) amortised.
 */
karst_error_t karst_sdf_ellipsoid(karst_ctx_t *ctx, karst_sdf_t *t, const double c[3],
                                  const double axes[3][3], const double radii[3], int label,
                                  karst_int_t *node) {
  /* Tolerance on the orthonormality of the given axes (they are used as a rotation). */
  const double ortho_tol = 1e-6;
  if (!finite3(c))
    return karst_set_error(ctx, KARST_EINVAL, "ellipsoid: centre (%g, %g, %g) is not finite", c[0],
                           c[1], c[2]);
  for (int i = 0; i < 3; i++) {
    if (!(radii[i] > 0) || !isfinite(radii[i]))
      return karst_set_error(ctx, KARST_EINVAL, "ellipsoid: semi-axis %d is %g, must be > 0", i,
                             radii[i]);
    for (int j = 0; j < 3; j++) {
      double d = axes[i][0] * axes[j][0] + axes[i][1] * axes[j][1] + axes[i][2] * axes[j][2];
      if (!(fabs(d - (i == j)) <= ortho_tol))
        return karst_set_error(ctx, KARST_EINVAL,
                               "ellipsoid: axes %d and %d have dot product %g, expected %d", i, j,
                               d, i == j);
    }
  }
  karst_i_node_t *nd = NULL;
  karst_error_t err = new_node(ctx, t, KARST_SDF_ELLIPSOID, &nd, node);
  if (err) return err;
  memcpy(nd->u.ell.c, c, sizeof nd->u.ell.c);
  memcpy(nd->u.ell.axes, axes, sizeof nd->u.ell.axes);
  nd->u.ell.rmin = mn(radii[0], mn(radii[1], radii[2]));
  for (int i = 0; i < 3; i++)
    nd->u.ell.inv[i] = 1.0 / radii[i];
  nd->label = label;
  nd->finite = 1;
  for (int a = 0; a < 3; a++) {
    double e = 0;
    for (int j = 0; j < 3; j++)
      e += (axes[j][a] * radii[j]) * (axes[j][a] * radii[j]);
    e = sqrt(e);
    nd->box[a] = c[a] - e;
    nd->box[a + 3] = c[a] + e;
  }
  pad_box(nd->box);
  return KARST_SUCCESS;
}

karst_error_t karst_i_sdf_add_section(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_t *s,
                                      int *out) {
  for (int i = 0; i < t->n_sections; i++)
    if (memcmp(&t->sections[i], s, sizeof *s) == 0) {
      *out = i;
      return KARST_SUCCESS;
    }
  karst_int_t cap = t->cap_sections;
  if (grow((void **)&t->sections, &cap, t->n_sections + 1, sizeof *t->sections))
    return karst_set_error(ctx, KARST_ENOMEM, "construction tree: out of memory (sections)");
  t->cap_sections = (int)cap;
  t->sections[t->n_sections] = *s;
  *out = t->n_sections++;
  return KARST_SUCCESS;
}

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static int normalize3(double *v) {
  double n = sqrt(dot3(v, v));
  if (!(n > 0) || !isfinite(n)) return -1;
  v[0] /= n, v[1] /= n, v[2] /= n;
  return 0;
}

int karst_i_sweep_frame(const double u[3], const double up[3], double side[3], double upv[3]) {
  double hint[3] = {0, 0, 1};
  if (up) memcpy(hint, up, sizeof hint);
  if (fabs(dot3(hint, u)) > KARST_I_SWEEP_VERTICAL_COS * sqrt(dot3(hint, hint))) {
    hint[0] = 0, hint[1] = 1, hint[2] = 0;
    if (fabs(u[1]) > KARST_I_SWEEP_VERTICAL_COS) hint[0] = 1, hint[1] = 0;
  }
  double h = dot3(hint, u);
  for (int i = 0; i < 3; i++)
    upv[i] = hint[i] - h * u[i];
  if (normalize3(upv)) return -1;
  cross3(upv, u, side); /* (side, up, u) right-handed */
  return 0;
}

/**
 * Sweep primitive: a closed piecewise-quadratic section swept along a–b
 * (Paris et al. 2021, Appendix B). With w the in-plane signed distance to the
 * scaled section (Appendix C) and s the signed distance to the end slab along
 * u = (b - a)/|b - a|, the field is the exact extrusion distance
 *     min(max(w, s), 0) + |(max(w, 0), max(s, 0))|,
 * which is Appendix B's sqrt(s² + d²) outside and also correct inside; it is
 * 1-Lipschitz because ∇w ⟂ ∇s. A mitred end replaces its cap by the plane
 * n.(p - end) <= 0, combined by max (1-Lipschitz for any n).
 * @param a, b      segment ends (distinct)
 * @param section   unit section (checked), scaled by @p radius > 0
 * @param up        section up hint (world z when NULL)
 * @param ends      end treatment at a and b (NULL: flat caps)
 * @return KARST_SUCCESS, KARST_EINVAL (degenerate segment, bad section or
 *         mitre normal), KARST_ENOMEM. Time complexity: O(pieces).
 */
karst_error_t karst_sdf_sweep(karst_ctx_t *ctx, karst_sdf_t *t, const double a[3],
                              const double b[3], const karst_section_t *section, double radius,
                              const double up[3], const karst_sweep_end_t ends[2], int label,
                              karst_int_t *node) {
  if (!(radius > 0) || !isfinite(radius))
    return karst_set_error(ctx, KARST_EINVAL, "sweep: radius %g must be > 0 and finite", radius);
  karst_error_t err = karst_section_check(ctx, section);
  if (err) return err;
  int sec = 0;
  if ((err = karst_i_sdf_add_section(ctx, t, section, &sec))) return err;
  return karst_i_sweep_create(ctx, t, a, b, (const double(*)[2])section->cp, 2 * section->n, radius,
                              sec, 0, up, ends, label, node);
}

karst_error_t karst_i_sweep_create(karst_ctx_t *ctx, karst_sdf_t *t, const double a[3],
                                   const double b[3], const double (*cp)[2], int ncp, double radius,
                                   int section, int morph, const double up[3],
                                   const karst_sweep_end_t ends[2], int label, karst_int_t *node) {
  /* A mitre plane must cross the axis at an angle: |n . u| at least this. */
  const double min_mitre_cos = 0.1;
  if (!finite3(a) || !finite3(b))
    return karst_set_error(ctx, KARST_EINVAL, "sweep: end points are not finite");
  karst_error_t err = KARST_SUCCESS;
  karst_i_sweep_t sw;
  memset(&sw, 0, sizeof sw);
  memcpy(sw.a, a, sizeof sw.a);
  for (int i = 0; i < 3; i++)
    sw.u[i] = b[i] - a[i];
  sw.len = sqrt(dot3(sw.u, sw.u));
  if (normalize3(sw.u))
    return karst_set_error(ctx, KARST_EINVAL,
                           "sweep: segment (%g, %g, %g)-(%g, %g, %g) has zero length", a[0], a[1],
                           a[2], b[0], b[1], b[2]);
  if (karst_i_sweep_frame(sw.u, up, sw.side, sw.up))
    return karst_set_error(ctx, KARST_EINVAL, "sweep: up vector is not usable");
  sw.radius = radius;
  sw.section = section;
  sw.morph = morph;
  for (int e = 0; e < 2; e++) {
    if (!ends || !ends[e].mitre) continue;
    double n[3] = {ends[e].n[0], ends[e].n[1], ends[e].n[2]};
    if (normalize3(n))
      return karst_set_error(ctx, KARST_EINVAL, "sweep: mitre normal at end %d is zero", e);
    double c = dot3(n, sw.u) * (e == 0 ? -1 : 1);
    if (!(c >= min_mitre_cos))
      return karst_set_error(ctx, KARST_EINVAL,
                             "sweep: mitre normal at end %d makes cos %g with the outward axis, "
                             "must be >= %g",
                             e, c, min_mitre_cos);
    sw.mitre[e] = 1;
    memcpy(sw.n[e], n, sizeof n);
  }
  double rmax = 0;
  for (int i = 0; i < ncp; i++)
    rmax = mx(rmax, hypot(cp[i][0], cp[i][1]));
  sw.rho = rmax * radius;
  karst_i_node_t *nd = NULL;
  err = new_node(ctx, t, KARST_SDF_SWEEP, &nd, node);
  if (err) return err;
  nd->u.sweep = sw;
  nd->label = label;
  nd->finite = 1;
  /* Box: the solid lies in the prism over the convex hull of the scaled
   * control points, cut by the end planes; take the hull's cut points. */
  for (int i = 0; i < 3; i++)
    nd->box[i] = INFINITY, nd->box[i + 3] = -INFINITY;
  for (int i = 0; i < ncp; i++) {
    double o[3];
    for (int c = 0; c < 3; c++)
      o[c] = radius * (cp[i][0] * sw.side[c] + cp[i][1] * sw.up[c]);
    for (int e = 0; e < 2; e++) {
      double tt = e == 0 ? 0 : sw.len;
      if (sw.mitre[e]) tt -= dot3(sw.n[e], o) / dot3(sw.n[e], sw.u);
      for (int c = 0; c < 3; c++) {
        double x = a[c] + o[c] + tt * sw.u[c];
        nd->box[c] = mn(nd->box[c], x);
        nd->box[c + 3] = mx(nd->box[c + 3], x);
      }
    }
  }
  pad_box(nd->box);
  return KARST_SUCCESS;
}

/**
 * Revolved section cut to a wedge (the joint of a sharp bend); see implicit.h.
 * @return KARST_SUCCESS; KARST_EINVAL (non-unit or non-orthogonal frame, axis
 *         out of the section plane, bad section or radius); KARST_ENOMEM.
 * Time complexity: O(pieces).
 */
karst_error_t karst_sdf_revolve(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                const double axis[3], const double side[3], const double up[3],
                                const karst_section_t *section, double radius, const double n[2][3],
                                int label, karst_int_t *node) {
  return karst_i_revolve_offset(ctx, t, o, axis, side, up, section, radius, n, 0, label, node);
}

karst_error_t karst_i_revolve_offset(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                     const double axis[3], const double side[3], const double up[3],
                                     const karst_section_t *section, double radius,
                                     const double n[2][3], double offset, int label,
                                     karst_int_t *node) {
  if (!(radius > 0) || !isfinite(radius))
    return karst_set_error(ctx, KARST_EINVAL, "revolve: radius %g must be > 0 and finite", radius);
  karst_error_t err = karst_section_check(ctx, section);
  if (err) return err;
  int sec = 0;
  if ((err = karst_i_sdf_add_section(ctx, t, section, &sec))) return err;
  return karst_i_revolve_create(ctx, t, o, axis, side, up, (const double(*)[2])section->cp,
                                2 * section->n, radius, sec, 0, n, offset, label, node);
}

karst_error_t karst_i_revolve_create(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                     const double axis[3], const double side[3], const double up[3],
                                     const double (*cp)[2], int ncp, double radius, int section,
                                     int morph, const double n[2][3], double offset, int label,
                                     karst_int_t *node) {
  /* Tolerance on the unit length and orthogonality of the given vectors. */
  const double tol = 1e-6;
  if (!finite3(o) || !finite3(axis) || !finite3(side) || !finite3(up))
    return karst_set_error(ctx, KARST_EINVAL, "revolve: origin or frame is not finite");
  karst_error_t err = KARST_SUCCESS;
  const double *vs[5] = {axis, side, up, n[0], n[1]};
  for (int i = 0; i < 5; i++)
    if (!(fabs(dot3(vs[i], vs[i]) - 1) <= tol))
      return karst_set_error(ctx, KARST_EINVAL, "revolve: vector %d has length %g, must be 1", i,
                             sqrt(dot3(vs[i], vs[i])));
  double pn[3];
  cross3(side, up, pn);
  if (!(fabs(dot3(side, up)) <= tol) || !(fabs(dot3(axis, pn)) <= tol))
    return karst_set_error(ctx, KARST_EINVAL,
                           "revolve: side.up = %g and axis.normal = %g, both must be 0",
                           dot3(side, up), dot3(axis, pn));
  karst_i_revolve_t rv;
  memset(&rv, 0, sizeof rv);
  memcpy(rv.o, o, sizeof rv.o);
  memcpy(rv.axis, axis, sizeof rv.axis);
  memcpy(rv.n, n, sizeof rv.n);
  double x[3];
  cross3(axis, pn, x); /* in the plane, perpendicular to the axis */
  rv.sx[0] = dot3(x, side), rv.sx[1] = dot3(x, up);
  rv.sz[0] = dot3(axis, side), rv.sz[1] = dot3(axis, up);
  rv.radius = radius;
  rv.section = section;
  rv.morph = morph;
  rv.offset = offset;
  double rmax = 0;
  for (int i = 0; i < ncp; i++)
    rmax = mx(rmax, hypot(cp[i][0], cp[i][1]));
  rv.rho = rmax * radius;
  karst_i_node_t *nd = NULL;
  if ((err = new_node(ctx, t, KARST_SDF_REVOLVE, &nd, node))) return err;
  nd->u.rev = rv;
  nd->label = label;
  nd->finite = 1;
  for (int a = 0; a < 3; a++) {
    nd->box[a] = o[a] - rv.rho;
    nd->box[a + 3] = o[a] + rv.rho;
  }
  pad_box(nd->box);
  return KARST_SUCCESS;
}

/**
 * Terrain primitive (Paris et al. 2021, §6.1 and Appendix A):
 * f = (z - h(x, y)) / sqrt(1 + λ²), negative in the bedrock. λ is the larger of
 * t->lipschitz and the maximum slope of the bilinear surface, computed here:
 * on each cell |∇h|² is a convex function of (x, y) (each partial derivative is
 * affine in the other coordinate), so its maximum is at a cell corner.
 * @param t a flat or grid terrain (copied)
 * @return KARST_SUCCESS, KARST_EINVAL (non-finite values, bad grid), KARST_ENOMEM.
 * Time complexity: O(grid cells).
 */
karst_error_t karst_sdf_terrain(karst_ctx_t *ctx, karst_sdf_t *sdf, const karst_terrain_t *t,
                                karst_int_t *node) {
  karst_terrain_t c;
  memset(&c, 0, sizeof c);
  double lambda = 0;
  if (!t) return karst_set_error(ctx, KARST_EINVAL, "terrain: none given");
  if (t->is_grid) {
    if (t->ncols < 1 || t->nrows < 1 || !t->z || !(t->cellsize > 0))
      return karst_set_error(ctx, KARST_EINVAL,
                             "terrain: grid of %lld x %lld cells of size %g is not usable",
                             (long long)t->ncols, (long long)t->nrows, t->cellsize);
    size_t n = (size_t)t->ncols * (size_t)t->nrows;
    for (size_t i = 0; i < n; i++)
      if (!isfinite(t->z[i]))
        return karst_set_error(ctx, KARST_EINVAL, "terrain: elevation %zu (row %lld) is %g", i,
                               (long long)(i / (size_t)t->ncols), t->z[i]);
    for (karst_int_t j = 0; j + 1 < t->nrows; j++)
      for (karst_int_t i = 0; i + 1 < t->ncols; i++) {
        const double *z = t->z;
        double z00 = z[j * t->ncols + i], z10 = z[j * t->ncols + i + 1];
        double z01 = z[(j + 1) * t->ncols + i], z11 = z[(j + 1) * t->ncols + i + 1];
        double gx0 = (z10 - z00) / t->cellsize, gx1 = (z11 - z01) / t->cellsize;
        double gy0 = (z01 - z00) / t->cellsize, gy1 = (z11 - z10) / t->cellsize;
        double g2 = mx(mx(gx0 * gx0 + gy0 * gy0, gx0 * gx0 + gy1 * gy1),
                       mx(gx1 * gx1 + gy0 * gy0, gx1 * gx1 + gy1 * gy1));
        lambda = mx(lambda, sqrt(g2));
      }
    /* One-row or one-column grids are linear along their only direction. */
    if (t->nrows == 1 || t->ncols == 1) {
      size_t m = (size_t)(t->nrows == 1 ? t->ncols : t->nrows);
      for (size_t i = 0; i + 1 < m; i++)
        lambda = mx(lambda, fabs(t->z[i + 1] - t->z[i]) / t->cellsize);
    }
    c = *t;
    c.path = NULL;
    c.z = malloc(n * sizeof *c.z);
    if (!c.z) return karst_set_error(ctx, KARST_ENOMEM, "terrain: out of memory");
    memcpy(c.z, t->z, n * sizeof *c.z);
  } else {
    if (!isfinite(t->elevation))
      return karst_set_error(ctx, KARST_EINVAL, "terrain: elevation %g is not finite",
                             t->elevation);
    c = *t;
    c.path = NULL;
    c.z = NULL;
  }
  if (isfinite(t->lipschitz) && t->lipschitz > lambda) lambda = t->lipschitz;
  c.lipschitz = lambda;
  karst_int_t cap = sdf->cap_terrains;
  if (grow((void **)&sdf->terrains, &cap, sdf->n_terrains + 1, sizeof *sdf->terrains)) {
    free(c.z);
    return karst_set_error(ctx, KARST_ENOMEM, "terrain: out of memory");
  }
  sdf->cap_terrains = (int)cap;
  karst_i_node_t *nd = NULL;
  karst_error_t err = new_node(ctx, sdf, KARST_SDF_TERRAIN, &nd, node);
  if (err) {
    free(c.z);
    return err;
  }
  sdf->terrains[sdf->n_terrains] = c;
  nd->u.terrain.index = sdf->n_terrains++;
  nd->u.terrain.inv_norm = 1.0 / sqrt(1.0 + lambda * lambda);
  nd->finite = 0;
  return KARST_SUCCESS;
}

/**
 * Axis-aligned box primitive (exact signed distance).
 * @return KARST_SUCCESS, KARST_EINVAL when not finite or lo >= hi on an axis.
 * Time complexity: O(1) amortised.
 */
karst_error_t karst_sdf_box(karst_ctx_t *ctx, karst_sdf_t *t, const double lo[3],
                            const double hi[3], karst_int_t *node) {
  for (int a = 0; a < 3; a++)
    if (!isfinite(lo[a]) || !isfinite(hi[a]) || !(lo[a] < hi[a]))
      return karst_set_error(ctx, KARST_EINVAL, "box: axis %d has bounds [%g, %g]", a, lo[a],
                             hi[a]);
  karst_i_node_t *nd = NULL;
  karst_error_t err = new_node(ctx, t, KARST_SDF_BOX, &nd, node);
  if (err) return err;
  memcpy(nd->u.box.lo, lo, sizeof nd->u.box.lo);
  memcpy(nd->u.box.hi, hi, sizeof nd->u.box.hi);
  nd->finite = 1;
  memcpy(nd->box, lo, 3 * sizeof *lo);
  memcpy(nd->box + 3, hi, 3 * sizeof *hi);
  pad_box(nd->box);
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* Operators.                                                              */
/* ---------------------------------------------------------------------- */

typedef struct {
  double c; /* centroid along the split axis */
  karst_int_t id;
} sort_item_t;

static int cmp_item(const void *a, const void *b) {
  const sort_item_t *x = a, *y = b;
  if (x->c < y->c) return -1;
  if (x->c > y->c) return 1;
  return (x->id > y->id) - (x->id < y->id); /* deterministic order */
}

/* Leaves of the hierarchy hold at most this many children. */
#define BVH_LEAF_SIZE 4

/* Build the hierarchy over kids[first .. first+n) (reordered in place), by
 * median split of the centroids along the longest axis of their box. */
static karst_error_t bvh_build(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t first, karst_int_t n,
                               sort_item_t *tmp, karst_int_t *out) {
  if (grow((void **)&t->bvh, &t->cap_bvh, t->n_bvh + 1, sizeof *t->bvh))
    return karst_set_error(ctx, KARST_ENOMEM, "hierarchy: out of memory");
  karst_int_t me = t->n_bvh++;
  double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
  double cb[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
  for (karst_int_t i = 0; i < n; i++) {
    const double *b = t->nodes[t->kids[first + i]].box;
    for (int a = 0; a < 3; a++) {
      box[a] = mn(box[a], b[a]);
      box[a + 3] = mx(box[a + 3], b[a + 3]);
      double c = 0.5 * (b[a] + b[a + 3]);
      cb[a] = mn(cb[a], c);
      cb[a + 3] = mx(cb[a + 3], c);
    }
  }
  memcpy(t->bvh[me].box, box, sizeof box);
  if (n <= BVH_LEAF_SIZE) {
    t->bvh[me].a = first;
    t->bvh[me].b = -1;
    t->bvh[me].n = (int)n;
    *out = me;
    return KARST_SUCCESS;
  }
  int axis = 0;
  for (int a = 1; a < 3; a++)
    if (cb[a + 3] - cb[a] > cb[axis + 3] - cb[axis]) axis = a;
  for (karst_int_t i = 0; i < n; i++) {
    const double *b = t->nodes[t->kids[first + i]].box;
    tmp[i].c = 0.5 * (b[axis] + b[axis + 3]);
    tmp[i].id = t->kids[first + i];
  }
  qsort(tmp, (size_t)n, sizeof *tmp, cmp_item);
  for (karst_int_t i = 0; i < n; i++)
    t->kids[first + i] = tmp[i].id;
  karst_int_t half = n / 2, l, r;
  karst_error_t err = bvh_build(ctx, t, first, half, tmp, &l);
  if (!err) err = bvh_build(ctx, t, first + half, n - half, tmp, &r);
  if (err) return err;
  t->bvh[me].a = l;
  t->bvh[me].b = r;
  t->bvh[me].n = 0;
  *out = me;
  return KARST_SUCCESS;
}

/**
 * Union (minimum) of @p n children, with a bounding-volume hierarchy over the
 * children with finite boxes (median split on the longest axis, leaves of at
 * most 4). An evaluation visits only hierarchy nodes whose box distance is
 * below the best value found so far; the box distance is a valid lower bound
 * because every node is clamped from below by the distance to its box.
 * @return KARST_SUCCESS, KARST_EINVAL (n < 1, unknown child), KARST_ENOMEM; on
 *         failure the tree is left as it was.
 * Time complexity: O(n log² n) to build.
 */
karst_error_t karst_sdf_union(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t n,
                              const karst_int_t *children, karst_int_t *node) {
  karst_error_t err = KARST_SUCCESS;
  sort_item_t *tmp = NULL;
  karst_int_t saved_kids = t->n_kids, saved_bvh = t->n_bvh, saved_nodes = t->n_nodes;
  if (n < 1)
    return karst_set_error(ctx, KARST_EINVAL, "union: %lld children, need >= 1", (long long)n);
  for (karst_int_t i = 0; i < n; i++)
    if ((err = check_node(ctx, t, children[i], "union"))) return err;
  if (grow((void **)&t->kids, &t->cap_kids, t->n_kids + n, sizeof *t->kids)) {
    err =
        karst_set_error(ctx, KARST_ENOMEM, "union: out of memory for %lld children", (long long)n);
    goto cleanup;
  }
  karst_int_t first = t->n_kids, nf = 0;
  for (karst_int_t i = 0; i < n; i++)
    if (t->nodes[children[i]].finite) t->kids[first + nf++] = children[i];
  karst_int_t inf_first = first + nf, ni = 0;
  for (karst_int_t i = 0; i < n; i++)
    if (!t->nodes[children[i]].finite) t->kids[inf_first + ni++] = children[i];
  t->n_kids += n;
  karst_int_t root = -1;
  if (nf > 0) {
    tmp = malloc((size_t)nf * sizeof *tmp);
    if (!tmp) {
      err = karst_set_error(ctx, KARST_ENOMEM, "union: out of memory");
      goto cleanup;
    }
    if ((err = bvh_build(ctx, t, first, nf, tmp, &root))) goto cleanup;
  }
  karst_i_node_t *nd = NULL;
  if ((err = new_node(ctx, t, KARST_SDF_UNION, &nd, node))) goto cleanup;
  nd->u.uni.first = first;
  nd->u.uni.n = nf;
  nd->u.uni.inf_first = inf_first;
  nd->u.uni.n_inf = ni;
  nd->u.uni.bvh_root = root;
  nd->finite = ni == 0;
  if (nd->finite) memcpy(nd->box, t->bvh[root].box, sizeof nd->box);
cleanup:
  free(tmp);
  if (err) {
    t->n_kids = saved_kids;
    t->n_bvh = saved_bvh;
    t->n_nodes = saved_nodes;
  }
  return err;
}

static karst_error_t binary(karst_ctx_t *ctx, karst_sdf_t *t, karst_sdf_kind_t kind, karst_int_t a,
                            karst_int_t b, double k, karst_int_t *node, const char *what) {
  karst_error_t err = check_node(ctx, t, a, what);
  if (!err) err = check_node(ctx, t, b, what);
  if (err) return err;
  karst_i_node_t *nd = NULL;
  if ((err = new_node(ctx, t, kind, &nd, node))) return err;
  nd->u.bin.a = a;
  nd->u.bin.b = b;
  nd->u.bin.k = k;
  const karst_i_node_t *na = &t->nodes[a], *nb = &t->nodes[b];
  switch (kind) {
  case KARST_SDF_INTERSECTION: /* inside both boxes */
    if (na->finite && nb->finite) {
      nd->finite = 1;
      for (int i = 0; i < 3; i++) {
        nd->box[i] = mx(na->box[i], nb->box[i]);
        nd->box[i + 3] = mn(na->box[i + 3], nb->box[i + 3]);
        if (nd->box[i] > nd->box[i + 3]) nd->box[i + 3] = nd->box[i]; /* empty: a point */
      }
    } else if (na->finite || nb->finite) {
      nd->finite = 1;
      memcpy(nd->box, na->finite ? na->box : nb->box, sizeof nd->box);
    }
    break;
  case KARST_SDF_DIFFERENCE: /* inside a's box */
    nd->finite = na->finite;
    memcpy(nd->box, na->box, sizeof nd->box);
    break;
  case KARST_SDF_BLEND:
    /* smin >= min(a, b) - k/4 >= sdbox(union box) - k/4: the solid lies in the
     * union of the boxes grown by k/4. */
    nd->finite = na->finite && nb->finite;
    for (int i = 0; i < 3; i++) {
      nd->box[i] = mn(na->box[i], nb->box[i]) - 0.25 * k;
      nd->box[i + 3] = mx(na->box[i + 3], nb->box[i + 3]) + 0.25 * k;
    }
    if (nd->finite) pad_box(nd->box);
    break;
  default:
    break;
  }
  return KARST_SUCCESS;
}

/** Intersection max(a, b) (1-Lipschitz as a max of 1-Lipschitz fields). O(1) amortised. */
karst_error_t karst_sdf_intersection(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t a, karst_int_t b,
                                     karst_int_t *node) {
  return binary(ctx, t, KARST_SDF_INTERSECTION, a, b, 0, node, "intersection");
}

/** Difference a minus b, max(a, -b): "terrain minus conduits" (§6). O(1) amortised. */
karst_error_t karst_sdf_difference(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t a, karst_int_t b,
                                   karst_int_t *node) {
  return binary(ctx, t, KARST_SDF_DIFFERENCE, a, b, 0, node, "difference");
}

/**
 * Smooth blend: the polynomial smooth minimum min(a, b) - k h²/4 with
 * h = max(k - |a - b|, 0)/k. Its gradient is λ∇a + (1-λ)∇b with
 * λ = clamp(1/2 + (b - a)/(2k), 0, 1), a convex combination, so the blend is
 * 1-Lipschitz when a and b are. @param k blend width > 0 (m). O(1) amortised.
 */
karst_error_t karst_sdf_blend(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t a, karst_int_t b,
                              double k, karst_int_t *node) {
  if (!(k > 0) || !isfinite(k))
    return karst_set_error(ctx, KARST_EINVAL, "blend: width %g must be > 0 and finite", k);
  return binary(ctx, t, KARST_SDF_BLEND, a, b, k, node, "blend");
}

/**
 * Noise displacement keeping the bound (§6, Zanni et al. 2012):
 * f' = (f + A n) / (1 + A Ln) with |n| <= 1 and Ln the Lipschitz constant of n
 * (noise.c). The kernel window radius equals the wavelength.
 * @param amplitude A >= 0 (m); @param wavelength λ > 0 (m)
 * @param rng draws the seed of the impulses
 * Time complexity: O(1) amortised.
 */
karst_error_t karst_sdf_noise(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child, double amplitude,
                              double wavelength, karst_rng_t *rng, karst_int_t *node) {
  karst_error_t err = check_node(ctx, t, child, "noise");
  if (err) return err;
  if (!(amplitude >= 0) || !isfinite(amplitude))
    return karst_set_error(ctx, KARST_EINVAL, "noise: amplitude %g must be >= 0 and finite",
                           amplitude);
  if (!(wavelength > 0) || !isfinite(wavelength))
    return karst_set_error(ctx, KARST_EINVAL, "noise: wavelength %g must be > 0 and finite",
                           wavelength);
  if (!rng) return karst_set_error(ctx, KARST_EINVAL, "noise: no random generator given");
  karst_i_node_t *nd = NULL;
  if ((err = new_node(ctx, t, KARST_SDF_NOISE, &nd, node))) return err;
  const karst_i_node_t *c = &t->nodes[child];
  nd->u.noise.child = child;
  nd->u.noise.amplitude = amplitude;
  nd->u.noise.wavelength = wavelength;
  nd->u.noise.kradius = wavelength;
  nd->u.noise.lipschitz = karst_i_noise_lipschitz(wavelength, wavelength);
  nd->u.noise.seed = karst_rng_u64(rng);
  nd->label = c->label;
  /* f' <= 0 needs f <= A, and f >= sdbox(child box): grow the box by A. */
  nd->finite = c->finite;
  for (int i = 0; i < 3; i++) {
    nd->box[i] = c->box[i] - amplitude;
    nd->box[i + 3] = c->box[i + 3] + amplitude;
  }
  if (nd->finite) pad_box(nd->box);
  return KARST_SUCCESS;
}

/** Set the root node. O(1). */
karst_error_t karst_sdf_set_root(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t node) {
  karst_error_t err = check_node(ctx, t, node, "root");
  if (err) return err;
  t->root = node;
  return KARST_SUCCESS;
}

karst_int_t karst_sdf_root(const karst_sdf_t *t) {
  return t ? t->root : -1;
}

void karst_sdf_node_box(const karst_sdf_t *t, karst_int_t node, double box[6]) {
  const karst_i_node_t *nd = &t->nodes[node];
  if (nd->finite) {
    memcpy(box, nd->box, 6 * sizeof *box);
  } else {
    for (int i = 0; i < 3; i++)
      box[i] = -INFINITY, box[i + 3] = INFINITY;
  }
}

/* ---------------------------------------------------------------------- */
/* Evaluation.                                                             */
/* ---------------------------------------------------------------------- */

static inline double sdbox(const double box[6], const double p[3]) {
  double out = 0, in = -INFINITY;
  for (int a = 0; a < 3; a++) {
    double q = mx(box[a] - p[a], p[a] - box[a + 3]);
    if (q > 0) out += q * q;
    if (q > in) in = q;
  }
  return sqrt(out) + mn(in, 0.0);
}

double karst_i_sdbox(const double box[6], const double p[3]) {
  return sdbox(box, p);
}

/* 1 only when sdbox(box, p) >= best, without the square root for best > 0: p outside the box
 * with squared distance above best² (1 + 1e-12), so that sqrt rounds to >= best; the boxes it
 * skips are a subset of those the exact test skips, and the skipped ones cannot hold a value
 * below best, so a union's value and label are the exact test's (the BVH culling of
 * eval_union). */
static inline int box_beyond(const double box[6], const double p[3], double best) {
  if (!(best > 0)) return sdbox(box, p) >= best;
  double out = 0;
  for (int a = 0; a < 3; a++) {
    double q = mx(box[a] - p[a], p[a] - box[a + 3]);
    if (q > 0) out += q * q;
  }
  return out > best * best * (1 + 1e-12);
}

/* Exact extrusion combination of an in-plane distance w and a slab distance s. */
static double extrude(double w, double s) {
  double wp = mx(w, 0), sp = mx(s, 0);
  return mn(mx(w, s), 0.0) + sqrt(wp * wp + sp * sp);
}

static double eval_sweep(const karst_sdf_t *t, const karst_i_sweep_t *sw, const double p[3],
                         double ub) {
  double d[3] = {p[0] - sw->a[0], p[1] - sw->a[1], p[2] - sw->a[2]};
  double l = dot3(d, sw->u), x = dot3(d, sw->side), y = dot3(d, sw->up);
  double s_flat = -INFINITY, s_mitre = -INFINITY;
  if (sw->mitre[0])
    s_mitre = dot3(d, sw->n[0]);
  else
    s_flat = -l;
  if (sw->mitre[1]) {
    double e[3] = {d[0] - sw->len * sw->u[0], d[1] - sw->len * sw->u[1], d[2] - sw->len * sw->u[2]};
    s_mitre = mx(s_mitre, dot3(e, sw->n[1]));
  } else {
    s_flat = mx(s_flat, l - sw->len);
  }
  /* Lower bound first: the section lies in the disc of radius rho, so
   * w >= hypot(x, y) - rho, and the combination is non-decreasing in w. */
  double wlo = sqrt(x * x + y * y) - sw->rho;
  /* a morphing section's field is divided by its Lipschitz factor (morph.c) */
  double k = sw->morph ? t->morphs[sw->morph - 1].k : 1.0;
  double lo = (s_flat == -INFINITY ? wlo : extrude(wlo, s_flat)) / k;
  lo = mx(lo, s_mitre);
  if (lo >= ub) return lo;
  double w;
  if (sw->morph) {
    w = karst_i_morph_sweep_w(t, &t->morphs[sw->morph - 1], l, x, y);
  } else {
    double q[2] = {x / sw->radius, y / sw->radius};
    w = sw->radius * karst_section_distance(&t->sections[sw->section], q);
  }
  double f = (s_flat == -INFINITY ? w : extrude(w, s_flat)) / k;
  return mx(f, s_mitre);
}

static double eval_revolve(const karst_sdf_t *t, const karst_i_revolve_t *rv, const double p[3],
                           double ub) {
  double v[3] = {p[0] - rv->o[0], p[1] - rv->o[1], p[2] - rv->o[2]};
  double z = dot3(v, rv->axis);
  double vp[3] = {v[0] - z * rv->axis[0], v[1] - z * rv->axis[1], v[2] - z * rv->axis[2]};
  double r = sqrt(dot3(vp, vp));
  double s = mx(dot3(v, rv->n[0]), dot3(v, rv->n[1])) - rv->offset;
  double lo = mx(sqrt(r * r + z * z) - rv->rho, s); /* the section lies in the disc of radius rho */
  if (lo >= ub) return lo;
  const karst_section_t *sec = &t->sections[rv->section];
  double q1[2] = {(r * rv->sx[0] + z * rv->sz[0]) / rv->radius,
                  (r * rv->sx[1] + z * rv->sz[1]) / rv->radius};
  double q2[2] = {(-r * rv->sx[0] + z * rv->sz[0]) / rv->radius,
                  (-r * rv->sx[1] + z * rv->sz[1]) / rv->radius};
  double w;
  if (rv->morph) {
    const karst_i_morph_t *m = &t->morphs[rv->morph - 1];
    w = rv->radius * mn(karst_i_morph_mix_w(t, m, m->wa, q1), karst_i_morph_mix_w(t, m, m->wa, q2));
  } else {
    w = rv->radius * mn(karst_section_distance(sec, q1), karst_section_distance(sec, q2));
  }
  return mx(w, s);
}

static double eval_union(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                         double ub, int *label, karst_int_t *touched) {
  double best = ub;
  int lab = KARST_SDF_NO_LABEL;
  for (karst_int_t i = 0; i < nd->u.uni.n_inf; i++) {
    int l;
    double v = karst_i_sdf_eval(t, t->kids[nd->u.uni.inf_first + i], p, best, &l, touched);
    if (v < best) best = v, lab = l;
  }
  if (nd->u.uni.bvh_root >= 0) {
    karst_int_t stack[128];
    int top = 0;
    stack[top++] = nd->u.uni.bvh_root;
    while (top > 0) {
      const karst_i_bvh_t *b = &t->bvh[stack[--top]];
      if (box_beyond(b->box, p, best)) continue;
      if (touched) (*touched)++;
      if (b->n > 0) {
        for (int k = 0; k < b->n; k++) {
          karst_int_t c = t->kids[b->a + k];
          if (box_beyond(t->nodes[c].box, p, best)) continue;
          int l;
          double v = karst_i_sdf_eval(t, c, p, best, &l, touched);
          if (v < best) best = v, lab = l;
        }
      } else if (top + 2 <= (int)(sizeof stack / sizeof *stack)) {
        /* nearer child last so it is visited first */
        double da = sdbox(t->bvh[b->a].box, p), db = sdbox(t->bvh[b->b].box, p);
        if (da <= db) {
          stack[top++] = b->b;
          stack[top++] = b->a;
        } else {
          stack[top++] = b->a;
          stack[top++] = b->b;
        }
      }
    }
  }
  if (label) *label = lab;
  return best;
}

double karst_i_sdf_eval(const karst_sdf_t *t, karst_int_t id, const double p[3], double ub,
                        int *label, karst_int_t *touched) {
  const karst_i_node_t *nd = &t->nodes[id];
  double v;
  int lab = nd->label;
  switch (nd->kind) {
  case KARST_SDF_SPHERE: {
    const double *c = nd->u.sphere.c;
    v = sqrt((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
             (p[2] - c[2]) * (p[2] - c[2])) -
        nd->u.sphere.r;
    break;
  }
  case KARST_SDF_ELLIPSOID: {
    double d[3] = {p[0] - nd->u.ell.c[0], p[1] - nd->u.ell.c[1], p[2] - nd->u.ell.c[2]};
    double g = 0;
    for (int i = 0; i < 3; i++) {
      double q = dot3(nd->u.ell.axes[i], d) * nd->u.ell.inv[i];
      g += q * q;
    }
    v = (sqrt(g) - 1.0) * nd->u.ell.rmin;
    break;
  }
  case KARST_SDF_SWEEP:
    v = eval_sweep(t, &nd->u.sweep, p, ub);
    break;
  case KARST_SDF_REVOLVE:
    v = eval_revolve(t, &nd->u.rev, p, ub);
    break;
  case KARST_SDF_TERRAIN: {
    const karst_terrain_t *tr = &t->terrains[nd->u.terrain.index];
    v = (p[2] - karst_terrain_height(tr, p[0], p[1])) * nd->u.terrain.inv_norm;
    break;
  }
  case KARST_SDF_BOX: {
    double b[6];
    memcpy(b, nd->u.box.lo, 3 * sizeof *b);
    memcpy(b + 3, nd->u.box.hi, 3 * sizeof *b);
    v = karst_i_sdbox(b, p);
    break;
  }
  case KARST_SDF_UNION:
    v = eval_union(t, nd, p, ub, &lab, touched);
    break;
  case KARST_SDF_INTERSECTION: {
    int la, lb;
    double a = karst_i_sdf_eval(t, nd->u.bin.a, p, INFINITY, &la, touched);
    double b = karst_i_sdf_eval(t, nd->u.bin.b, p, INFINITY, &lb, touched);
    v = a >= b ? a : b;
    lab = a >= b ? la : lb;
    break;
  }
  case KARST_SDF_DIFFERENCE: {
    /* max(a, -b) >= a: a at or above ub decides; else b is needed exactly
     * only when -b > a, that is below -a */
    int la, lb;
    double a = karst_i_sdf_eval(t, nd->u.bin.a, p, ub, &la, touched);
    if (a >= ub) {
      v = a, lab = la;
      break;
    }
    double b = -karst_i_sdf_eval(t, nd->u.bin.b, p, -a, &lb, touched);
    v = a >= b ? a : b;
    lab = a >= b ? la : lb;
    break;
  }
  case KARST_SDF_BLEND: {
    /* smin(a, b) >= min(a, b) - k/4, and equals min(a, b) when |a - b| >= k:
     * each child is needed exactly only below ub + k/4, and then the other
     * only within k of it */
    int la, lb;
    double k = nd->u.bin.k, ua = isfinite(ub) ? ub + 0.25 * k : INFINITY;
    double a = karst_i_sdf_eval(t, nd->u.bin.a, p, ua, &la, touched), b;
    if (a >= ua) {
      b = karst_i_sdf_eval(t, nd->u.bin.b, p, ua, &lb, touched);
      if (b >= ua) {
        v = mx(mn(a, b) - 0.25 * k, ub), lab = a <= b ? la : lb; /* >= ub */
        break;
      }
      a = karst_i_sdf_eval(t, nd->u.bin.a, p, b + k, &la, touched);
    } else {
      b = karst_i_sdf_eval(t, nd->u.bin.b, p, a + k, &lb, touched);
    }
    double h = mx(k - fabs(a - b), 0.0) / k;
    v = mn(a, b) - 0.25 * k * h * h;
    lab = a <= b ? la : lb;
    break;
  }
  case KARST_SDF_PLANE:
    v = dot3(nd->u.plane.u, p) - nd->u.plane.d;
    break;
  case KARST_SDF_SMOOTH_INTERSECTION:
    v = karst_i_eval_smooth_intersection(t, nd, p, ub, &lab, touched);
    break;
  case KARST_SDF_THICK:
    v = karst_i_eval_thick(t, nd, p);
    break;
  case KARST_SDF_EXTERNAL:
    v = nd->u.ext.fn(nd->u.ext.arg, p, ub, &lab);
    break;
  case KARST_SDF_NOISE: {
    const karst_i_noise_t *nz = &nd->u.noise;
    double scale = 1.0 + nz->amplitude * nz->lipschitz;
    /* f' < ub needs f < ub scale + A: pass that bound down. */
    double cub = isfinite(ub) ? ub * scale + nz->amplitude : INFINITY;
    double f = karst_i_sdf_eval(t, nz->child, p, cub, &lab, touched);
    if (f >= cub) {
      v = mx((f - nz->amplitude) / scale, ub); /* >= ub, a valid answer under the contract */
    } else {
      v = (f + nz->amplitude * karst_i_noise_eval(nz, p)) / scale;
    }
    break;
  }
  case KARST_SDF_WARP:
    v = karst_i_warp_eval(t, nd, p, ub, &lab, touched);
    break;
  case KARST_SDF_DETAILS:
    v = karst_i_details_eval(t, nd, p, ub, &lab, touched);
    break;
  case KARST_SDF_ROUND_CONE:
    v = karst_i_round_cone_eval(nd, p);
    break;
  case KARST_SDF_RESCALE:
    v = karst_i_rescale_eval(t, nd, p, ub, &lab, touched);
    break;
  default:
    v = INFINITY;
    break;
  }
  if (nd->finite) {
    double bl = sdbox(nd->box, p);
    if (bl > v) v = bl; /* clamp: the solid lies inside the box */
  }
  if (label) *label = lab;
  return v;
}

/**
 * Field of node @p node at @p p (see karst_sdf_eval).
 * @param label   receives the deciding primitive's label (may be NULL)
 * @param touched increased by the number of hierarchy nodes visited (may be NULL)
 * Time complexity: O(log n) for well-separated primitives, O(n) worst case.
 */
double karst_sdf_eval_node(const karst_sdf_t *t, karst_int_t node, const double p[3], int *label,
                           karst_int_t *touched) {
  if (!t || node < 0 || node >= t->n_nodes) {
    if (label) *label = KARST_SDF_NO_LABEL;
    return INFINITY;
  }
  return karst_i_sdf_eval(t, node, p, INFINITY, label, touched);
}

/**
 * Field of the root at @p p (+infinity for an empty tree). Thread-safe.
 * Time complexity: as karst_sdf_eval_node.
 */
double karst_sdf_eval(const karst_sdf_t *t, const double p[3], int *label) {
  return karst_sdf_eval_node(t, t ? t->root : -1, p, label, NULL);
}

/** Size and memory of a tree. O(nodes). */
void karst_sdf_stats(const karst_sdf_t *t, karst_sdf_stats_t *st) {
  memset(st, 0, sizeof *st);
  if (!t) return;
  st->n_nodes = t->n_nodes;
  for (karst_int_t i = 0; i < t->n_nodes; i++)
    st->by_kind[t->nodes[i].kind]++;
  st->n_bvh_nodes = t->n_bvh;
  st->memory_bytes =
      sizeof *t + (size_t)t->n_nodes * sizeof *t->nodes + (size_t)t->n_kids * sizeof *t->kids +
      (size_t)t->n_bvh * sizeof *t->bvh + (size_t)t->n_sections * sizeof *t->sections +
      (size_t)t->n_coords * sizeof *t->coords + (size_t)t->n_terrains * sizeof *t->terrains +
      (size_t)t->n_warps * sizeof *t->warps;
  for (karst_int_t i = 0; i < t->n_images; i++)
    st->memory_bytes += (size_t)t->images[i].w * (size_t)t->images[i].h * sizeof(float);
  for (int i = 0; i < t->n_terrains; i++)
    if (t->terrains[i].z)
      st->memory_bytes +=
          (size_t)t->terrains[i].ncols * (size_t)t->terrains[i].nrows * sizeof(double);
}
