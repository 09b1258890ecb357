/* Speleothems: round cones hung from conduit ceilings (stalactites) and
 * grown from their floors (stalagmites, paired under stalactites where the
 * ceiling is low), placed by a density per tunnel type with a clearance, by
 * rays cast in the conduits' 1-Lipschitz field; and their union with a
 * dripstone relief. Beyond the papers (Paris et al. 2021 names them as
 * future work). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel_internal.h"
#include "implicit/implicit_internal.h"

/* Stream of the speleothems in karst_rng_derive(seed, realisation, stream). */
#define STREAM_SPELEOTHEMS 0x7370656cULL /* "spel" */
/* Ray marching: smallest step (m) and bisection steps of the hit. */
#define RAY_MIN_STEP 1e-3
#define RAY_BISECTIONS 30
/* Candidates are drawn over these fractions of an edge's length and width. */
#define SPAN_LENGTH 0.8
#define SPAN_WIDTH 0.7
/* Spacing of the balls that certify a speleothem's body inside the void (m). */
#define CERTIFY_STEP 0.02
/* Stalactite root and tip radii, as fractions of the length and of the root. */
#define STALACTITE_ROOT_LO 0.08
#define STALACTITE_ROOT_HI 0.14
#define STALACTITE_TIP 0.15
/* Stalagmites: length as a fraction of the free height under the stalactite,
 * root radius as a fraction of the length, tip as a fraction of the root. */
#define STALAGMITE_LENGTH_LO 0.3
#define STALAGMITE_LENGTH_HI 0.8
#define STALAGMITE_ROOT_LO 0.12
#define STALAGMITE_ROOT_HI 0.22
#define STALAGMITE_TIP 0.5
/* Smallest radius of a speleothem's ball (m). */
#define MIN_RADIUS 0.01

/**
 * Round cone primitive (see implicit.h). In the plane of the axis, with y
 * along ab and x >= 0 the distance to the axis, the side is the line
 * cos θ x + sin θ y = ra, sin θ = (ra - rb)/L, tangent to both circles; the
 * point's position s = -sin θ x + cos θ y along it decides whether the
 * nearest part is ball a (s < 0), ball b (s > L cos θ) or the side. O(1).
 */
karst_error_t karst_sdf_round_cone(karst_ctx_t *ctx, karst_sdf_t *t, const double a[3], double ra,
                                   const double b[3], double rb, int label, karst_int_t *node) {
  double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double len = sqrt(karst_i_dot3(u, u));
  if (!isfinite(len) || !isfinite(a[0] + a[1] + a[2]) || !(ra > 0) || !(rb > 0) ||
      !isfinite(ra + rb) || !(fabs(ra - rb) < len))
    return karst_set_error(ctx, KARST_EINVAL,
                           "round cone: radii %g and %g must be > 0 and differ by less than the "
                           "axis length %g m",
                           ra, rb, len);
  karst_i_node_t *nd = NULL;
  karst_error_t err = karst_i_sdf_new_node(ctx, t, KARST_SDF_ROUND_CONE, &nd, node);
  if (err) return err;
  memcpy(nd->u.cone.a, a, sizeof nd->u.cone.a);
  for (int c = 0; c < 3; c++)
    nd->u.cone.u[c] = u[c] / len;
  nd->u.cone.len = len;
  nd->u.cone.ra = ra;
  nd->u.cone.rb = rb;
  nd->u.cone.sn = (ra - rb) / len;
  nd->u.cone.cs = sqrt(1 - nd->u.cone.sn * nd->u.cone.sn);
  nd->label = label;
  nd->finite = 1;
  for (int c = 0; c < 3; c++) {
    nd->box[c] = fmin(a[c] - ra, b[c] - rb);
    nd->box[c + 3] = fmax(a[c] + ra, b[c] + rb);
  }
  karst_i_pad_box(nd->box);
  return KARST_SUCCESS;
}

double karst_i_round_cone_eval(const karst_i_node_t *nd, const double p[3]) {
  const double *a = nd->u.cone.a, *u = nd->u.cone.u;
  double v[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  double y = karst_i_dot3(v, u), x2 = karst_i_dot3(v, v) - y * y, x = x2 > 0 ? sqrt(x2) : 0;
  double sn = nd->u.cone.sn, cs = nd->u.cone.cs, L = nd->u.cone.len;
  double s = -sn * x + cs * y;
  if (s < 0) return sqrt(x * x + y * y) - nd->u.cone.ra;
  if (s > L * cs) return sqrt(x * x + (y - L) * (y - L)) - nd->u.cone.rb;
  return cs * x + sn * y - nd->u.cone.ra;
}

/* ---------------------------------------------------------------------- */
/* Placement.                                                              */
/* ---------------------------------------------------------------------- */

static double field(const karst_sdf_t *t, karst_int_t node, const double p[3]) {
  return karst_sdf_eval_node(t, node, p, NULL, NULL);
}

/* From p (in the void, f < 0) along +z (dz = 1) or -z (dz = -1): the z where
 * the field turns non-negative, within max_dist; -1 when none. The step is
 * |f| (the field is 1-Lipschitz, so no surface is skipped). */
static int ray_to_wall(const karst_sdf_t *t, karst_int_t node, const double p[3], int dz,
                       double max_dist, double *hit) {
  double q[3] = {p[0], p[1], p[2]}, in = p[2], f = field(t, node, q);
  if (!(f < 0)) return -1;
  while (fabs(q[2] - p[2]) <= max_dist) {
    in = q[2];
    q[2] += dz * fmax(-f, RAY_MIN_STEP);
    f = field(t, node, q);
    if (f >= 0) {
      double lo = in, hi = q[2];
      for (int i = 0; i < RAY_BISECTIONS; i++) {
        double m[3] = {p[0], p[1], 0.5 * (lo + hi)};
        if (field(t, node, m) < 0)
          lo = m[2];
        else
          hi = m[2];
      }
      *hit = hi;
      return 0;
    }
  }
  return -1;
}

/* Rock above (dz = 1) or below (dz = -1) the wall at z0: 1 when the field is
 * positive all the way to z0 + dz need (stepping by the field's value). */
static int rock_for(const karst_sdf_t *t, karst_int_t node, const double p[3], double z0, int dz,
                    double need) {
  double q[3] = {p[0], p[1], z0 + dz * RAY_MIN_STEP};
  while (dz * (q[2] - z0) < need) {
    double f = field(t, node, q);
    if (!(f > 0)) return 0;
    q[2] += dz * fmax(f, RAY_MIN_STEP);
  }
  return 1;
}

/* The body of a speleothem from root (ra) to tip (rb) is certified inside
 * the void: every ball of the axis that stays clear of the wall's level zw
 * by more than ra (its top below zw - ra for a stalactite, dz = -1), grown by
 * the spacing of the checks so that the balls between two checks are
 * covered, has a field below minus its radius (1-Lipschitz: the ball is
 * void); the root is in rock up to need beyond zw and at 8 points around it.
 * The balls within ra of the wall's level form the root zone, merged with
 * the wall (ra of slack for a wall sloping by up to 45° over the root). */
static int certified(const karst_sdf_t *t, karst_int_t node, const double root[3], double ra,
                     const double tip[3], double rb, double zw, int dz, double need) {
  double len =
      sqrt((tip[0] - root[0]) * (tip[0] - root[0]) + (tip[1] - root[1]) * (tip[1] - root[1]) +
           (tip[2] - root[2]) * (tip[2] - root[2]));
  int n = (int)ceil(len / CERTIFY_STEP);
  double dr = fabs(rb - ra) / (n > 0 ? n : 1), step = len / (n > 0 ? n : 1);
  for (int i = 0; i <= n; i++) {
    double s = n > 0 ? (double)i / n : 1, c[3], r = ra + s * (rb - ra);
    for (int k = 0; k < 3; k++)
      c[k] = root[k] + s * (tip[k] - root[k]);
    double need_in = r + step + dr;
    /* within reach of the wall, with one root radius for its slope: the root zone */
    if (-dz * (c[2] - zw) + need_in + ra > 0) continue;
    if (!(field(t, node, c) <= -need_in)) return 0;
  }
  if (!rock_for(t, node, root, zw, -dz, need)) return 0;
  for (int k = 0; k < 8; k++) {
    double th = 2 * M_PI * k / 8;
    double q[3] = {root[0] + ra * cos(th), root[1] + ra * sin(th), root[2]};
    if (!(field(t, node, q) > 0)) return 0;
  }
  return 1;
}

/* Poisson(λ) draw: Knuth's product method, a rounded normal beyond 30. */
static karst_int_t poisson(karst_rng_t *r, double lambda) {
  if (lambda <= 0) return 0;
  if (lambda > 30) {
    double x = floor(lambda + sqrt(lambda) * karst_rng_gaussian(r) + 0.5);
    return x < 0 ? 0 : (karst_int_t)x;
  }
  double L = exp(-lambda), p = 1;
  karst_int_t k = 0;
  do {
    k++;
    p *= karst_rng_uniform(r);
  } while (p > L);
  return k - 1;
}

typedef struct {
  karst_speleothem_t *v;
  karst_int_t n, cap;
} list_t;

static int push(list_t *l, const karst_speleothem_t *s) {
  if (l->n == l->cap) {
    karst_int_t c = l->cap ? 2 * l->cap : 64;
    karst_speleothem_t *q = realloc(l->v, (size_t)c * sizeof *q);
    if (!q) return -1;
    l->v = q;
    l->cap = c;
  }
  l->v[l->n++] = *s;
  return 0;
}

/* No root of @p l within twice the larger root radius of (x, y) in plan. */
static int spaced(const list_t *l, double x, double y, double r) {
  for (karst_int_t i = 0; i < l->n; i++) {
    double dx = l->v[i].root[0] - x, dy = l->v[i].root[1] - y, m = 2 * fmax(r, l->v[i].root_radius);
    if (dx * dx + dy * dy < m * m) return 0;
  }
  return 1;
}

static karst_error_t check_rule(karst_ctx_t *ctx, int k, const karst_speleothem_rule_t *r) {
  const char *name = karst_tunnel_type_name((karst_tunnel_type_t)k);
  if (!(r->density >= 0) || !isfinite(r->density))
    return karst_set_error(ctx, KARST_EINVAL, "speleothems of %s: density %g must be >= 0 per m²",
                           name, r->density);
  if (r->density == 0) return KARST_SUCCESS;
  if (!(r->clearance >= 0) || !isfinite(r->clearance) || !(r->pair_height >= 0) ||
      !isfinite(r->pair_height))
    return karst_set_error(ctx, KARST_EINVAL,
                           "speleothems of %s: clearance %g and pair_height %g must be >= 0 m",
                           name, r->clearance, r->pair_height);
  if (!(r->min_length > 0) || !(r->min_length <= r->max_length) || !isfinite(r->max_length))
    return karst_set_error(ctx, KARST_EINVAL,
                           "speleothems of %s: lengths must satisfy 0 < min_length <= max_length, "
                           "got %g and %g m",
                           name, r->min_length, r->max_length);
  return KARST_SUCCESS;
}

/* At most this many candidates are examined at once (bounds the memory; the result does not
 * depend on it). */
#define CANDIDATE_BATCH 4096

/* An edge's frame and candidates (karst_speleothems_place). */
typedef struct {
  int ok, type, chamber;
  const double *pa;
  double r, len, u[3], side[3], along, width, span;
  karst_int_t n_cand, first; /* its candidates: [first, first + n_cand) of the batch */
  karst_rng_t rng;           /* its stream after the count was drawn */
} spel_edge_t;

/* A candidate examined on its own: its stalactite when that passes every test but the spacing
 * from those placed before (ok), and the stalagmite under it (have_m). */
typedef struct {
  int ok, have_m;
  karst_speleothem_t s, m;
} spel_cand_t;

typedef struct {
  const karst_sdf_t *sdf;
  const karst_geometry_t *g;
  karst_int_t conduits, e0, e1; /* the batch's edges */
  double embed;
  spel_edge_t *edges;
  spel_cand_t *cand;
} cand_job_t;

/* The candidates of edge e: draws (from the edge's stream, in order), rays to the ceiling and
 * floor, lengths, radii and the certification of the bodies. */
static void edge_candidates(const cand_job_t *J, karst_int_t e) {
  const spel_edge_t *E = &J->edges[e];
  const karst_speleothem_rule_t *rule = &J->g->speleothems[E->type];
  const double embed = J->embed, clear = rule->clearance + embed;
  karst_rng_t re = E->rng;
  for (karst_int_t c = 0; c < E->n_cand; c++) {
    spel_cand_t *C = &J->cand[E->first + c];
    C->ok = C->have_m = 0;
    double fl = karst_rng_uniform_range(&re, -0.5 * SPAN_LENGTH, 0.5 * SPAN_LENGTH);
    double fx = karst_rng_uniform_range(&re, -SPAN_WIDTH, SPAN_WIDTH);
    double lt = karst_rng_uniform(&re), rr = karst_rng_uniform(&re);
    double mt = karst_rng_uniform(&re), mr = karst_rng_uniform(&re);
    double l = 0.5 * E->len + fl * E->along;
    double w = E->chamber ? E->width * sqrt(fmax(0, 1 - 4 * fl * fl)) : E->width;
    double p0[3];
    for (int k = 0; k < 3; k++)
      p0[k] = E->pa[k] + l * E->u[k] + fx * w * E->side[k];
    double zc, zf;
    if (ray_to_wall(J->sdf, J->conduits, p0, 1, E->span, &zc) ||
        ray_to_wall(J->sdf, J->conduits, p0, -1, E->span, &zf))
      continue;
    double H = zc - zf;
    double len_t = rule->min_length + lt * (rule->max_length - rule->min_length);
    int paired = H < rule->pair_height;
    double free_h = H - clear; /* what the speleothems may fill */
    if (paired)
      len_t = fmin(len_t, 0.5 * free_h);
    else
      len_t = fmin(len_t, free_h);
    if (len_t < rule->min_length) continue;
    double ra = fmax(MIN_RADIUS * 2, len_t * (STALACTITE_ROOT_LO +
                                              rr * (STALACTITE_ROOT_HI - STALACTITE_ROOT_LO)));
    double rb = fmax(MIN_RADIUS, STALACTITE_TIP * ra);
    karst_speleothem_t *s = &C->s;
    memset(s, 0, sizeof *s);
    s->kind = KARST_STALACTITE;
    s->edge = e;
    s->type = E->type;
    s->ceiling = zc;
    s->floor = zf;
    s->root[0] = s->tip[0] = p0[0];
    s->root[1] = s->tip[1] = p0[1];
    s->root[2] = zc + embed + ra; /* one radius deeper: roots hold on ceilings sloping up to 45° */
    s->tip[2] = zc - len_t + rb;
    s->root_radius = ra;
    s->tip_radius = rb;
    if (!(s->root[2] - s->tip[2] > ra - rb)) continue;
    if (!certified(J->sdf, J->conduits, s->root, ra, s->tip, rb, zc, -1, embed + 3 * ra)) continue;
    C->ok = 1;
    if (paired) {
      double len_m =
          (free_h - len_t) * (STALAGMITE_LENGTH_LO + mt * (STALAGMITE_LENGTH_HI - STALAGMITE_LENGTH_LO));
      double ma = fmax(MIN_RADIUS * 2, len_m * (STALAGMITE_ROOT_LO +
                                                mr * (STALAGMITE_ROOT_HI - STALAGMITE_ROOT_LO)));
      double mb = fmax(MIN_RADIUS, STALAGMITE_TIP * ma);
      karst_speleothem_t *m = &C->m;
      *m = *s;
      m->kind = KARST_STALAGMITE;
      m->root[2] = zf - embed - ma;
      m->tip[2] = zf + len_m - mb;
      m->root_radius = ma;
      m->tip_radius = mb;
      C->have_m = len_m > 2 * ma && m->tip[2] - m->root[2] > ma - mb &&
                  certified(J->sdf, J->conduits, m->root, ma, m->tip, mb, zf, 1, embed + 3 * ma);
    }
  }
}

static void task_candidates(void *arg, int tid, int nth) {
  cand_job_t *J = arg;
  for (karst_int_t e = J->e0 + tid; e < J->e1; e += nth)
    if (J->edges[e].ok) edge_candidates(J, e);
}

/**
 * Place speleothems (see implicit.h). The candidates are examined on ctx->nthreads threads by
 * edges (each edge draws from its own stream), in batches of at most CANDIDATE_BATCH; only the
 * spacing from those placed before depends on the others, so the candidates that pass every
 * other test are then accepted in edge order: the list does not depend on the thread count.
 * Time complexity: O(Σ candidates (ray steps + certification) x field cost
 * + placed²); memory O(max(CANDIDATE_BATCH, the largest edge's candidates)), KARST_ENOMEM
 * when that does not fit.
 */
karst_error_t karst_speleothems_place(karst_ctx_t *ctx, const karst_sdf_t *sdf,
                                      karst_int_t conduits, const karst_network_t *net,
                                      const karst_geometry_t *g, double default_radius,
                                      double embed, uint64_t seed, uint64_t realisation,
                                      karst_speleothem_t **out, karst_int_t *n_out) {
  *out = NULL;
  *n_out = 0;
  if (!sdf || conduits < 0 || conduits >= sdf->n_nodes || !net || !g)
    return karst_set_error(ctx, KARST_EINVAL, "speleothems: no field, network or rules given");
  if (!(embed >= 0) || !isfinite(embed) || !(default_radius > 0))
    return karst_set_error(ctx, KARST_EINVAL, "speleothems: embed %g m must be >= 0", embed);
  karst_error_t err;
  int any = 0;
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++) {
    if ((err = check_rule(ctx, k, &g->speleothems[k]))) return err;
    any |= g->speleothems[k].density > 0;
  }
  if (!any) return KARST_SUCCESS;
  const karst_attr_t *rad = karst_network_attr_find(net, KARST_ATTR_EDGE, "radius");
  const karst_attr_t *typ = karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
  karst_section_t sec[KARST_TUNNEL_TYPE_COUNT];
  double halfw[KARST_TUNNEL_TYPE_COUNT], reach[KARST_TUNNEL_TYPE_COUNT];
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++) {
    if ((err = karst_section_for_type(ctx, k, &sec[k]))) return err;
    halfw[k] = reach[k] = 0;
    for (int i = 0; i < 2 * sec[k].n; i++) {
      halfw[k] = fmax(halfw[k], fabs(sec[k].cp[i][0]));
      reach[k] = fmax(reach[k], hypot(sec[k].cp[i][0], sec[k].cp[i][1]));
    }
  }
  karst_rng_t base;
  karst_rng_derive(&base, seed, realisation, STREAM_SPELEOTHEMS);
  uint64_t edge_seed = karst_rng_u64(&base);
  list_t placed = {0};
  const karst_int_t n_edges = net->n_edges;
  spel_edge_t *edges = calloc((size_t)(n_edges > 0 ? n_edges : 1), sizeof *edges);
  spel_cand_t *cand = NULL;
  if (!edges) goto nomem;
  /* Each edge's frame and candidate count. */
  karst_int_t max_cand = 0;
  for (karst_int_t e = 0; e < n_edges; e++) {
    spel_edge_t *E = &edges[e];
    double tv = typ ? typ->data[e * typ->ncomp] : KARST_TUNNEL_TUBE;
    if (!(tv >= 0 && tv < KARST_TUNNEL_TYPE_COUNT)) continue; /* the builder reports it */
    int type = (int)tv;
    const karst_speleothem_rule_t *rule = &g->speleothems[type];
    if (rule->density <= 0) continue;
    double r = rad ? rad->data[e * rad->ncomp] : default_radius;
    karst_int_t ia = net->edges[2 * e], ib = net->edges[2 * e + 1];
    if (!(r > 0) || ia < 0 || ib < 0 || ia >= net->n_nodes || ib >= net->n_nodes) continue;
    const double *pa = net->xyz + 3 * ia, *pb = net->xyz + 3 * ib;
    double u[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]}, len = sqrt(karst_i_dot3(u, u));
    if (!(len > 0) || !isfinite(len)) continue;
    for (int c = 0; c < 3; c++)
      u[c] /= len;
    double side[3], up[3];
    if (karst_i_sweep_frame(u, NULL, side, up)) continue;
    int chamber = type == KARST_TUNNEL_CHAMBER;
    /* footprint: the chamber's ellipse (semi-axes L/2 + r, r), else length x width */
    double along = chamber ? len + 2 * r : len, width = chamber ? r : r * halfw[type];
    double area = chamber ? M_PI * 0.5 * along * width : len * 2 * width;
    E->ok = 1, E->type = type, E->chamber = chamber, E->pa = pa, E->r = r, E->len = len;
    memcpy(E->u, u, sizeof u), memcpy(E->side, side, sizeof side);
    E->along = along, E->width = width, E->span = 2 * reach[type] * r + 2 * (embed + 1);
    karst_rng_init(&E->rng, edge_seed, (uint64_t)e);
    E->n_cand = poisson(&E->rng, rule->density * area);
    if (E->n_cand > max_cand) max_cand = E->n_cand;
  }
  size_t cap = (size_t)(max_cand > CANDIDATE_BATCH ? max_cand : CANDIDATE_BATCH);
  if (!(cand = malloc(cap * sizeof *cand))) goto nomem;
  const int nth = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  for (karst_int_t e0 = 0; e0 < n_edges;) {
    /* a batch of edges with at most cap candidates */
    karst_int_t e1 = e0, n = 0;
    for (; e1 < n_edges && n + edges[e1].n_cand <= (karst_int_t)cap; e1++)
      edges[e1].first = n, n += edges[e1].n_cand;
    cand_job_t J = {sdf, g, conduits, e0, e1, embed, edges, cand};
    karst_i_parallel_run(nth, task_candidates, &J);
    /* in edge order: the spacing from those placed before */
    for (karst_int_t i = 0; i < n; i++) {
      const spel_cand_t *C = &cand[i];
      if (!C->ok || !spaced(&placed, C->s.root[0], C->s.root[1], C->s.root_radius)) continue;
      if (push(&placed, &C->s) || (C->have_m && push(&placed, &C->m))) goto nomem;
    }
    e0 = e1;
  }
  free(edges);
  free(cand);
  *out = placed.v;
  *n_out = placed.n;
  return KARST_SUCCESS;
nomem:
  free(edges);
  free(cand);
  free(placed.v);
  return karst_set_error(ctx, KARST_ENOMEM, "speleothems: out of memory");
}

/**
 * The union of speleothems with their dripstone relief (see implicit.h).
 * Time complexity: O(n log n).
 */
karst_error_t karst_sdf_speleothems(karst_ctx_t *ctx, karst_sdf_t *sdf, const karst_speleothem_t *s,
                                    karst_int_t n, double relief, karst_rng_t *rng,
                                    karst_int_t *node) {
  if (!s || n < 1) return karst_set_error(ctx, KARST_EINVAL, "speleothems: none given");
  if (!(relief >= 0) || !isfinite(relief))
    return karst_set_error(ctx, KARST_EINVAL, "speleothems: relief %g must be >= 0 m", relief);
  karst_int_t *ids = malloc((size_t)n * sizeof *ids);
  if (!ids) return karst_set_error(ctx, KARST_ENOMEM, "speleothems: out of memory");
  karst_error_t err = KARST_SUCCESS;
  for (karst_int_t i = 0; i < n && !err; i++)
    err = karst_sdf_round_cone(ctx, sdf, s[i].root, s[i].root_radius, s[i].tip, s[i].tip_radius,
                               KARST_SDF_LABEL(s[i].type, KARST_SDF_FEATURE_SPELEOTHEM), &ids[i]);
  karst_int_t un = -1;
  if (!err) err = karst_sdf_union(ctx, sdf, n, ids, &un);
  free(ids);
  if (err) return err;
  *node = un;
  if (relief == 0) return KARST_SUCCESS;
  karst_relief_t r;
  karst_relief_init(&r, KARST_RELIEF_NOISE);
  r.amplitude = relief;
  r.wavelength = 0.3;
  r.octaves = 2;
  karst_warp_params_t wp;
  karst_warp_params_init(&wp);
  wp.epsilon = 0.05;
  wp.band = 3 * relief;
  return karst_sdf_warp(ctx, sdf, un, &r, &wp, rng, node);
}
