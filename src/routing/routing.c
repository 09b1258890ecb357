/* Two-stage hydrological routing of the key points (include/karst/routing.h,
 * docs/generation.md "Routing"). */
#include "karst/routing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory_internal.h"
#include "karst/generations.h"

/** Memory (bytes) the plan may spend on its per-target rows (4 bytes per vertex per target);
 *  beyond it no rows are kept and the skeleton's searches use the Euclidean bound alone. 1 GiB. */
#define KARST_ROUTING_ROW_BUDGET ((size_t)1 << 30)

void karst_routing_plan_init(karst_routing_plan_t *plan) {
  memset(plan, 0, sizeof *plan);
}

void karst_routing_plan_destroy(karst_routing_plan_t *plan) {
  free(plan->dz);
  if (plan->arc_costs)
    for (int s = 0; s < plan->n_springs; s++)
      free(plan->arc_costs[s]);
  free(plan->arc_costs);
  free(plan->routes);
  free(plan->targets);
  free(plan->bound);
  free(plan->succ);
  free(plan->closed);
  free(plan->key_spring);
  free(plan->active);
  free(plan->pairs);
  memset(plan, 0, sizeof *plan);
}

void karst_routing_plan_drop_rows(karst_routing_plan_t *plan) {
  free(plan->bound);
  free(plan->succ);
  plan->bound = NULL;
  plan->succ = NULL;
}

const karst_route_t *karst_routing_route(const karst_routing_plan_t *plan, int spring) {
  return spring >= 0 && spring < plan->n_springs ? &plan->routes[spring] : NULL;
}

/* "FILE:LINE:COLUMN: " of a key point, or "". */
static void kp_where(const karst_scenario_t *sc, const karst_keypoint_t *kp, char *buf, size_t sz) {
  buf[0] = '\0';
  if (sc->path && kp->line > 0)
    snprintf(buf, sz, "%s:%d:%d: ", sc->path, kp->line, kp->column > 0 ? kp->column : 1);
}

/* The connectivity value of sink @p s towards spring key @p p: 0 never, 1 allowed, 2 required;
 * -1 when the scenario says nothing of this sink (every spring allowed). */
static int connectivity_of(const karst_scenario_t *sc, int s, int p) {
  const karst_keypoint_t *kp = &sc->key_points[s];
  if (kp->n_drains_to > 0) {
    for (int i = 0; i < kp->n_drains_to; i++)
      if (kp->drains_to[i] == p) return 2;
    return 0;
  }
  const karst_connectivity_t *c = &sc->connectivity;
  if (!c->given) return -1;
  int row = -1, col = -1;
  for (int i = 0; i < c->n_sinks && row < 0; i++)
    if (c->sinks[i] == s) row = i;
  if (row < 0) return -1;
  for (int j = 0; j < c->n_springs && col < 0; j++)
    if (c->springs[j] == p) col = j;
  if (col < 0) return 0; /* a spring the matrix leaves out: never */
  return c->matrix[row * c->n_springs + col];
}

/* Whether sink s has any required spring among those taking part in the generation routed. */
static int has_required(const karst_scenario_t *sc, const karst_geology_t *geo, int s) {
  for (int i = 0; i < karst_geology_n_springs(geo); i++) {
    int key = karst_geology_spring_key(geo, i);
    if (karst_generation_key_active(sc, key) && connectivity_of(sc, s, key) == 2) return 1;
  }
  return 0;
}

static karst_error_t unreachable(karst_ctx_t *ctx, const karst_scenario_t *sc, int a, int b,
                                 const char *why) {
  const karst_keypoint_t *ka = &sc->key_points[a], *kb = &sc->key_points[b];
  char where[KARST_ERRMSG_MAX / 4], bline[32] = "";
  kp_where(sc, ka, where, sizeof where);
  if (kb->line > 0) snprintf(bline, sizeof bline, " (line %d)", kb->line);
  return karst_set_error(
      ctx, KARST_EUNREACHABLE,
      "%skey point '%s' at (%.2f, %.2f, %.2f) cannot drain to '%s'%s%s: no path through "
      "the bedrock reaches it without rising back from the water table into the vadose zone or "
      "crossing an exclusion zone; raise sampling.k (now %d) or lower sampling.fill_radius (now "
      "%g m) so that the samples join up, and check the water table of '%s' and the exclusions",
      where, ka->name, ka->p[0], ka->p[1], ka->p[2], kb->name, bline, why, sc->sampling.k,
      sc->sampling.fill_radius, kb->name);
}

/* d^γ ratio test of the γ rule (see karst_skeleton_gamma_keep). */
static int gamma_prunes(double dab, double dak, double dkb, double gamma) {
  if (!(dab > 0) || !(dak < INFINITY) || !(dkb < INFINITY)) return 0;
  double ra = dak / dab, rb = dkb / dab;
  if (isinf(gamma)) return fmax(ra, rb) < 1.0;
  return pow(ra, gamma) + pow(rb, gamma) < 1.0;
}

static int pair_cmp(const void *x, const void *y) {
  const karst_route_pair_t *p = x, *q = y;
  if (p->d != q->d) return p->d < q->d ? -1 : 1;
  if (p->src != q->src) return p->src < q->src ? -1 : 1;
  return (p->dst > q->dst) - (p->dst < q->dst);
}

/* Tabulate the routed costs of spring @p s (karst_route_tabulate) when @p searches searches will
 * read them and the budget allows: tabulating costs two formula evaluations and 8 bytes per arc,
 * which a few searches over the whole graph (a routing row relaxes every arc once) or many
 * path-sharing A* searches repay, and one search does not. Out of memory it is left undone (the
 * searches then evaluate the same formula). */
static void tabulate_spring(const karst_ctx_t *ctx, const karst_graph_t *g, karst_routing_plan_t *P,
                            int s, int searches, int min_searches) {
  const size_t bytes = 2 * (size_t)g->n_arcs * sizeof(karst_arc_cost_t);
  size_t tables = 1; /* with this one */
  for (int q = 0; q < P->n_springs; q++)
    tables += P->arc_costs[q] != NULL;
  if (searches < min_searches || P->arc_costs[s] || g->n_arcs == 0 ||
      tables * bytes > KARST_ROUTING_ARC_BUDGET)
    return;
  karst_arc_cost_t *fwd = karst_i_alloc_large(bytes);
  if (!fwd) return;
  karst_route_tabulate(ctx, g, &P->routes[s], fwd, fwd + g->n_arcs);
  P->arc_costs[s] = fwd;
  P->routes[s].arc_fwd = fwd;
  P->routes[s].arc_bwd = fwd + g->n_arcs;
}

/**
 * The routing plan (routing.h). The searches are exact and break ties by vertex index, so the
 * plan does not depend on the thread count.
 */
karst_error_t karst_routing_plan(karst_ctx_t *ctx, const karst_geology_t *geo,
                                 const karst_graph_t *g, int want_succ,
                                 karst_routing_plan_t *plan) {
  const karst_scenario_t *sc = karst_geology_scenario(geo);
  const int K = sc->n_key_points, S = karst_geology_n_springs(geo);
  const karst_int_t n = g->n;
  karst_error_t err = KARST_SUCCESS;
  int *srcs = NULL, *allowed = NULL;
  karst_int_t *tv = NULL, *sv = NULL;
  double *rows = NULL, *D = NULL;
  const karst_route_t **troutes = NULL;
  unsigned char *perm = NULL;
  int *tspring = NULL;
  karst_routing_plan_t P;
  karst_routing_plan_init(&P);
  if (K < 1 || n < K)
    return karst_set_error(ctx, KARST_EINVAL, "routing: %d key points on a graph of %lld vertices",
                           K, (long long)n);
  if (S < 1)
    return karst_set_error(ctx, KARST_EINVAL,
                           "routing: the scenario has no spring; every sink must drain to one");
  P.n_keys = K;
  P.n_springs = S;
  const karst_routing_t *rt = &sc->routing;
  P.dz = karst_i_alloc_large((size_t)S * 2 * (size_t)n * sizeof *P.dz);
  P.routes = calloc((size_t)S, sizeof *P.routes);
  P.arc_costs = calloc((size_t)S, sizeof *P.arc_costs);
  P.closed = karst_i_calloc_large((size_t)n, 1);
  P.key_spring = malloc((size_t)K * sizeof *P.key_spring);
  P.targets = malloc((size_t)K * sizeof *P.targets);
  srcs = malloc((size_t)K * sizeof *srcs);
  tv = malloc((size_t)K * sizeof *tv);
  sv = malloc((size_t)K * sizeof *sv);
  D = malloc((size_t)K * (size_t)K * sizeof *D);
  troutes = malloc((size_t)K * sizeof *troutes);
  allowed = malloc((size_t)K * (size_t)S * sizeof *allowed);
  perm = calloc((size_t)K * (size_t)K, 1);
  P.active = malloc((size_t)K);
  tspring = malloc((size_t)K * sizeof *tspring);
  if (!P.dz || !P.routes || !P.arc_costs || !P.closed || !P.key_spring || !P.targets || !srcs ||
      !tv || !sv || !D || !troutes || !allowed || !perm || !P.active || !tspring) {
    err = karst_set_error(ctx, KARST_ENOMEM, "routing: out of memory for %lld vertices",
                          (long long)n);
    goto cleanup;
  }
  /* Per spring: every vertex's depth below that spring's water table, and its elevation. */
  for (int s = 0; s < S; s++) {
    float *dz = P.dz + (size_t)s * 2 * (size_t)n;
    for (karst_int_t v = 0; v < n; v++) {
      const double *p = g->xyz + 3 * v;
      dz[2 * v] = (float)(karst_geology_water_table(geo, s, p[0], p[1]) - p[2]);
      dz[2 * v + 1] = (float)p[2];
    }
    P.routes[s] = (karst_route_t){dz,
                                  (float)rt->water_table_band,
                                  rt->vadose_factor,
                                  rt->rise_cost,
                                  1.0 / rt->phreatic_depth,
                                  NULL,
                                  NULL};
  }
  /* Only the key points of the generation routed take part (generations.h); the others are
   * ordinary vertices that paths may cross. */
  int n_src = 0;
  for (int k = 0; k < K; k++) {
    P.active[k] = (unsigned char)karst_generation_key_active(sc, k);
    P.key_spring[k] = P.active[k] ? karst_geology_spring_of_key(geo, k) : -1;
    if (!P.active[k]) continue;
    if (sc->key_points[k].type != KARST_KEYPOINT_WAYPOINT) P.closed[k] = 1;
    if (sc->key_points[k].type != KARST_KEYPOINT_SPRING) srcs[n_src] = k, sv[n_src++] = k;
  }
  for (int i = 0; i < K * K; i++)
    D[i] = INFINITY;
  for (int k = 0; k < K; k++)
    D[k * K + k] = 0.0;
  /* Targets: the springs, then the waypoints (tspring: the spring of a spring target). */
  int T = 0;
  for (int s = 0; s < S; s++)
    if (P.active[karst_geology_spring_key(geo, s)])
      tspring[T] = s, P.targets[T++] = karst_geology_spring_key(geo, s);
  int n_spring_targets = T;
  if (n_spring_targets == 0) {
    err = karst_set_error(ctx, KARST_EINVAL,
                          "routing: generation %d has no spring; every sink must drain to one",
                          sc->active_generation);
    goto cleanup;
  }
  for (int k = 0; k < K; k++)
    if (P.active[k] && sc->key_points[k].type == KARST_KEYPOINT_WAYPOINT) P.targets[T++] = k;
  P.n_targets = T;
  size_t row_bytes = (size_t)T * (size_t)n * 4;
  if (row_bytes <= KARST_ROUTING_ROW_BUDGET) {
    if (want_succ)
      P.succ = karst_i_alloc_large(row_bytes);
    else
      P.bound = karst_i_alloc_large(row_bytes);
    if (!P.succ && !P.bound) {
      err = karst_set_error(ctx, KARST_ENOMEM, "routing: out of memory for the search rows");
      goto cleanup;
    }
  }
  rows = malloc((size_t)T * (size_t)(n_src > 0 ? n_src : 1) * sizeof *rows);
  if (!rows) {
    err = karst_set_error(ctx, KARST_ENOMEM, "routing: out of memory");
    goto cleanup;
  }
  /* 1. One backward search per spring: every sink's and waypoint's cost to it. With one spring,
   *    every waypoint drains to it (step 2), so its row and the waypoints' are all on its costs:
   *    tabulated now, its own row reads the table too instead of evaluating the formula on
   *    every arc (the same values: karst_route_tabulate). */
  if (n_spring_targets == 1)
    tabulate_spring(ctx, g, &P, tspring[0], T, KARST_ROUTING_TABULATE_MIN_ROWS);
  for (int t = 0; t < n_spring_targets; t++)
    tv[t] = P.targets[t], troutes[t] = &P.routes[tspring[t]];
  karst_progress(ctx, "paths", 0, 1);
  if ((err = karst_paths_target_rows(ctx, g, n_spring_targets, tv, troutes, P.closed, n_src, sv,
                                     rows, P.bound, P.succ)))
    goto cleanup;
  for (int t = 0; t < n_spring_targets; t++)
    for (int j = 0; j < n_src; j++)
      D[srcs[j] * K + P.targets[t]] = rows[t * n_src + j];
  /* 2. Each waypoint drains to the spring it reaches most cheaply (ties: the first). */
  for (int t = n_spring_targets; t < T; t++) {
    int w = P.targets[t], best = -1;
    for (int q = 0; q < n_spring_targets; q++)
      if (D[w * K + P.targets[q]] < INFINITY &&
          (best < 0 || D[w * K + P.targets[q]] < D[w * K + P.targets[best]]))
        best = q;
    if (best < 0) {
      err = unreachable(ctx, sc, w, P.targets[0],
                        n_spring_targets > 1 ? " nor any other spring" : "");
      goto cleanup;
    }
    P.key_spring[w] = tspring[best];
  }
  /* 3. One backward search per waypoint, on the routed costs of its spring (tabulated first for a
   *    spring that several waypoints drain to). */
  if (T > n_spring_targets) {
    for (int q = 0; q < n_spring_targets; q++) {
      int rows_on = 0;
      for (int t = n_spring_targets; t < T; t++)
        rows_on += P.key_spring[P.targets[t]] == tspring[q];
      tabulate_spring(ctx, g, &P, tspring[q], rows_on, KARST_ROUTING_TABULATE_MIN_ROWS);
    }
    for (int t = n_spring_targets; t < T; t++)
      tv[t - n_spring_targets] = P.targets[t],
             troutes[t - n_spring_targets] = &P.routes[P.key_spring[P.targets[t]]];
    size_t off = (size_t)n_spring_targets * (size_t)n;
    if ((err = karst_paths_target_rows(ctx, g, T - n_spring_targets, tv, troutes, P.closed, n_src,
                                       sv, rows, P.bound ? P.bound + off : NULL,
                                       P.succ ? P.succ + off : NULL)))
      goto cleanup;
    for (int t = n_spring_targets; t < T; t++)
      for (int j = 0; j < n_src; j++)
        D[srcs[j] * K + P.targets[t]] = rows[(t - n_spring_targets) * n_src + j];
  }
  karst_progress(ctx, "paths", 1, 1);
  /* 4. Each sink's springs: the required ones, else the cheapest allowed one. */
  for (int k = 0; k < K; k++) {
    if (!P.active[k] || sc->key_points[k].type != KARST_KEYPOINT_SINK) continue;
    int req = has_required(sc, geo, k), best = -1;
    for (int s = 0; s < S; s++)
      allowed[k * S + s] = 0;
    for (int q = 0; q < n_spring_targets; q++) {
      int c = connectivity_of(sc, k, P.targets[q]);
      allowed[k * S + tspring[q]] = c != 0;
      if (req && c == 2 && !(D[k * K + P.targets[q]] < INFINITY)) {
        err = unreachable(ctx, sc, k, P.targets[q], ", which the connectivity requires");
        goto cleanup;
      }
      if (!req && c != 0 && D[k * K + P.targets[q]] < INFINITY &&
          (best < 0 || D[k * K + P.targets[q]] < D[k * K + P.targets[best]]))
        best = q;
    }
    if (!req && best < 0) {
      int first = 0, n_allowed = 0;
      while (first < n_spring_targets - 1 && !allowed[k * S + tspring[first]])
        first++;
      for (int q = 0; q < n_spring_targets; q++)
        n_allowed += allowed[k * S + tspring[q]];
      err = unreachable(ctx, sc, k, P.targets[first],
                        n_allowed > 1 ? " nor any other spring it may drain to" : "");
      goto cleanup;
    }
    for (int q = 0; q < n_spring_targets; q++) /* its routes: required springs, or the best one */
      perm[k * K + P.targets[q]] = req ? connectivity_of(sc, k, P.targets[q]) == 2 : q == best;
    P.key_spring[k] = -1;
    for (int q = 0; q < n_spring_targets && P.key_spring[k] < 0; q++)
      if (perm[k * K + P.targets[q]]) P.key_spring[k] = tspring[q];
  }
  /* 5. Candidate routes (perm[a][b]): sink → its springs, sink → a waypoint whose spring it may
   *    drain to, waypoint → its spring, waypoint → waypoint of the same spring. */
  for (int t = n_spring_targets; t < T; t++) {
    int w = P.targets[t], sw = P.key_spring[w];
    perm[w * K + karst_geology_spring_key(geo, sw)] = 1;
    for (int k = 0; k < K; k++) {
      const karst_keypoint_t *kp = &sc->key_points[k];
      if (k == w || !P.active[k] || !(D[k * K + w] < INFINITY)) continue;
      if (kp->type == KARST_KEYPOINT_SINK && allowed[k * S + sw]) perm[k * K + w] = 1;
      if (kp->type == KARST_KEYPOINT_WAYPOINT && P.key_spring[k] == sw) perm[k * K + w] = 1;
    }
  }
  int cap = 0;
  for (int i = 0; i < K * K; i++)
    cap += perm[i];
  P.pairs = malloc((size_t)(cap > 0 ? cap : 1) * sizeof *P.pairs);
  if (!P.pairs) {
    err = karst_set_error(ctx, KARST_ENOMEM, "routing: out of memory");
    goto cleanup;
  }
  int *tidx = srcs; /* reuse: target index of each key point */
  for (int k = 0; k < K; k++)
    tidx[k] = -1;
  for (int t = 0; t < T; t++)
    tidx[P.targets[t]] = t;
  /* 6. The γ rule on the candidates, waypoints the only intermediates (a path through a sink or a
   *    spring is not a route); required connections are kept. Between two waypoints only the
   *    cheaper direction is laid (ties: from the lower index). */
  for (int a = 0; a < K; a++)
    for (int b = 0; b < K; b++) {
      if (!perm[a * K + b]) continue;
      double dab = D[a * K + b];
      if (!(dab < INFINITY)) continue;
      P.n_candidates++;
      int both_way = sc->key_points[a].type == KARST_KEYPOINT_WAYPOINT &&
                     sc->key_points[b].type == KARST_KEYPOINT_WAYPOINT;
      if (both_way && perm[b * K + a] && (D[b * K + a] < dab || (D[b * K + a] == dab && b < a)))
        continue;
      int required =
          sc->key_points[a].type == KARST_KEYPOINT_SINK && connectivity_of(sc, a, b) == 2;
      int pruned = 0;
      for (int k = 0; k < K && !required && !pruned; k++) {
        if (k == a || k == b || sc->key_points[k].type != KARST_KEYPOINT_WAYPOINT) continue;
        if (!perm[a * K + k] || !perm[k * K + b]) continue;
        pruned = gamma_prunes(dab, D[a * K + k], D[k * K + b], sc->gamma);
      }
      if (pruned) continue;
      int spring = sc->key_points[b].type == KARST_KEYPOINT_SPRING
                       ? karst_geology_spring_of_key(geo, b)
                       : P.key_spring[b];
      P.pairs[P.n_pairs++] = (karst_route_pair_t){dab, a, b, tidx[b], spring, required};
    }
  qsort(P.pairs, (size_t)P.n_pairs, sizeof *P.pairs, pair_cmp);
  /* The skeleton's path-sharing searches (no successor rows wanted) on each spring's costs. */
  if (!want_succ)
    for (int q = 0; q < S; q++) {
      int routes_on = 0;
      for (int i = 0; i < P.n_pairs; i++)
        routes_on += P.pairs[i].spring == q;
      tabulate_spring(ctx, g, &P, q, routes_on, KARST_ROUTING_TABULATE_MIN_ROUTES);
    }
  for (int k = 0; k < K; k++)
    if (P.active[k] && sc->key_points[k].type == KARST_KEYPOINT_SPRING)
      P.key_spring[k] = karst_geology_spring_of_key(geo, k);
  karst_routing_plan_destroy(plan);
  *plan = P;
  karst_routing_plan_init(&P);
cleanup:
  karst_routing_plan_destroy(&P);
  free(srcs);
  free(tv);
  free(sv);
  free(rows);
  free(D);
  free(troutes);
  free(allowed);
  free(perm);
  free(tspring);
  return err;
}
