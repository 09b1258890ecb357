/* One realisation of the generation pipeline of Paris et al. 2021 (§4–5):
 * sampling -> graph (+ costs) -> key-point paths -> γ-skeleton ->
 * amplification -> classification. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "generate/generate_internal.h"
#include "karst/amplification.h"
#include "karst/classification.h"
#include "karst/cost.h"
#include "karst/sampling.h"
#include "karst/skeleton.h"

static const char *const stage_names[KARST_STAGE_COUNT] = {
    "sampling", "graph", "paths", "skeleton", "amplification", "classification"};

/** Name of a pipeline stage ("sampling", "graph", ...); "unknown" out of range. O(1). */
const char *karst_stage_name(int stage) {
  return stage >= 0 && stage < KARST_STAGE_COUNT ? stage_names[stage] : "unknown";
}

double karst_i_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

size_t karst_i_peak_bytes(void) {
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
  return (size_t)ru.ru_maxrss * 1024u; /* Linux reports kilobytes */
}

static karst_node_kind_t key_kind(karst_keypoint_type_t t) {
  switch (t) {
  case KARST_KEYPOINT_SINK:
    return KARST_NODE_SINK;
  case KARST_KEYPOINT_SPRING:
    return KARST_NODE_SPRING;
  default:
    return KARST_NODE_WAYPOINT;
  }
}

/*
 * Connected pieces of the graph and of its key points: BFS over the CSR
 * adjacency. *pieces counts them all, *key_pieces those holding a key point
 * (vertices 0 .. n_keys-1). Returns 0, or -1 when out of memory. O(n + arcs).
 */
static int count_pieces(const karst_graph_t *g, karst_int_t n_keys, karst_int_t *pieces,
                        karst_int_t *key_pieces) {
  karst_int_t *comp = malloc(sizeof *comp * (size_t)(g->n > 0 ? g->n : 1));
  karst_int_t *queue = malloc(sizeof *queue * (size_t)(g->n > 0 ? g->n : 1));
  unsigned char *seen = calloc((size_t)(g->n > 0 ? g->n : 1), 1);
  if (!comp || !queue || !seen) {
    free(comp), free(queue), free(seen);
    return -1;
  }
  for (karst_int_t v = 0; v < g->n; v++)
    comp[v] = -1;
  karst_int_t c = 0;
  for (karst_int_t s = 0; s < g->n; s++) {
    if (comp[s] >= 0) continue;
    karst_int_t head = 0, tail = 0;
    queue[tail++] = s;
    comp[s] = c;
    while (head < tail) {
      karst_int_t u = queue[head++];
      for (karst_int_t a = g->offsets[u]; a < g->offsets[u + 1]; a++) {
        karst_int_t w = g->adj[a];
        if (comp[w] < 0) {
          comp[w] = c;
          queue[tail++] = w;
        }
      }
    }
    c++;
  }
  karst_int_t kc = 0;
  for (karst_int_t i = 0; i < n_keys && i < g->n; i++)
    if (!seen[comp[i]]) {
      seen[comp[i]] = 1;
      kc++;
    }
  *pieces = c;
  *key_pieces = kc;
  free(comp), free(queue), free(seen);
  return 0;
}

/*
 * Every key point must be joined to the others. Key points are grouped by
 * finite distance (connected components of the distance matrix); the main
 * group is the one holding the first spring (or key point 0 without a
 * spring). The first key point outside it is named in the error, at its
 * FILE:LINE:COLUMN in the scenario, with the number of connected pieces of
 * the graph and what to change.
 */
static karst_error_t check_connected(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                     const karst_graph_t *g, karst_int_t n, const double *dist) {
  karst_int_t ref = 0;
  for (karst_int_t i = 0; i < n; i++)
    if (sc->key_points[i].type == KARST_KEYPOINT_SPRING) {
      ref = i;
      break;
    }
  for (karst_int_t i = 0; i < n; i++) {
    if (dist[ref * n + i] < INFINITY) continue;
    const karst_keypoint_t *k = &sc->key_points[i], *r = &sc->key_points[ref];
    /* When the reference itself is the isolated one, name it instead. */
    karst_int_t reach_ref = 0, reach_i = 0;
    for (karst_int_t j = 0; j < n; j++) {
      reach_ref += dist[ref * n + j] < INFINITY;
      reach_i += dist[i * n + j] < INFINITY;
    }
    if (reach_ref < reach_i) k = r, r = &sc->key_points[i];
    char where[KARST_ERRMSG_MAX / 4] = "", rline[32] = "", pieces_text[256] = "";
    if (sc->path && k->line > 0)
      snprintf(where, sizeof where, "%s:%d:%d: ", sc->path, k->line, k->column > 0 ? k->column : 1);
    if (r->line > 0) snprintf(rline, sizeof rline, " (line %d)", r->line);
    karst_int_t pieces = 0, key_pieces = 0;
    if (count_pieces(g, n, &pieces, &key_pieces) == 0)
      snprintf(pieces_text, sizeof pieces_text,
               "the k-nearest-neighbour graph of %lld samples falls into %lld connected "
               "piece%s, and the %lld key points lie in %lld of them",
               (long long)g->n, (long long)pieces, pieces == 1 ? "" : "s", (long long)n,
               (long long)key_pieces);
    else
      snprintf(pieces_text, sizeof pieces_text, "the k-nearest-neighbour graph is disconnected");
    return karst_set_error(
        ctx, KARST_EUNREACHABLE,
        "%skey point '%s' at (%.2f, %.2f, %.2f) cannot be connected to '%s'%s: no path through "
        "the bedrock joins them; %s. Raise sampling.k (now %d) or lower sampling.fill_radius "
        "(now %g m) so that the samples join up, and check that the terrain or the domain box "
        "does not cut the key point off",
        where, k->name, k->p[0], k->p[1], k->p[2], r->name, rline, pieces_text, sc->sampling.k,
        sc->sampling.fill_radius);
  }
  return KARST_SUCCESS;
}

static double total_length(const karst_network_t *net) {
  double s = 0;
  for (karst_int_t e = 0; e < net->n_edges; e++)
    s += karst_network_edge_length(net, e);
  return s;
}

/*
 * Everything after the graph: key-point distances, γ-skeleton, amplification
 * (ramification + midpoint displacement), classification. Samples 0 ..
 * n_key_points-1 of the graph are the scenario's key points.
 */
karst_error_t karst_i_generate_from_graph(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                          uint64_t seed, uint64_t realisation,
                                          const karst_graph_t *g, double lb_per_metre,
                                          karst_network_t *net, karst_generate_stats_t *stats) {
  karst_error_t err = KARST_SUCCESS;
  const karst_int_t n = sc->n_key_points;
  karst_int_t *keys = NULL;
  double *dist = NULL;
  int32_t *pred = NULL;
  float *bound = NULL;
  karst_skeleton_t sk;
  int sk_ready = 0;
  karst_network_t out;
  karst_network_init(&out);
  karst_rng_t r_amp, r_class;
  double t;
  if (n < 1)
    return karst_set_error(ctx, KARST_EINVAL, "the scenario has no key point: nothing to connect");
  if (g->n < n)
    return karst_set_error(ctx, KARST_EINVAL,
                           "the graph has %lld vertices, fewer than the %lld key points",
                           (long long)g->n, (long long)n);
  if (!(sc->tortuosity >= 0 && sc->tortuosity <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "tortuosity must be within [0, 1], got %g",
                           sc->tortuosity);
  keys = malloc((size_t)n * sizeof *keys);
  dist = malloc((size_t)(n * n) * sizeof *dist);
  if (!keys || !dist) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory for %lld key points", (long long)n);
    goto cleanup;
  }
  for (karst_int_t i = 0; i < n; i++)
    keys[i] = i;

  karst_progress(ctx, "paths", 0, 1);
  t = karst_i_now();
  /* One Dijkstra per key point gives the distances and, per key point, what the skeleton
   * needs to lay its paths (see karst_paths_keypoint_distances for why rows beat A* pairs):
   * with plain union (reuse = 1) the shortest-path trees it reads the paths from; with path
   * sharing the distance rows that make its A* heuristic tight (karst_paths_astar_reuse). */
  const int sharing = sc->reuse < 1.0;
  if (n > 1 && (size_t)(n - 1) * (size_t)g->n <= KARST_I_TREE_BUDGET / sizeof(int32_t)) {
    if (sharing)
      bound = malloc((size_t)(n - 1) * (size_t)g->n * sizeof *bound);
    else
      pred = malloc((size_t)(n - 1) * (size_t)g->n * sizeof *pred);
    if (!pred && !bound) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory for the key-point trees");
      goto cleanup;
    }
  }
  err = pred    ? karst_paths_keypoint_trees(ctx, g, n, keys, dist, pred)
        : bound ? karst_paths_keypoint_bounds(ctx, g, n, keys, dist, bound)
                : karst_paths_keypoint_distances(ctx, g, n, keys, lb_per_metre,
                                                 KARST_I_KEYPOINT_METHOD, dist);
  if (err) goto cleanup;
  if ((err = check_connected(ctx, sc, g, n, dist))) goto cleanup;
  if (stats) stats->stage_seconds[KARST_STAGE_PATHS] = karst_i_now() - t;

  karst_progress(ctx, "skeleton", 0, 1);
  t = karst_i_now();
  if ((err = karst_skeleton_init(ctx, &sk, g))) goto cleanup;
  sk_ready = 1;
  karst_int_t kept = 0;
  if ((err = karst_skeleton_build(ctx, g, n, keys, dist, pred, bound, sc->gamma, sc->reuse,
                                  lb_per_metre, &sk, &kept)))
    goto cleanup;
  if (stats) {
    stats->n_skeleton_nodes = sk.net.n_nodes;
    stats->skeleton_length = total_length(&sk.net);
  }
  for (karst_int_t i = 0; i < n; i++) {
    if ((err = karst_skeleton_mark_node(ctx, &sk, g, keys[i], key_kind(sc->key_points[i].type))))
      goto cleanup;
    if (karst_network_set_label(&sk.net, sk.node_of_vertex[keys[i]], sc->key_points[i].name)) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
  }
  if (stats) {
    stats->n_skeleton_paths = kept;
    stats->stage_seconds[KARST_STAGE_SKELETON] = karst_i_now() - t;
  }

  karst_progress(ctx, "amplification", 0, 1);
  t = karst_i_now();
  karst_rng_derive(&r_amp, seed, realisation, KARST_I_STREAM_AMPLIFICATION);
  if ((err = karst_amplification_ramify(ctx, sc, g, &r_amp, NULL, &sk, NULL, NULL))) goto cleanup;
  karst_skeleton_mark_junctions(&sk);
  if ((err = karst_amplification_displace(ctx, sc, sc->tortuosity, &r_amp, NULL, &sk.net, &out)))
    goto cleanup;
  if (stats) stats->stage_seconds[KARST_STAGE_AMPLIFICATION] = karst_i_now() - t;

  karst_progress(ctx, "classification", 0, 1);
  t = karst_i_now();
  karst_rng_derive(&r_class, seed, realisation, KARST_I_STREAM_CLASSIFICATION);
  if ((err = karst_classification_run(ctx, sc, &r_class, &out))) goto cleanup;
  if (sc->name && !out.title) {
    out.title = strdup(sc->name);
    if (!out.title) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
  }
  if (stats) {
    stats->stage_seconds[KARST_STAGE_CLASSIFICATION] = karst_i_now() - t;
    stats->n_key_points = n;
    stats->n_nodes = out.n_nodes;
    stats->n_edges = out.n_edges;
    stats->total_length = total_length(&out);
  }
  karst_network_destroy(net);
  *net = out;
  karst_network_init(&out);
  karst_progress(ctx, "classification", 1, 1);
cleanup:
  if (sk_ready) karst_skeleton_destroy(&sk);
  karst_network_destroy(&out);
  free(keys);
  free(dist);
  free(pred);
  free(bound);
  return err;
}

/**
 * One realisation of Paris et al. 2021, §4–5 (see generate.h for the
 * attributes written). Each drawing stage has its own stream
 * karst_rng_derive(seed, realisation, KARST_I_STREAM_<stage>), so changing one stage's draws
 * never shifts another's, and the result does not depend on ctx->nthreads
 * (the only parallel stages — graph costs and key-point distances — compute
 * values that do not depend on the split).
 *
 * @param ctx         context (threads, progress, interrupt, errors).
 * @param sc          scenario (validated by karst_scenario_load / _check).
 * @param seed        base seed; @p realisation the realisation index.
 * @param net         initialised by the caller; receives the network.
 * @param samples     when not NULL, receives the sample cloud (else it is freed).
 * @param stats       counts and stage wall times (may be NULL).
 * @return KARST_SUCCESS; KARST_EUNREACHABLE naming a key point that cannot be
 *         connected; the errors of each stage. On failure @p net is unchanged.
 * Time complexity: sampling O(n), graph O(n k log n), paths O(K (m + n) log n)
 * for K key points, skeleton O(K³) + one A* per kept pair.
 */
karst_error_t karst_generate(karst_ctx_t *ctx, const karst_scenario_t *sc, uint64_t seed,
                             uint64_t realisation, karst_network_t *net, karst_samples_t *samples,
                             karst_generate_stats_t *stats) {
  karst_error_t err = KARST_SUCCESS;
  karst_samples_t own;
  karst_samples_t *smp = samples ? samples : &own;
  karst_graph_t g;
  karst_rng_t r;
  karst_samples_init(&own);
  karst_graph_init(&g);
  if (stats) memset(stats, 0, sizeof *stats);
  if (samples) {
    karst_samples_destroy(samples);
    karst_samples_init(samples);
  }
  if (!sc || !net) return karst_set_error(ctx, KARST_EINVAL, "generate: no scenario or network");
  if (sc->n_key_points < 1)
    return karst_set_error(ctx, KARST_EINVAL, "the scenario has no key point: nothing to connect");

  karst_progress(ctx, "sampling", 0, 1);
  double t = karst_i_now();
  karst_rng_derive(&r, seed, realisation, KARST_I_STREAM_SAMPLING);
  if ((err = karst_sampling_run(ctx, sc, &r, smp))) goto cleanup;
  if (stats) stats->stage_seconds[KARST_STAGE_SAMPLING] = karst_i_now() - t;

  karst_progress(ctx, "graph", 0, 1);
  t = karst_i_now();
  /* karst_graph_build computes the kNN graph and the edge costs together: one stage, "graph". */
  if ((err = karst_graph_build(ctx, sc, smp, &g))) goto cleanup;
  if (stats) {
    stats->stage_seconds[KARST_STAGE_GRAPH] = karst_i_now() - t;
    stats->n_samples = smp->n;
    stats->n_graph_edges = g.n_arcs / 2;
  }
  if (smp->n_key_points != sc->n_key_points) {
    err = karst_set_error(ctx, KARST_EINVAL,
                          "sampling kept %lld key points of the scenario's %d (a key point "
                          "outside the bedrock?)",
                          (long long)smp->n_key_points, sc->n_key_points);
    goto cleanup;
  }
  double lb = karst_cost_lower_bound_per_metre(sc);
  if ((err = karst_i_generate_from_graph(ctx, sc, seed, realisation, &g, lb, net, stats)))
    goto cleanup;
  if (stats) stats->peak_bytes = karst_i_peak_bytes();
cleanup:
  karst_graph_destroy(&g);
  karst_samples_destroy(&own);
  if (err && samples) {
    karst_samples_destroy(samples);
    karst_samples_init(samples);
  }
  return err;
}
