/* Speleogenetic phases (include/karst/generations.h, docs/generation.md "Generations"). */
#include "karst/generations.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int karst_generation_count(const karst_scenario_t *sc) {
  return sc->n_generations > 0 ? sc->n_generations : 1;
}

void karst_generation_view(const karst_scenario_t *sc, int g, karst_scenario_t *view) {
  *view = *sc;
  if (sc->n_generations < 1 || g < 1 || g > sc->n_generations) {
    view->active_generation = 0;
    return;
  }
  const karst_generation_t *G = &sc->generations[g - 1];
  view->routing = G->routing;
  view->gamma = G->gamma;
  view->reuse = G->reuse;
  view->amplification = G->amplification;
  view->active_generation = g;
}

int karst_generation_key_active(const karst_scenario_t *sc, int k) {
  if (k < 0 || k >= sc->n_key_points) return 0;
  int kg = sc->key_points[k].generation;
  return sc->active_generation == 0 || kg == 0 || kg == sc->active_generation;
}

double karst_generation_cohesion(const karst_scenario_t *sc, int g) {
  if (g < 2 || g > sc->n_generations) return 1.0;
  return sc->generations[g - 1].cohesion;
}

void karst_inherited_init(karst_inherited_t *h) {
  memset(h, 0, sizeof *h);
}

void karst_inherited_destroy(karst_inherited_t *h) {
  free(h->arc);
  free(h->cost);
  memset(h, 0, sizeof *h);
}

static int push_arc(karst_inherited_t *h, karst_int_t arc, double cost) {
  if (h->n == h->cap) {
    karst_int_t cap = h->cap ? 2 * h->cap : 1024;
    karst_int_t *a = realloc(h->arc, (size_t)cap * sizeof *a);
    if (!a) return -1;
    h->arc = a;
    double *c = realloc(h->cost, (size_t)cap * sizeof *c);
    if (!c) return -1;
    h->cost = c;
    h->cap = cap;
  }
  h->arc[h->n] = arc;
  h->cost[h->n] = cost;
  h->n++;
  return 0;
}

/**
 * karst_generation_discount: see generations.h. The routed cost of an arc grows with its base cost
 * (docs/generation.md, "Routing"), so an inherited conduit is cheaper to follow in both stages,
 * and every lower bound of the A* heuristics stays one when multiplied by min(1, factor).
 * Time complexity: O(edges log degree).
 */
karst_error_t karst_generation_discount(karst_ctx_t *ctx, karst_graph_t *g,
                                        const karst_skeleton_t *sk, double factor,
                                        karst_inherited_t *saved) {
  if (!(factor > 0 && factor <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "generations: cohesion must be within (0, 1], got %g",
                           factor);
  const karst_network_t *net = &sk->net;
  const karst_attr_t *gen = karst_network_attr_find(net, KARST_ATTR_EDGE, "generation");
  const karst_attr_t *obs = karst_network_attr_find(net, KARST_ATTR_EDGE, "observed");
  if (!gen || factor == 1.0) return KARST_SUCCESS;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    if (!(gen->data[e] > 0) || (obs && obs->data[e] != 0)) continue;
    karst_int_t u = sk->vertex_of_node[net->edges[2 * e]],
                w = sk->vertex_of_node[net->edges[2 * e + 1]];
    for (int dir = 0; dir < 2; dir++) {
      karst_int_t a = dir ? karst_graph_find_arc(g, w, u) : karst_graph_find_arc(g, u, w);
      if (a < 0) continue;
      if (push_arc(saved, a, g->cost[a]))
        return karst_set_error(ctx, KARST_ENOMEM, "generations: out of memory");
      g->cost[a] = karst_arc_cost_round(g->cost[a] * factor);
    }
  }
  return KARST_SUCCESS;
}

void karst_generation_restore(karst_graph_t *g, karst_inherited_t *saved) {
  for (karst_int_t i = saved->n - 1; i >= 0; i--)
    g->cost[saved->arc[i]] = (karst_arc_cost_t)saved->cost[i]; /* exact: saved from a float */
  saved->n = 0;
}

/* karst_skeleton_path_fn: remember every step of every path the generation lays. */
static karst_error_t record_path(void *arg, const karst_path_t *path) {
  karst_generation_track_t *t = arg;
  for (karst_int_t i = 1; i < path->n; i++) {
    if (t->n + 2 > t->cap) {
      karst_int_t cap = t->cap ? 2 * t->cap : 4096;
      karst_int_t *p = realloc(t->pairs, (size_t)cap * sizeof *p);
      if (!p) return KARST_ENOMEM;
      t->pairs = p;
      t->cap = cap;
    }
    t->pairs[t->n++] = path->v[i - 1];
    t->pairs[t->n++] = path->v[i];
  }
  return KARST_SUCCESS;
}

void karst_generation_track_begin(karst_generation_track_t *t, karst_skeleton_t *sk, int g) {
  memset(t, 0, sizeof *t);
  t->g = g;
  t->e0 = sk->net.n_edges;
  sk->on_path = record_path;
  sk->on_path_arg = t;
}

/* splitmix64 finaliser, for the node-pair table. */
static size_t mix(uint64_t k, size_t mask) {
  k ^= k >> 30;
  k *= 0xbf58476d1ce4e5b9ULL;
  k ^= k >> 27;
  k *= 0x94d049bb133111ebULL;
  k ^= k >> 31;
  return (size_t)k & mask;
}

static uint64_t pair_key(karst_int_t a, karst_int_t b) {
  karst_int_t lo = a < b ? a : b, hi = a < b ? b : a;
  return ((uint64_t)lo << 32 | (uint64_t)hi) + 1;
}

/**
 * karst_generation_track_finish: see generations.h. Stops the recording on @p sk.
 * Time complexity: O(edges + recorded steps) expected.
 */
karst_error_t karst_generation_track_finish(karst_ctx_t *ctx, karst_generation_track_t *t,
                                            karst_skeleton_t *sk, karst_generation_stats_t *stats) {
  sk->on_path = NULL;
  sk->on_path_arg = NULL;
  karst_network_t *net = &sk->net;
  double *gen, *re;
  karst_error_t err = KARST_SUCCESS;
  uint64_t *keys = NULL;
  karst_int_t *edge = NULL;
  if (karst_network_attr_add(net, KARST_ATTR_EDGE, "generation", 1, 1, &gen) ||
      karst_network_attr_add(net, KARST_ATTR_EDGE, "reactivated", 1, 1, &re)) {
    err = karst_set_error(ctx, KARST_ENOMEM, "generations: out of memory");
    goto cleanup;
  }
  gen = karst_network_attr_find(net, KARST_ATTR_EDGE, "generation")->data;
  re = karst_network_attr_find(net, KARST_ATTR_EDGE, "reactivated")->data;
  const karst_attr_t *obs = karst_network_attr_find(net, KARST_ATTR_EDGE, "observed");
  karst_generation_stats_t st = {0, 0, 0, 0};
  for (karst_int_t e = t->e0; e < net->n_edges; e++) {
    if (obs && obs->data[e] != 0) continue;
    gen[e] = t->g;
    st.n_new_edges++;
    st.new_length += karst_network_edge_length(net, e);
  }
  /* The edges that existed before the generation, by their node pair. */
  size_t cap = 64;
  while (cap < 2 * (size_t)(t->e0 + 1))
    cap *= 2;
  keys = calloc(cap, sizeof *keys);
  edge = malloc(cap * sizeof *edge);
  if (!keys || !edge) {
    err = karst_set_error(ctx, KARST_ENOMEM, "generations: out of memory");
    goto cleanup;
  }
  for (karst_int_t e = 0; e < t->e0; e++) {
    uint64_t k = pair_key(net->edges[2 * e], net->edges[2 * e + 1]);
    size_t h = mix(k, cap - 1);
    while (keys[h] && keys[h] != k)
      h = (h + 1) & (cap - 1);
    keys[h] = k;
    edge[h] = e;
  }
  for (karst_int_t i = 0; i < t->n; i += 2) {
    karst_int_t a = sk->node_of_vertex[t->pairs[i]], b = sk->node_of_vertex[t->pairs[i + 1]];
    if (a < 0 || b < 0 || a == b) continue;
    uint64_t k = pair_key(a, b);
    size_t h = mix(k, cap - 1);
    while (keys[h] && keys[h] != k)
      h = (h + 1) & (cap - 1);
    if (!keys[h]) continue;
    karst_int_t e = edge[h];
    if (re[e] != t->g) {
      re[e] = t->g;
      st.reactivated_length += karst_network_edge_length(net, e);
    }
  }
  if (stats) {
    st.n_routes = stats->n_routes;
    *stats = st;
  }
cleanup:
  free(keys);
  free(edge);
  free(t->pairs);
  t->pairs = NULL;
  t->n = t->cap = 0;
  return err;
}
