/* Surveyed legs as edges of a built sample graph (karst_conditioning_add_legs): the one place
 * conditioning touches the graph, kept apart so that the graph stage stays what it is. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "graph/graph_internal.h"
#include "karst/conditioning.h"

typedef struct {
  karst_int_t u, v;
  double cost;
} arc_t;

static int cmp_arc(const void *x, const void *y) {
  const arc_t *a = x, *b = y;
  if (a->u != b->u) return a->u < b->u ? -1 : 1;
  if (a->v != b->v) return a->v < b->v ? -1 : 1;
  return (a->cost > b->cost) - (a->cost < b->cost);
}

/**
 * karst_conditioning_add_legs: every leg a–b becomes the edge of cost
 * cost_factor × lb_per_metre × |a − b| in both directions: an arc the k-nearest-neighbour graph
 * already has takes that cost (never more than its own: the geology's cost of an edge is at least
 * lb_per_metre × its length and cost_factor <= 1), the others are inserted so every row stays
 * sorted by neighbour. Because a leg's cost does not depend on the rock it crosses, a surveyed
 * passage that the coarse geological model puts across an exclusion or an insoluble bed is kept.
 * The lower bound of the A* heuristics becomes cost_factor × lb_per_metre
 * (karst_conditioning_lower_bound_per_metre).
 *
 * @param station_vertex  graph vertex of each station (karst_conditioning_add_samples)
 * @return KARST_SUCCESS, KARST_EINVAL (a station outside the graph), KARST_ENOMEM.
 * Time complexity: O(n + arcs + legs log legs).
 */
karst_error_t karst_conditioning_add_legs(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                          const karst_int_t *station_vertex, double lb_per_metre,
                                          karst_graph_t *g) {
  const karst_survey_set_t *s = sc->conditioning.data;
  if (!s || s->n_legs == 0) return KARST_SUCCESS;
  const double per_metre = fmin(1.0, sc->conditioning.cost_factor) * lb_per_metre;
  karst_error_t err = KARST_SUCCESS;
  arc_t *extra = malloc((size_t)s->n_legs * 2 * sizeof *extra);
  karst_int_t *offsets = NULL;
  int32_t *adj = NULL;
  karst_arc_cost_t *cost = NULL;
  if (!extra) return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  karst_int_t m = 0;
  for (karst_int_t l = 0; l < s->n_legs; l++) {
    karst_int_t a = station_vertex[s->legs[2 * l]], b = station_vertex[s->legs[2 * l + 1]];
    if (a < 0 || b < 0 || a >= g->n || b >= g->n) {
      err = karst_set_error(ctx, KARST_EINVAL,
                            "conditioning: leg %lld joins vertices %lld and %lld of a graph of "
                            "%lld vertices",
                            (long long)l, (long long)a, (long long)b, (long long)g->n);
      goto cleanup;
    }
    if (a == b) continue;
    const double *p = &g->xyz[3 * a], *q = &g->xyz[3 * b];
    double len = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                      (p[2] - q[2]) * (p[2] - q[2]));
    double c = per_metre * len;
    extra[m++] = (arc_t){a, b, c};
    extra[m++] = (arc_t){b, a, c};
  }
  qsort(extra, (size_t)m, sizeof *extra, cmp_arc);
  /* Count the arcs that are new (not in the row already); repeats keep their first, cheapest. */
  karst_int_t n_new = 0;
  for (karst_int_t i = 0; i < m; i++) {
    if (i > 0 && extra[i].u == extra[i - 1].u && extra[i].v == extra[i - 1].v) continue;
    if (karst_graph_find_arc(g, extra[i].u, extra[i].v) < 0) n_new++;
  }
  offsets = malloc((size_t)(g->n + 1) * sizeof *offsets);
  adj = malloc((size_t)(g->n_arcs + n_new > 0 ? g->n_arcs + n_new : 1) * sizeof *adj);
  cost = malloc((size_t)(g->n_arcs + n_new > 0 ? g->n_arcs + n_new : 1) * sizeof *cost);
  if (!offsets || !adj || !cost) {
    err = karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory for the graph");
    goto cleanup;
  }
  /* Merge every row with its extra arcs, both sorted by neighbour. */
  karst_int_t w = 0, x = 0;
  for (karst_int_t u = 0; u < g->n; u++) {
    offsets[u] = w;
    karst_int_t a = g->offsets[u], end = g->offsets[u + 1];
    /* The row's heads, read in order: head is that of arc a while a < end. */
    karst_arc_reader_t rd = karst_graph_arcs(g, u);
    karst_int_t head = a < end ? karst_arc_next(&rd) : -1;
    while (a < end || (x < m && extra[x].u == u)) {
      if (x < m && extra[x].u == u && x > 0 && extra[x - 1].u == u &&
          extra[x - 1].v == extra[x].v) {
        x++; /* a repeated leg */
        continue;
      }
      int take_extra = x < m && extra[x].u == u && (a >= end || extra[x].v <= head);
      if (take_extra) {
        adj[w] = (int32_t)extra[x].v;
        /* Rounded up: a leg costs exactly the A* bound per metre times its length, and the
         * heuristic must not exceed it by the rounding of the store. */
        cost[w] = karst_arc_cost_round(extra[x].cost);
        if ((double)cost[w] < extra[x].cost) cost[w] = nextafterf(cost[w], INFINITY);
        if (a < end && head == extra[x].v) { /* the k-NN arc: replaced */
          a++;
          head = a < end ? karst_arc_next(&rd) : -1;
        }
        x++;
      } else {
        adj[w] = (int32_t)head;
        cost[w] = g->cost[a];
        a++;
        head = a < end ? karst_arc_next(&rd) : -1;
      }
      w++;
    }
  }
  offsets[g->n] = w;
  err = karst_i_graph_take_rows(ctx, g, g->n, g->xyz, offsets, adj, cost);
  offsets = NULL;
  cost = NULL;
cleanup:
  free(extra);
  free(offsets);
  free(adj);
  free(cost);
  return err;
}
