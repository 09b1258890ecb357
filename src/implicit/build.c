/* From a classified network to the construction tree of its conduits
 * (Paris et al. 2021, §6.2): sweeps along straight edges, mitred at gentle
 * joints; at sharp bends the sections revolved about the bend axis, or
 * unions of Poisson spheres selected by their distance to interpolated
 * cross-sections (the paper's method, par->bend_spheres); balls at junctions;
 * ellipsoids for breakout chambers; optional wall noise; terrain minus
 * conduits. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "implicit/implicit_internal.h"
#include "karst/geology.h"

/* Poisson disk sampling tries this many candidates around each active sample
 * before retiring it (Bridson 2007, k = 30). */
#define POISSON_TRIES 30
/* Largest background grid (cells) of one bend's Poisson sampling. */
#define POISSON_MAX_CELLS (1 << 24)

/**
 * Documented defaults of the geometry stage (see implicit.h). O(1).
 */
void karst_implicit_params_init(karst_implicit_params_t *par) {
  memset(par, 0, sizeof *par);
  par->default_radius = 1.0;
  par->mitre_max_angle = 60.0;
  par->sphere_radius = 0.2;
  par->sphere_rel = 0.25;
  par->chamber_height = 0.6;
  par->noise_amplitude = 0.0;
  par->noise_wavelength = 2.0;
  par->seed = 1;
  par->realisation = 0;
  par->geometry = NULL;
  par->details = 1;
  par->speleothems = 1;
  par->voxel = 0;
  par->fractures = NULL;
  par->n_fractures = 0;
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
/* Rotate v by angle th about the unit axis k (Rodrigues). */
static void rotate(const double *v, const double *k, double th, double *out) {
  double c = cos(th), s = sin(th), kv[3];
  cross3(k, v, kv);
  double kd = dot3(k, v) * (1 - c);
  for (int i = 0; i < 3; i++)
    out[i] = v[i] * c + kv[i] * s + k[i] * kd;
}

static karst_error_t check_params(karst_ctx_t *ctx, const karst_implicit_params_t *p) {
#define POSITIVE(field)                                                                            \
  if (!(p->field > 0) || !isfinite(p->field))                                                      \
    return karst_set_error(ctx, KARST_EINVAL, "geometry parameters: " #field " = %g, must be > 0", \
                           p->field);
  POSITIVE(default_radius)
  POSITIVE(sphere_radius)
  POSITIVE(sphere_rel)
  POSITIVE(chamber_height)
  POSITIVE(noise_wavelength)
#undef POSITIVE
  if (!(p->mitre_max_angle >= 0 && p->mitre_max_angle <= 150))
    return karst_set_error(ctx, KARST_EINVAL,
                           "geometry parameters: mitre_max_angle = %g degrees, must be in [0, 150]",
                           p->mitre_max_angle);
  if (!(p->noise_amplitude >= 0) || !isfinite(p->noise_amplitude))
    return karst_set_error(ctx, KARST_EINVAL,
                           "geometry parameters: noise_amplitude = %g, must be >= 0",
                           p->noise_amplitude);
  if (!(p->voxel >= 0) || !isfinite(p->voxel))
    return karst_set_error(ctx, KARST_EINVAL, "geometry parameters: voxel = %g, must be >= 0",
                           p->voxel);
  if (p->n_fractures < 0 || (p->n_fractures > 0 && !p->fractures))
    return karst_set_error(ctx, KARST_EINVAL, "geometry parameters: %d fractures but none given",
                           p->n_fractures);
  return KARST_SUCCESS;
}

static karst_error_t check_geometry(karst_ctx_t *ctx, const karst_geometry_t *g) {
  if (!(g->blend < 0 || isfinite(g->blend)) || isnan(g->blend))
    return karst_set_error(ctx, KARST_EINVAL, "geometry.blend = %g m is not finite", g->blend);
  if (!(g->blend_factor > 0) || !isfinite(g->blend_factor))
    return karst_set_error(ctx, KARST_EINVAL, "geometry.blend_factor = %g, must be > 0",
                           g->blend_factor);
  if (!(g->continuation_angle >= 0 && g->continuation_angle <= 90))
    return karst_set_error(ctx, KARST_EINVAL,
                           "geometry.continuation_angle = %g, must be in [0, 90] degrees",
                           g->continuation_angle);
  if (!(g->speleothem_relief >= 0) || !isfinite(g->speleothem_relief))
    return karst_set_error(ctx, KARST_EINVAL, "geometry.speleothem_relief = %g, must be >= 0 m",
                           g->speleothem_relief);
  if (!(g->fracture_relief >= 0) || !isfinite(g->fracture_relief) || !(g->fracture_spacing > 0) ||
      !(g->fracture_width > 0))
    return karst_set_error(ctx, KARST_EINVAL,
                           "geometry: fracture_relief %g must be >= 0 m, fracture_spacing %g and "
                           "fracture_width %g > 0 m",
                           g->fracture_relief, g->fracture_spacing, g->fracture_width);
  return KARST_SUCCESS;
}

/* Growable list of node ids. */
typedef struct {
  karst_int_t *v;
  karst_int_t n, cap;
} idlist_t;

static int push(idlist_t *l, karst_int_t x) {
  if (l->n == l->cap) {
    karst_int_t c = l->cap ? 2 * l->cap : 256;
    karst_int_t *q = realloc(l->v, (size_t)c * sizeof *q);
    if (!q) return -1;
    l->v = q;
    l->cap = c;
  }
  l->v[l->n++] = x;
  return 0;
}

/* Per edge: its geometry and classification. */
typedef struct {
  int ok;   /* non-degenerate */
  int type; /* tunnel type */
  double r; /* radius */
  double u[3], len;
  double side[3], up[3];
  karst_sweep_end_t end[2];
} edge_geom_t;

/* One interpolated cross-section of a bend: its plane (origin o, normal t,
 * in-plane axes ex, ey) and its curve in metres. */
typedef struct {
  double t[3], ex[3], ey[3];
  karst_section_t s;
} bend_section_t;

/* Signed distance from v (relative to the bend node) to the filled section j.
 * Within the wedge swept by the sections (@p in_wedge) a point that projects
 * inside the section gets the in-plane distance (its offset from the plane is
 * at most half the spacing of the sections, R/8, and is ignored); otherwise
 * the 3-D distance to the planar region. */
static double section_region_distance(const bend_section_t *bs, const double v[3], int in_wedge) {
  double h = dot3(v, bs->t);
  double q[2] = {dot3(v, bs->ex), dot3(v, bs->ey)};
  double w = karst_section_distance(&bs->s, q);
  if (w < 0) return in_wedge ? w : fabs(h);
  return sqrt(h * h + w * w);
}

/* Unit section of an edge, placed as a 3-D curve around the node: offsets
 * r (x side + y up) of its control points, with side flipped when @p flip. */
static void section_offsets(const karst_section_t *unit, const edge_geom_t *e, int flip,
                            double off[][3]) {
  for (int k = 0; k < 2 * unit->n; k++)
    for (int c = 0; c < 3; c++)
      off[k][c] =
          e->r * ((flip ? -1 : 1) * unit->cp[k][0] * e->side[c] + unit->cp[k][1] * e->up[c]);
}

/*
 * Union of Poisson spheres around the sharp bend at node @p v between edges
 * e1 (arriving, direction t1) and e2 (leaving, direction t2) (§6.2, Fig. 14):
 * n+1 cross-sections interpolated between the two edges' sections, rotating
 * about the bend axis b = t1 x t2 through the node; Poisson disk samples
 * (Bridson 2007, minimum distance R/2) in their bounding box grown by R;
 * a sphere of radius R for every sample whose sphere comes closer than R/2
 * to the interpolated sections, read as: the sphere leaves the section by
 * less than R/2 (centre at least R/2 inside it). The paper's "minimum distance
 * lower than R/2" taken for the centre would let the union bulge 1.5 R out of
 * the conduit; this reading bounds the bulge by R/2. Appends the spheres to
 * @p prims.
 */
static karst_error_t bend_spheres(karst_ctx_t *ctx, karst_sdf_t *sdf, const double node[3],
                                  const edge_geom_t *e1, const double t1[3], const edge_geom_t *e2,
                                  const double t2[3], const karst_section_t *sec1,
                                  const karst_section_t *sec2, const karst_implicit_params_t *par,
                                  karst_rng_t *rng, idlist_t *prims, karst_int_t *count) {
  karst_error_t err = KARST_SUCCESS;
  bend_section_t *bs = NULL;
  int *grid = NULL;
  double *pts = NULL;
  karst_int_t *active = NULL;
  double b[3];
  cross3(t1, t2, b);
  if (normalize3(b)) return KARST_SUCCESS; /* straight or reversed: nothing to fill */
  double phi = acos(fmax(-1.0, fmin(1.0, dot3(t1, t2))));
  double rmax = fmax(e1->r, e2->r);
  double R = fmax(par->sphere_radius, par->sphere_rel * fmin(e1->r, e2->r));
  double dp = 0.5 * R;
  /* Extent of the sections (control hull radius, metres). */
  double rho = 0;
  for (int k = 0; k < 2 * sec1->n; k++)
    rho = fmax(rho, e1->r * hypot(sec1->cp[k][0], sec1->cp[k][1]));
  for (int k = 0; k < 2 * sec2->n; k++)
    rho = fmax(rho, e2->r * hypot(sec2->cp[k][0], sec2->cp[k][1]));
  (void)rmax;
  /* Sections every R/4 of arc at the outer rim. */
  int n = (int)ceil(phi * rho / (0.25 * R));
  if (n < 2) n = 2;
  bs = calloc((size_t)n + 1, sizeof *bs);
  double(*o1)[3] = malloc(sizeof(double[2 * KARST_SECTION_MAX_PIECES][3]));
  double(*o2)[3] = malloc(sizeof(double[2 * KARST_SECTION_MAX_PIECES][3]));
  if (!bs || !o1 || !o2) {
    err = karst_set_error(ctx, KARST_ENOMEM, "bend: out of memory");
    goto cleanup;
  }
  /* Align the second section's side axis with the first one rotated through
   * the bend, so that control points correspond (no mirror collapse). */
  double s1r[3];
  rotate(e1->side, b, phi, s1r);
  int flip2 = dot3(s1r, e2->side) < 0;
  int same = e1->type == e2->type;
  section_offsets(sec1, e1, 0, o1);
  section_offsets(sec2, e2, flip2, o2);
  double bbox[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
  for (int j = 0; j <= n; j++) {
    double th = phi * j / n, s = (double)j / n;
    bend_section_t *S = &bs[j];
    rotate(t1, b, th, S->t);
    rotate(e1->side, b, th, S->ex);
    rotate(e1->up, b, th, S->ey);
    S->s.n = sec1->n;
    for (int k = 0; k < 2 * sec1->n; k++) {
      double p1[3], p2[3], o[3];
      rotate(o1[k], b, th, p1);
      rotate(o2[k], b, th - phi, p2);
      for (int c = 0; c < 3; c++) {
        /* same section: interpolate the control points (and so the radius);
         * different sections have no common parametrization (an
         * interpolation could fold), so each keeps its own half of the bend */
        o[c] = same ? (1 - s) * p1[c] + s * p2[c] : (2 * j <= n ? p1[c] : p2[c]);
        bbox[c] = fmin(bbox[c], o[c]);
        bbox[c + 3] = fmax(bbox[c + 3], o[c]);
      }
      S->s.cp[k][0] = dot3(o, S->ex);
      S->s.cp[k][1] = dot3(o, S->ey);
    }
  }
  for (int c = 0; c < 3; c++)
    bbox[c] -= R, bbox[c + 3] += R;
  /* Bridson's Poisson disk sampling in the box (coordinates relative to the node). */
  double cs = dp / sqrt(3.0);
  karst_int_t gn[3];
  double gcells = 1;
  for (int c = 0; c < 3; c++) {
    gn[c] = (karst_int_t)ceil((bbox[c + 3] - bbox[c]) / cs);
    if (gn[c] < 1) gn[c] = 1;
    gcells *= (double)gn[c];
  }
  if (gcells > POISSON_MAX_CELLS) {
    err = karst_set_error(
        ctx, KARST_EINVAL,
        "bend at (%g, %g, %g): Poisson grid of %.0f cells (sphere radius %g m "
        "for conduits of radius %g m) exceeds %d; raise sphere_radius or sphere_rel",
        node[0], node[1], node[2], gcells, R, rmax, POISSON_MAX_CELLS);
    goto cleanup;
  }
  karst_int_t ncell = (karst_int_t)gcells;
  grid = malloc((size_t)ncell * sizeof *grid);
  pts = malloc((size_t)ncell * 3 * sizeof *pts);
  active = malloc((size_t)ncell * sizeof *active);
  if (!grid || !pts || !active) {
    err =
        karst_set_error(ctx, KARST_ENOMEM, "bend: out of memory for %lld cells", (long long)ncell);
    goto cleanup;
  }
  for (karst_int_t i = 0; i < ncell; i++)
    grid[i] = -1;
  karst_int_t npts = 0, nact = 0;
#define CELL_OF(p, ci)                                                                             \
  for (int c_ = 0; c_ < 3; c_++) {                                                                 \
    ci[c_] = (karst_int_t)floor(((p)[c_] - bbox[c_]) / cs);                                        \
    if (ci[c_] < 0) ci[c_] = 0;                                                                    \
    if (ci[c_] >= gn[c_]) ci[c_] = gn[c_] - 1;                                                     \
  }
  /* Only points of the wedge swept by the sections, within rho of the node,
   * can be selected (below): the sampling is confined to that region. */
  double w1[3];
  cross3(b, t1, w1);
#define USABLE(v)                                                                                  \
  (dot3(v, v) <= rho * rho &&                                                                      \
   (atan2(-dot3(v, t1), dot3(v, w1)) + (atan2(-dot3(v, t1), dot3(v, w1)) < 0 ? M_PI : 0)) <= phi)
  {
    /* seed: half way out along the outer bisector, which is in the wedge */
    double p0[3];
    for (int c = 0; c < 3; c++)
      p0[c] = 0.5 * rho * (t1[c] - t2[c]) / sqrt(2 - 2 * cos(phi));
    karst_int_t ci[3];
    CELL_OF(p0, ci)
    memcpy(pts, p0, sizeof p0);
    grid[(ci[2] * gn[1] + ci[1]) * gn[0] + ci[0]] = 0;
    active[nact++] = 0;
    npts = 1;
  }
  while (nact > 0) {
    karst_int_t ai = (karst_int_t)karst_rng_below(rng, (uint64_t)nact);
    const double *base = pts + 3 * active[ai];
    int placed = 0;
    for (int tr = 0; tr < POISSON_TRIES && !placed; tr++) {
      double d[3], cand[3];
      karst_rng_unit_vector(rng, d);
      double rr =
          dp * cbrt(1.0 + 7.0 * karst_rng_uniform(rng)); /* uniform in the shell [dp, 2dp] */
      int inside = 1;
      for (int c = 0; c < 3; c++) {
        cand[c] = base[c] + rr * d[c];
        if (cand[c] < bbox[c] || cand[c] > bbox[c + 3]) inside = 0;
      }
      if (!inside || !USABLE(cand)) continue;
      karst_int_t ci[3];
      CELL_OF(cand, ci)
      int ok = 1;
      for (karst_int_t z = ci[2] - 2; z <= ci[2] + 2 && ok; z++)
        for (karst_int_t y = ci[1] - 2; y <= ci[1] + 2 && ok; y++)
          for (karst_int_t x = ci[0] - 2; x <= ci[0] + 2 && ok; x++) {
            if (x < 0 || y < 0 || z < 0 || x >= gn[0] || y >= gn[1] || z >= gn[2]) continue;
            karst_int_t g = grid[(z * gn[1] + y) * gn[0] + x];
            if (g < 0) continue;
            const double *q = pts + 3 * g;
            double dd = (q[0] - cand[0]) * (q[0] - cand[0]) + (q[1] - cand[1]) * (q[1] - cand[1]) +
                        (q[2] - cand[2]) * (q[2] - cand[2]);
            if (dd < dp * dp) ok = 0;
          }
      if (!ok) continue;
      memcpy(pts + 3 * npts, cand, sizeof cand);
      grid[(ci[2] * gn[1] + ci[1]) * gn[0] + ci[0]] = (int)npts;
      active[nact++] = npts++;
      placed = 1;
    }
    if (!placed) active[ai] = active[--nact];
  }
#undef CELL_OF
  /* Selection by distance to the interpolated sections. A point's nearest
   * section planes are those whose angle about b is closest to its own. */
#undef USABLE
  for (karst_int_t i = 0; i < npts; i++) {
    const double *v = pts + 3 * i;
    double th = atan2(-dot3(v, t1), dot3(v, w1)); /* plane through v and the axis */
    if (th < 0) th += M_PI;
    int cand[5] = {0, n, -1, -1, -1};
    int in_wedge = th <= phi;
    if (in_wedge) {
      int j = (int)floor(th / phi * n + 0.5);
      cand[2] = j - 1, cand[3] = j, cand[4] = j + 1;
    }
    double best = INFINITY;
    int bj = 0;
    for (int c = 0; c < 5; c++) {
      int j = cand[c];
      if (j < 0 || j > n) continue;
      /* ignoring the offset from the plane is only right for the sections
       * next to the point's own angle */
      double d = section_region_distance(&bs[j], v, in_wedge && c >= 2);
      if (d < best) best = d, bj = j;
    }
    if (!(best + R < 0.5 * R)) continue;
    double cen[3] = {node[0] + v[0], node[1] + v[1], node[2] + v[2]};
    karst_int_t id;
    int label = 2 * bj <= n ? e1->type : e2->type;
    if ((err = karst_sdf_sphere(ctx, sdf, cen, R, label, &id))) goto cleanup;
    if (push(prims, id)) {
      err = karst_set_error(ctx, KARST_ENOMEM, "bend: out of memory");
      goto cleanup;
    }
    (*count)++;
  }
cleanup:
  free(bs);
  free(o1);
  free(o2);
  free(grid);
  free(pts);
  free(active);
  return err;
}

/* Streams of the stages drawn from (seed, realisation), karst_rng_derive. */
#define STREAM_DETAILS 0x64657461ULL           /* "deta" */
#define STREAM_FRACTURE_RELIEF 0x66726163ULL   /* "frac" */
#define STREAM_SPELEOTHEM_RELIEF 0x64726970ULL /* "drip" */
/* The details' skeleton: a segment's weight reaches this many times its
 * section's extent (r max|cp|) from its axis, plus the detail shell. */
#define DETAIL_SUPPORT 2.0
/* Speleothem roots are sunk this much deeper than the wall details reach (m). */
#define EMBED_MARGIN 0.02

/* The mixture of the sections of types with weights @p w (n = 7 types). */
static void make_mix(const karst_section_t *unit, const double *w, karst_section_mix_t *m) {
  memset(m, 0, sizeof *m);
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++)
    if (w[k] > 0 && m->n < KARST_SECTION_MIX_MAX) {
      m->section[m->n] = unit[k];
      m->weight[m->n] = w[k];
      m->n++;
    }
}

/* The one type of a pure mixture, -1 when mixed. */
static int pure_type(const double *w) {
  int t = -1;
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++)
    if (w[k] > 0) {
      if (t >= 0) return -1;
      t = k;
    }
  return t;
}

/* Whether edge g, with areas @p area and type weights @p wa, @p wb at its ends, is a plain
 * sweep: the same area at both ends and its own type only. */
static int plain_edge(const edge_geom_t *g, const double area[2], const double *wa,
                      const double *wb) {
  return area[0] == area[1] && pure_type(wa) == g->type && pure_type(wb) == g->type;
}

/* Inscribed radius (m) at the end @p end (0: a, 1: b) of the primitive made
 * for an edge: r times the section's inscribed radius for a plain sweep, the
 * end's scale times the mixture's distance from the axis for a morph. */
static double end_inscribed(const karst_sdf_t *t, karst_int_t id, int end) {
  const karst_i_node_t *nd = &t->nodes[id];
  const double o[2] = {0, 0};
  if (nd->kind != KARST_SDF_SWEEP) return 0;
  const karst_i_sweep_t *sw = &nd->u.sweep;
  if (!sw->morph)
    return fmax(0.0, -sw->radius * karst_section_distance(&t->sections[sw->section], o));
  const karst_i_morph_t *m = &t->morphs[sw->morph - 1];
  return fmax(0.0, -m->rho[end ? KARST_I_MORPH_TAB : 0] *
                       karst_i_morph_mix_w(t, m, end ? m->wb : m->wa, o));
}

/**
 * Construction tree of a network's conduits (Paris et al. 2021, §6.2); see
 * implicit.h. Edges need no attribute: "tunnel_type" defaults to tube and
 * "radius" to par->default_radius.
 * @param net      the network (edges with optional "tunnel_type", "radius")
 * @param par      parameters (NULL: defaults)
 * @param terrain  when non-NULL the root is terrain minus conduits
 * @param sdf      an empty tree from karst_sdf_create; its root is set
 * @param stats    counts of what was built (may be NULL)
 * @return KARST_SUCCESS; KARST_EINVAL for bad parameters, radii, tunnel types
 *         or a network without usable edge (and no terrain); KARST_ENOMEM.
 * Time complexity: O(E log E + bends × Poisson samples + speleothem rays).
 */
karst_error_t karst_implicit_build(karst_ctx_t *ctx, const karst_network_t *net,
                                   const karst_implicit_params_t *par,
                                   const karst_terrain_t *terrain, karst_sdf_t *sdf,
                                   karst_implicit_stats_t *stats) {
  karst_error_t err = KARST_SUCCESS;
  karst_implicit_params_t defaults;
  karst_geometry_t gdef;
  edge_geom_t *eg = NULL;
  karst_int_t *deg = NULL, *start = NULL, *inc = NULL, *partner = NULL, *prim = NULL;
  double(*endw)[KARST_TUNNEL_TYPE_COUNT] = NULL, *enda = NULL;
  int *grouped = NULL, *flip = NULL;
  karst_skeleton_segment_t *segs = NULL;
  karst_speleothem_t *spel = NULL;
  karst_int_t n_spel = 0;
  idlist_t prims = {0};
  karst_implicit_stats_t st;
  memset(&st, 0, sizeof st);
  if (!par) {
    karst_implicit_params_init(&defaults);
    par = &defaults;
  }
  if (!net || !sdf) return karst_set_error(ctx, KARST_EINVAL, "geometry: no network or tree given");
  if ((err = check_params(ctx, par))) return err;
  const karst_geometry_t *geo = par->geometry;
  if (!geo) {
    karst_geometry_init(&gdef);
    geo = &gdef;
  }
  if ((err = check_geometry(ctx, geo))) return err;
  if (sdf->n_nodes != 0)
    return karst_set_error(ctx, KARST_EINVAL, "geometry: the tree must be empty (has %lld nodes)",
                           (long long)sdf->n_nodes);
  karst_section_t unit[KARST_TUNNEL_TYPE_COUNT];
  double inscribed[KARST_TUNNEL_TYPE_COUNT], green[KARST_TUNNEL_TYPE_COUNT],
      reach[KARST_TUNNEL_TYPE_COUNT];
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++) {
    if ((err = karst_section_for_type(ctx, k, &unit[k]))) return err;
    double o[2] = {0, 0};
    inscribed[k] = fmax(0.0, -karst_section_distance(&unit[k], o));
    green[k] = karst_section_area(&unit[k]);
    reach[k] = 0;
    for (int i = 0; i < 2 * unit[k].n; i++)
      reach[k] = fmax(reach[k], hypot(unit[k].cp[i][0], unit[k].cp[i][1]));
  }
  const karst_attr_t *rad = karst_network_attr_find(net, KARST_ATTR_EDGE, "radius");
  const karst_attr_t *typ = karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
  karst_int_t E = net->n_edges, V = net->n_nodes;
  karst_rng_t rng;
  karst_rng_derive(&rng, par->seed, 0x696d706c69636974ULL /* "implicit" */, 0);

  size_t e1 = (size_t)(E > 0 ? E : 1), v1 = (size_t)(V > 0 ? V : 1);
  eg = calloc(e1, sizeof *eg);
  deg = calloc(v1 + 1, sizeof *deg);
  start = calloc(v1 + 1, sizeof *start);
  inc = malloc(2 * e1 * sizeof *inc);
  partner = malloc(2 * e1 * sizeof *partner);
  endw = calloc(2 * e1, sizeof *endw);
  enda = calloc(2 * e1, sizeof *enda);
  prim = malloc(e1 * sizeof *prim);
  grouped = calloc(e1, sizeof *grouped);
  if (!eg || !deg || !start || !inc || !partner || !endw || !enda || !prim || !grouped) {
    err =
        karst_set_error(ctx, KARST_ENOMEM, "geometry: out of memory for %lld edges", (long long)E);
    goto cleanup;
  }
  /* Edge geometry and classification. */
  for (karst_int_t e = 0; e < E; e++) {
    karst_int_t a = net->edges[2 * e], b = net->edges[2 * e + 1];
    prim[e] = -1;
    partner[2 * e] = partner[2 * e + 1] = -1;
    if (a < 0 || b < 0 || a >= V || b >= V) {
      err = karst_set_error(ctx, KARST_EINVAL,
                            "geometry: edge %lld joins nodes %lld and %lld, "
                            "network has %lld nodes",
                            (long long)e, (long long)a, (long long)b, (long long)V);
      goto cleanup;
    }
    edge_geom_t *g = &eg[e];
    g->r = rad ? rad->data[e * rad->ncomp] : par->default_radius;
    if (!(g->r > 0) || !isfinite(g->r)) {
      err = karst_set_error(ctx, KARST_EINVAL, "geometry: edge %lld has radius %g, must be > 0",
                            (long long)e, g->r);
      goto cleanup;
    }
    double tv = typ ? typ->data[e * typ->ncomp] : KARST_TUNNEL_TUBE;
    if (!(tv >= 0 && tv < KARST_TUNNEL_TYPE_COUNT) || tv != floor(tv)) {
      err = karst_set_error(ctx, KARST_EINVAL,
                            "geometry: edge %lld has tunnel_type %g, expected an integer in 0..%d",
                            (long long)e, tv, KARST_TUNNEL_TYPE_COUNT - 1);
      goto cleanup;
    }
    g->type = (int)tv;
    const double *pa = net->xyz + 3 * a, *pb = net->xyz + 3 * b;
    if (!isfinite(pa[0] + pa[1] + pa[2] + pb[0] + pb[1] + pb[2])) {
      err = karst_set_error(ctx, KARST_EINVAL, "geometry: edge %lld has a non-finite end point",
                            (long long)e);
      goto cleanup;
    }
    for (int c = 0; c < 3; c++)
      g->u[c] = pb[c] - pa[c];
    g->len = sqrt(dot3(g->u, g->u));
    if (a == b || normalize3(g->u) || karst_i_sweep_frame(g->u, NULL, g->side, g->up)) {
      st.n_skipped_edges++;
      continue;
    }
    g->ok = 1;
    deg[a]++, deg[b]++;
  }
  for (karst_int_t v = 0; v < V; v++)
    start[v + 1] = start[v] + deg[v];
  memset(deg, 0, v1 * sizeof *deg);
  for (karst_int_t e = 0; e < E; e++) {
    if (!eg[e].ok) continue;
    for (int k = 0; k < 2; k++) {
      karst_int_t v = net->edges[2 * e + k];
      inc[start[v] + deg[v]++] = 2 * e + k; /* edge e at its end k */
    }
  }
  /* Continuations: at a node of two edges they continue each other; at a
   * junction, two edges that are each other's straightest continuation and
   * turn by at most continuation_angle. Chambers keep their ellipsoid. */
  double cont_cos = cos(geo->continuation_angle * M_PI / 180);
  for (karst_int_t v = 0; v < V; v++) {
    karst_int_t n = deg[v];
    if (n < 2) continue;
    karst_int_t best[64];
    if (n > 64) continue; /* no pairing at such a knot (the blend covers it) */
    for (karst_int_t i = 0; i < n; i++) {
      karst_int_t ei = inc[start[v] + i];
      const edge_geom_t *gi = &eg[ei / 2];
      best[i] = -1;
      if (gi->type == KARST_TUNNEL_CHAMBER) continue;
      double bc = -2;
      for (karst_int_t j = 0; j < n; j++) {
        karst_int_t ej = inc[start[v] + j];
        const edge_geom_t *gj = &eg[ej / 2];
        if (j == i || gj->type == KARST_TUNNEL_CHAMBER) continue;
        /* arriving along i (towards v), leaving along j (away from v) */
        double si = ei % 2 ? 1 : -1, sj = ej % 2 ? -1 : 1;
        double c = si * sj * dot3(gi->u, gj->u);
        if (c > bc) bc = c, best[i] = j;
      }
      if (n > 2 && bc < cont_cos) best[i] = -1;
    }
    for (karst_int_t i = 0; i < n; i++)
      if (best[i] >= 0 && best[best[i]] == i) {
        partner[inc[start[v] + i]] = inc[start[v] + best[i]];
        if (n > 2 && i < best[i]) st.n_continuations++;
      }
  }
  /* End sections: the edge's own, or the mean with its continuation's. */
  for (karst_int_t e = 0; e < E; e++) {
    const edge_geom_t *g = &eg[e];
    if (!g->ok) continue;
    for (int k = 0; k < 2; k++) {
      karst_int_t end = 2 * e + k, p = partner[end];
      double own = g->r * g->r * green[g->type];
      endw[end][g->type] += p >= 0 ? 0.5 : 1.0;
      enda[end] = own;
      if (p >= 0) {
        const edge_geom_t *q = &eg[p / 2];
        endw[end][q->type] += 0.5;
        enda[end] = 0.5 * (own + q->r * q->r * green[q->type]);
      }
    }
  }
  /* Joints of two edges: mitres, revolved sections, Poisson spheres. */
  for (karst_int_t v = 0; v < V; v++) {
    const double *pv = net->xyz + 3 * v;
    if (deg[v] != 2) continue;
    karst_int_t i1 = inc[start[v]], i2 = inc[start[v] + 1];
    edge_geom_t *g1 = &eg[i1 / 2], *g2 = &eg[i2 / 2];
    if (g1->type == KARST_TUNNEL_CHAMBER || g2->type == KARST_TUNNEL_CHAMBER) continue;
    /* d: unit direction towards the node along each edge. */
    double d1[3], d2[3];
    for (int c = 0; c < 3; c++) {
      d1[c] = (i1 % 2 ? 1 : -1) * g1->u[c];
      d2[c] = (i2 % 2 ? 1 : -1) * g2->u[c];
    }
    double t2[3] = {-d2[0], -d2[1], -d2[2]};
    double cosphi = fmax(-1.0, fmin(1.0, dot3(d1, t2)));
    double phi = acos(cosphi) * 180.0 / M_PI;
    if (cosphi >= 1.0) continue; /* straight: flat caps meet exactly */
    if (phi <= par->mitre_max_angle) {
      double m[3] = {d1[0] - d2[0], d1[1] - d2[1], d1[2] - d2[2]};
      if (normalize3(m)) continue;
      g1->end[i1 % 2].mitre = 1;
      memcpy(g1->end[i1 % 2].n, m, sizeof m);
      g2->end[i2 % 2].mitre = 1;
      for (int c = 0; c < 3; c++)
        g2->end[i2 % 2].n[c] = -m[c];
      st.n_mitred_ends += 2;
    } else if (!par->bend_spheres) {
      /* revolve the node's section (both ends have it) about the bend axis,
       * each edge's frame over its half of the gap wedge {l1 >= 0, l2 <= 0}
       * between the flat caps, split at the bisector */
      double b[3], m[3] = {d1[0] + t2[0], d1[1] + t2[1], d1[2] + t2[2]};
      cross3(d1, t2, b);
      if (normalize3(b) || normalize3(m)) {
        /* a U-turn: no bend plane; a ball of the smaller inscribed radius */
        double rb = fmin(g1->r * inscribed[g1->type], g2->r * inscribed[g2->type]);
        karst_int_t id;
        if ((err = karst_sdf_sphere(ctx, sdf, pv, rb, g1->type, &id))) goto cleanup;
        if (push(&prims, id)) goto nomem;
        st.n_joint_balls++;
        continue;
      }
      double n1[2][3] = {{-d1[0], -d1[1], -d1[2]}, {m[0], m[1], m[2]}};
      double n2[2][3] = {{-m[0], -m[1], -m[2]}, {t2[0], t2[1], t2[2]}};
      const double *w = endw[i1];
      int pt = pure_type(w);
      karst_int_t id1, id2;
      if (pt >= 0) {
        double r = sqrt(enda[i1] / green[pt]);
        if ((err = karst_i_revolve_offset(ctx, sdf, pv, b, g1->side, g1->up, &unit[pt], r,
                                          (const double(*)[3])n1, KARST_I_JOINT_OVERLAP, g1->type,
                                          &id1)) ||
            (err = karst_i_revolve_offset(ctx, sdf, pv, b, g2->side, g2->up, &unit[pt], r,
                                          (const double(*)[3])n2, KARST_I_JOINT_OVERLAP, g2->type,
                                          &id2)))
          goto cleanup;
      } else {
        karst_section_mix_t mix;
        make_mix(unit, w, &mix);
        if ((err = karst_i_revolve_mix_offset(ctx, sdf, pv, b, g1->side, g1->up, &mix, enda[i1],
                                              (const double(*)[3])n1, KARST_I_JOINT_OVERLAP,
                                              g1->type, &id1)) ||
            (err = karst_i_revolve_mix_offset(ctx, sdf, pv, b, g2->side, g2->up, &mix, enda[i1],
                                              (const double(*)[3])n2, KARST_I_JOINT_OVERLAP,
                                              g2->type, &id2)))
          goto cleanup;
      }
      if (push(&prims, id1) || push(&prims, id2)) goto nomem;
      st.n_revolves += 2;
      st.n_bends++;
    } else {
      karst_int_t before = st.n_spheres;
      if ((err = bend_spheres(ctx, sdf, pv, g1, d1, g2, t2, &unit[g1->type], &unit[g2->type], par,
                              &rng, &prims, &st.n_spheres)))
        goto cleanup;
      if (st.n_spheres > before) st.n_bends++;
      /* a ball of the inscribed radius guarantees the joint is closed */
      double rb = fmin(g1->r * inscribed[g1->type], g2->r * inscribed[g2->type]);
      if (rb > 0) {
        karst_int_t id;
        if ((err = karst_sdf_sphere(ctx, sdf, pv, rb, g1->type, &id))) goto cleanup;
        if (push(&prims, id)) goto nomem;
        st.n_joint_balls++;
      }
    }
  }
  /* The morphing sweeps' unit mixtures, integrated on ctx->nthreads threads ahead of the edges
   * (most of the tree's building time): their sections, and the plain sweeps', are added to the
   * tree in the order of the loop below, so that every section keeps its index. */
  {
    karst_int_t first = sdf->n_mix_areas;
    for (karst_int_t e = 0; e < E; e++) {
      const edge_geom_t *g = &eg[e];
      if (!g->ok || g->type == KARST_TUNNEL_CHAMBER) continue;
      const double *wa = endw[2 * e], *wb = endw[2 * e + 1];
      int idx;
      if (plain_edge(g, enda + 2 * e, wa, wb)) {
        if ((err = karst_i_sdf_add_section(ctx, sdf, &unit[g->type], &idx))) goto cleanup;
      } else {
        karst_section_mix_t ma, mb;
        make_mix(unit, wa, &ma);
        make_mix(unit, wb, &mb);
        if ((err = karst_i_morph_plan(ctx, sdf, &ma, &mb))) goto cleanup;
      }
    }
    karst_i_morph_integrate(sdf, first, ctx && ctx->nthreads > 1 ? ctx->nthreads : 1);
  }
  /* Edges: plain sweeps, or sweeps morphing between their end sections. */
  for (karst_int_t e = 0; e < E; e++) {
    const edge_geom_t *g = &eg[e];
    if (!g->ok) continue;
    const double *pa = net->xyz + 3 * net->edges[2 * e], *pb = net->xyz + 3 * net->edges[2 * e + 1];
    karst_int_t id;
    if (g->type == KARST_TUNNEL_CHAMBER) {
      double c[3], axes[3][3], radii[3] = {0.5 * g->len + g->r, g->r, par->chamber_height * g->r};
      for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (pa[k] + pb[k]);
        axes[0][k] = g->u[k];
        axes[1][k] = g->side[k];
        axes[2][k] = g->up[k];
      }
      if ((err = karst_sdf_ellipsoid(ctx, sdf, c, (const double(*)[3])axes, radii, g->type, &id)))
        goto cleanup;
      st.n_ellipsoids++;
    } else {
      /* at a joint the sweep reaches KARST_I_JOINT_OVERLAP past its node */
      double qa[3], qb[3];
      karst_int_t na = net->edges[2 * e], nb = net->edges[2 * e + 1];
      for (int c = 0; c < 3; c++) {
        qa[c] = pa[c] - (deg[na] >= 2 ? KARST_I_JOINT_OVERLAP : 0) * g->u[c];
        qb[c] = pb[c] + (deg[nb] >= 2 ? KARST_I_JOINT_OVERLAP : 0) * g->u[c];
      }
      pa = qa, pb = qb;
      const double *wa = endw[2 * e], *wb = endw[2 * e + 1];
      if (plain_edge(g, enda + 2 * e, wa, wb)) {
        double r = sqrt(enda[2 * e] / green[g->type]);
        if ((err =
                 karst_sdf_sweep(ctx, sdf, pa, pb, &unit[g->type], r, NULL, g->end, g->type, &id)))
          goto cleanup;
      } else {
        karst_section_mix_t ma, mb;
        make_mix(unit, wa, &ma);
        make_mix(unit, wb, &mb);
        if ((err = karst_sdf_sweep_morph(ctx, sdf, pa, pb, &ma, enda[2 * e], &mb, enda[2 * e + 1],
                                         NULL, g->end, g->type, &id)))
          goto cleanup;
        st.n_morphs++;
      }
      st.n_sweeps++;
    }
    prim[e] = id;
  }
  /* Junctions: a ball of the largest inscribed radius of the sections
   * meeting there (chambers excluded), smoothly united with the conduits. */
  for (karst_int_t v = 0; v < V; v++) {
    if (deg[v] < 3) continue;
    const double *pv = net->xyz + 3 * v;
    double rb = 0, rmin = INFINITY;
    int lab = KARST_TUNNEL_TUBE;
    for (karst_int_t i = 0; i < deg[v]; i++) {
      karst_int_t end = inc[start[v] + i];
      const edge_geom_t *g = &eg[end / 2];
      rmin = fmin(rmin, g->r);
      if (g->type == KARST_TUNNEL_CHAMBER) continue; /* its ellipsoid covers the node */
      double r = end_inscribed(sdf, prim[end / 2], (int)(end % 2));
      if (r > rb) rb = r, lab = g->type;
    }
    karst_int_t ball = -1;
    if (rb > 0) {
      if ((err = karst_sdf_sphere(ctx, sdf, pv, rb, lab, &ball))) goto cleanup;
      st.n_joint_balls++;
    }
    double k = geo->blend >= 0 ? geo->blend : geo->blend_factor * rmin;
    if (!(k > 0)) {
      if (ball >= 0 && push(&prims, ball)) goto nomem;
      continue;
    }
    /* A continuation pair is one conduit: the hard union of its halves,
     * which abut along their joint plane (a smooth union would bulge by k/4
     * all round it). The conduits are smoothly united with each other; the
     * ball, inside them but for the gaps between their flat caps, joins by a
     * hard union (a smooth union with a solid nested in the others swells
     * by k/4 where their walls are close). */
    karst_int_t grp = -1;
    int parts = 0;
    for (karst_int_t i = 0; i < deg[v]; i++) {
      karst_int_t end = inc[start[v] + i], e = end / 2, p = partner[end], comp = prim[e];
      grouped[e] = 1;
      if (p >= 0) {
        if (p / 2 < e) continue; /* the pair was made at its other member */
        karst_int_t two[2] = {prim[e], prim[p / 2]};
        if ((err = karst_sdf_union(ctx, sdf, 2, two, &comp))) goto cleanup;
      }
      if (grp < 0) {
        grp = comp;
      } else if ((err = karst_sdf_blend(ctx, sdf, grp, comp, k, &grp))) {
        goto cleanup;
      }
      parts++;
    }
    if (ball >= 0) {
      karst_int_t two[2] = {ball, grp};
      if ((err = karst_sdf_union(ctx, sdf, 2, two, &grp))) goto cleanup;
    }
    if (push(&prims, grp)) goto nomem;
    if (parts > 1) st.n_blends++;
  }
  for (karst_int_t e = 0; e < E; e++)
    if (eg[e].ok && !grouped[e] && push(&prims, prim[e])) goto nomem;
  karst_int_t root = -1;
  int want_details = 0, present[KARST_TUNNEL_TYPE_COUNT] = {0};
  double amax = 0;
  for (karst_int_t e = 0; e < E; e++)
    if (eg[e].ok) present[eg[e].type] = 1;
  /* only the types of this network's edges count (their amplitudes, ranges) */
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++)
    if (present[k]) amax = fmax(amax, geo->details[k].amplitude);
  want_details = par->details && amax > 0;
  if (prims.n > 0) {
    if ((err = karst_sdf_union(ctx, sdf, prims.n, prims.v, &root))) goto cleanup;
    if (par->noise_amplitude > 0) {
      karst_int_t nz;
      if ((err = karst_sdf_noise(ctx, sdf, root, par->noise_amplitude, par->noise_wavelength, &rng,
                                 &nz)))
        goto cleanup;
      root = nz;
    }
    karst_int_t conduits = root, details_node = -1; /* conduits: where speleothems are placed */
    if (geo->fracture_relief > 0 && par->n_fractures > 0) {
      karst_relief_t rel;
      karst_relief_init(&rel, KARST_RELIEF_FRACTURES);
      rel.amplitude = geo->fracture_relief;
      rel.spacing = geo->fracture_spacing;
      rel.width = fmin(geo->fracture_width, 4 * geo->fracture_spacing);
      rel.n_planes =
          par->n_fractures < KARST_RELIEF_MAX_PLANES ? par->n_fractures : KARST_RELIEF_MAX_PLANES;
      for (int k = 0; k < rel.n_planes; k++) {
        karst_plane_normal(par->fractures[k].dip_direction, par->fractures[k].dip, rel.normals[k]);
        rel.weights[k] = par->fractures[k].weight;
      }
      karst_warp_params_t wp;
      karst_warp_params_init(&wp);
      wp.band = 4 * geo->fracture_relief;
      karst_rng_t rf;
      karst_rng_derive(&rf, par->seed, par->realisation, STREAM_FRACTURE_RELIEF);
      karst_int_t w;
      if ((err = karst_sdf_warp(ctx, sdf, root, &rel, &wp, &rf, &w))) goto cleanup;
      root = w;
    }
    if (want_details) {
      /* the skeleton, oriented along chains of two-edge nodes (the noise is
       * symmetric: only the cancellation of opposite directions matters) */
      karst_details_params_t dp;
      karst_details_params_init(&dp);
      memcpy(dp.type, geo->details, sizeof dp.type);
      for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++)
        if (!present[k]) dp.type[k].amplitude = 0;
      double shell = KARST_DETAILS_SHELL_FACTOR * amax, r = 1 - 1 / KARST_DETAILS_SHELL_FACTOR;
      double hmax = amax / (r * r * r * r * r * r);
      if (par->voxel > 0) dp.band = sqrt(3.0) * par->voxel + 2 * hmax;
      segs = calloc(e1, sizeof *segs);
      flip = calloc(e1, sizeof *flip);
      if (!segs || !flip) goto nomem;
      int *seen = grouped; /* reused: 2 = oriented */
      karst_int_t ns = 0;
      for (karst_int_t e0 = 0; e0 < E; e0++) {
        if (!eg[e0].ok || seen[e0] == 2) continue;
        seen[e0] = 2;
        /* walk forwards from e0's head and backwards from its tail through
         * nodes of two edges: an edge met at its stored start (forwards) or
         * end (backwards) keeps its direction, else it is flipped */
        for (int dir = 0; dir < 2; dir++) {
          karst_int_t e = e0, v = net->edges[2 * e0 + (dir ? 0 : 1)];
          while (deg[v] == 2) {
            karst_int_t o = inc[start[v]] / 2 == e ? inc[start[v] + 1] : inc[start[v]];
            karst_int_t eo = o / 2, k = o % 2;
            if (seen[eo] == 2) break;
            flip[eo] = dir == 0 ? k == 1 : k == 0;
            seen[eo] = 2;
            e = eo;
            v = net->edges[2 * eo + (1 - k)];
          }
        }
      }
      for (karst_int_t e = 0; e < E; e++) {
        const edge_geom_t *g = &eg[e];
        if (!g->ok) continue;
        const double *pa = net->xyz + 3 * net->edges[2 * e],
                     *pb = net->xyz + 3 * net->edges[2 * e + 1];
        karst_skeleton_segment_t *s = &segs[ns++];
        memcpy(s->a, flip[e] ? pb : pa, sizeof s->a);
        memcpy(s->b, flip[e] ? pa : pb, sizeof s->b);
        s->support = DETAIL_SUPPORT * g->r * reach[g->type] + shell;
        s->type = g->type;
      }
      karst_rng_t rd;
      karst_rng_derive(&rd, par->seed, par->realisation, STREAM_DETAILS);
      /* unscaled here: the speleothems are subtracted from the detailed walls
       * in the same units (labels compare true values), and one rescaling
       * node above both makes the field 1-Lipschitz */
      karst_int_t d;
      if ((err = karst_i_details_create(ctx, sdf, root, &dp, segs, ns, &rd, 1, &d))) goto cleanup;
      st.details_lipschitz = karst_sdf_details_lipschitz(sdf, d);
      details_node = d;
      root = d;
    }
    if (par->speleothems) {
      double relief = geo->speleothem_relief;
      double embed = (want_details ? amax : 0) + sqrt(3.0) * relief + EMBED_MARGIN;
      if ((err = karst_speleothems_place(ctx, sdf, conduits, net, geo, par->default_radius, embed,
                                         par->seed, par->realisation, &spel, &n_spel)))
        goto cleanup;
      for (karst_int_t i = 0; i < n_spel; i++) {
        if (spel[i].kind == KARST_STALACTITE)
          st.n_stalactites++;
        else
          st.n_stalagmites++;
      }
      if (n_spel > 0) {
        karst_rng_t rs;
        karst_rng_derive(&rs, par->seed, par->realisation, STREAM_SPELEOTHEM_RELIEF);
        karst_int_t s, dn;
        if ((err = karst_sdf_speleothems(ctx, sdf, spel, n_spel, relief, &rs, &s)) ||
            (err = karst_sdf_difference(ctx, sdf, root, s, &dn)))
          goto cleanup;
        root = dn;
      }
    }
    if (details_node >= 0) {
      karst_int_t rn;
      if ((err = karst_i_rescale(ctx, sdf, root, st.details_lipschitz,
                                 karst_i_details_band(sdf, details_node), &rn)))
        goto cleanup;
      root = rn;
    }
  }
  if (terrain) {
    karst_int_t tn;
    if ((err = karst_sdf_terrain(ctx, sdf, terrain, &tn))) goto cleanup;
    if (root >= 0) {
      karst_int_t dn;
      if ((err = karst_sdf_difference(ctx, sdf, tn, root, &dn))) goto cleanup;
      root = dn;
    } else {
      root = tn;
    }
  }
  if (root < 0) {
    err = karst_set_error(ctx, KARST_EINVAL,
                          "geometry: the network has no edge of non-zero length (%lld edges, "
                          "%lld skipped) and no terrain was given: nothing to build",
                          (long long)E, (long long)st.n_skipped_edges);
    goto cleanup;
  }
  err = karst_sdf_set_root(ctx, sdf, root);
  karst_log(ctx, KARST_LOG_INFO,
            "geometry: %lld sweeps (%lld morphing, %lld mitred ends), %lld ellipsoids, %lld "
            "junction balls, %lld blended junctions (%lld continuations), %lld sharp bends (%lld "
            "revolved sections, %lld spheres), %lld stalactites, %lld stalagmites, %lld "
            "zero-length edges skipped",
            (long long)st.n_sweeps, (long long)st.n_morphs, (long long)st.n_mitred_ends,
            (long long)st.n_ellipsoids, (long long)st.n_joint_balls, (long long)st.n_blends,
            (long long)st.n_continuations, (long long)st.n_bends, (long long)st.n_revolves,
            (long long)st.n_spheres, (long long)st.n_stalactites, (long long)st.n_stalagmites,
            (long long)st.n_skipped_edges);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "geometry: out of memory");
cleanup:
  if (err) karst_i_sdf_clear(sdf);
  if (stats) *stats = st;
  free(eg);
  free(deg);
  free(start);
  free(inc);
  free(partner);
  free(endw);
  free(enda);
  free(prim);
  free(grouped);
  free(flip);
  free(segs);
  free(spel);
  free(prims.v);
  return err;
}
