/* One realisation of the generation pipeline of Paris et al. 2021 (§4–5):
 * sampling -> graph (+ costs) -> key-point paths -> γ-skeleton ->
 * amplification -> classification. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "core/memory_internal.h"
#include "generate/generate_internal.h"
#include "karst/amplification.h"
#include "karst/classification.h"
#include "karst/conditioning.h"
#include "karst/cost.h"
#include "karst/generations.h"
#include "karst/geology.h"
#include "karst/routing.h"
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

/* The kernel's VmHWM (peak resident set of this address space) from /proc/self/status, or 0.
 * getrusage's ru_maxrss is not that: Linux carries it over execve from the address space the
 * program replaced, so a process started by posix_spawn or vfork from a large one (a notebook,
 * a benchmark, an MPI launcher) reports its parent's resident set as its own peak. */
static size_t vm_hwm_bytes(void) {
  FILE *fp = fopen("/proc/self/status", "r");
  if (!fp) return 0;
  char line[256];
  unsigned long long kib = 0;
  while (fgets(line, sizeof line, fp))
    if (strncmp(line, "VmHWM:", 6) == 0) {
      if (sscanf(line + 6, "%llu", &kib) != 1) kib = 0;
      break;
    }
  fclose(fp);
  return (size_t)kib * 1024u;
}

size_t karst_i_peak_bytes(void) {
  size_t hwm = vm_hwm_bytes();
  if (hwm > 0) return hwm;
  struct rusage ru; /* no /proc: the rusage figure (see above) */
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
  karst_int_t *comp = karst_i_alloc_large(sizeof *comp * (size_t)(g->n > 0 ? g->n : 1));
  karst_int_t *queue = karst_i_alloc_large(sizeof *queue * (size_t)(g->n > 0 ? g->n : 1));
  unsigned char *seen = karst_i_calloc_large((size_t)(g->n > 0 ? g->n : 1), 1);
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
      karst_arc_reader_t rd = karst_graph_arcs(g, u);
      for (karst_int_t a = g->offsets[u]; a < g->offsets[u + 1]; a++) {
        karst_int_t w = karst_arc_next(&rd);
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

/* Append to ctx->errmsg how the graph falls apart, when a key point cannot be reached. */
static void explain_pieces(karst_ctx_t *ctx, const karst_graph_t *g, karst_int_t n_keys) {
  karst_int_t pieces = 0, key_pieces = 0;
  if (!ctx || count_pieces(g, n_keys, &pieces, &key_pieces) != 0) return;
  size_t len = strlen(ctx->errmsg);
  snprintf(ctx->errmsg + len, KARST_ERRMSG_MAX - len,
           " (the k-nearest-neighbour graph of %lld samples falls into %lld connected piece%s, "
           "and the %lld key points lie in %lld of them)",
           (long long)g->n, (long long)pieces, pieces == 1 ? "" : "s", (long long)n_keys,
           (long long)key_pieces);
}

static double total_length(const karst_network_t *net) {
  double s = 0;
  for (karst_int_t e = 0; e < net->n_edges; e++)
    s += karst_network_edge_length(net, e);
  return s;
}

/* Mark the key points generation @p plan routed (kind, spring, name). */
static karst_error_t mark_key_points(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                     const karst_graph_t *g, const karst_routing_plan_t *plan,
                                     karst_skeleton_t *sk) {
  karst_error_t err;
  for (karst_int_t i = 0; i < sc->n_key_points; i++) {
    if (plan->active && !plan->active[i]) continue;
    if ((err = karst_skeleton_mark_node(ctx, sk, g, i, key_kind(sc->key_points[i].type))))
      return err;
    karst_int_t node = sk->node_of_vertex[i];
    karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "spring")->data[node] = plan->key_spring[i];
    if (karst_network_set_label(&sk->net, node, sc->key_points[i].name))
      return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  }
  return KARST_SUCCESS;
}

/* One generation (docs/generation.md, "Generations"): its routing on the graph whose inherited
 * conduits cost cohesion × their cost, its skeleton routes and ramification laid into @p sk.
 * @p lb is the lower bound of the graph's base cost per metre before the discount. */
static karst_error_t run_generation(karst_ctx_t *ctx, const karst_geology_t *geo, uint64_t seed,
                                    uint64_t realisation, int gi, karst_graph_t *g,
                                    const karst_int_t *station_vertex, double lb,
                                    karst_rng_t *r_amp, karst_skeleton_t *sk,
                                    karst_generate_stats_t *stats) {
  const karst_scenario_t *sc = karst_geology_scenario(geo);
  karst_error_t err = KARST_SUCCESS;
  karst_scenario_t view;
  karst_generation_view(sc, gi, &view);
  karst_geology_t *own = NULL;
  const karst_geology_t *geo_g = geo;
  karst_routing_plan_t plan;
  karst_routing_plan_init(&plan);
  karst_inherited_t saved;
  karst_inherited_init(&saved);
  karst_generation_track_t track;
  karst_generation_stats_t gst = {0, 0, 0, 0};
  int tracking = 0;
  double t = karst_i_now();
  if (sc->n_generations > 0) {
    /* The generation's own routing, skeleton and amplification parameters; the same seed gives
     * the same fracture discs as the scenario's geology. */
    if ((err = karst_geology_create(ctx, &view, seed, realisation, &own))) goto cleanup;
    geo_g = own;
  }
  double cohesion = karst_generation_cohesion(sc, gi);
  if (cohesion < 1.0 && (err = karst_generation_discount(ctx, g, sk, cohesion, &saved)))
    goto cleanup;
  const double lb_g = lb * fmin(1.0, cohesion);
  /* One backward search per spring and per waypoint gives the routed costs and what the skeleton
   * needs to lay its paths: with plain union (reuse = 1) the successor rows it reads the paths
   * from; with path sharing the rows that make its A* heuristic tight. */
  err = karst_routing_plan(ctx, geo_g, g, view.reuse >= 1.0, &plan);
  if (err == KARST_EUNREACHABLE) explain_pieces(ctx, g, sc->n_key_points);
  if (err) goto cleanup;
  if (stats) stats->stage_seconds[KARST_STAGE_PATHS] += karst_i_now() - t;

  karst_progress(ctx, "skeleton", 0, 1);
  t = karst_i_now();
  karst_generation_track_begin(&track, sk, gi);
  tracking = 1;
  karst_int_t kept = 0;
  const karst_int_t nodes_before = sk->net.n_nodes;
  const double length_before = stats ? total_length(&sk->net) : 0;
  if ((err = karst_skeleton_build_routes(ctx, g, &plan, view.reuse, lb_g, sk, &kept))) goto cleanup;
  if ((err = mark_key_points(ctx, sc, g, &plan, sk))) goto cleanup;
  if (stats) { /* S before amplification: what this generation's routes added */
    stats->n_skeleton_nodes += sk->net.n_nodes - nodes_before;
    stats->skeleton_length += total_length(&sk->net) - length_before;
  }
  if (station_vertex &&
      (err = karst_conditioning_assign_springs(ctx, &view, station_vertex, plan.key_spring, sk)))
    goto cleanup;
  gst.n_routes = kept;
  if (stats) {
    stats->n_skeleton_paths += kept;
    stats->stage_seconds[KARST_STAGE_SKELETON] += karst_i_now() - t;
  }
  karst_routing_plan_drop_rows(&plan); /* the skeleton's alone: memory for the amplification */
  karst_progress(ctx, "amplification", 0, 1);
  t = karst_i_now();
  if ((err = karst_amplification_ramify(ctx, geo_g, g, &plan, r_amp, NULL, sk, NULL, NULL)))
    goto cleanup;
  if (stats) stats->stage_seconds[KARST_STAGE_AMPLIFICATION] += karst_i_now() - t;
cleanup:
  if (tracking) {
    karst_error_t e2 = karst_generation_track_finish(ctx, &track, sk, &gst);
    if (!err) err = e2;
  }
  if (stats && gi >= 1 && gi <= KARST_SCENARIO_MAX_GENERATIONS) stats->generations[gi - 1] = gst;
  karst_generation_restore(g, &saved);
  karst_inherited_destroy(&saved);
  karst_routing_plan_destroy(&plan);
  karst_geology_free(own);
  return err;
}

/*
 * Everything after the graph: per generation routing (two-stage paths between its key points),
 * skeleton and ramification, then for the whole network midpoint displacement and
 * classification. Samples 0 .. n_key_points-1 of the graph are the scenario's key points;
 * @p station_vertex (NULL without conditioning) the graph vertex of each surveyed station, whose
 * legs the graph already carries (karst_conditioning_add_legs) and which are laid first.
 */
karst_error_t karst_i_generate_network(karst_ctx_t *ctx, const karst_geology_t *geo, uint64_t seed,
                                       uint64_t realisation, karst_graph_t *g,
                                       const karst_int_t *station_vertex, double lb_per_metre,
                                       karst_network_t *net, karst_generate_stats_t *stats) {
  karst_error_t err = KARST_SUCCESS;
  const karst_scenario_t *sc = karst_geology_scenario(geo);
  const karst_int_t n = sc->n_key_points;
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
  if (stats) {
    stats->seed = seed, stats->realisation = realisation;
    stats->n_skeleton_paths = 0;
    for (int st = KARST_STAGE_PATHS; st < KARST_STAGE_COUNT; st++)
      stats->stage_seconds[st] = 0;
  }

  t = karst_i_now();
  if ((err = karst_skeleton_init(ctx, &sk, g))) goto cleanup;
  sk_ready = 1;
  /* The surveyed legs first (edge attribute "observed"), so that every route may follow them. */
  if ((err = karst_conditioning_lay(ctx, sc, g, station_vertex, &sk))) goto cleanup;
  if (stats) { /* S counts the surveyed legs, then each generation's routes (run_generation) */
    stats->n_skeleton_nodes = sk.net.n_nodes;
    stats->skeleton_length = total_length(&sk.net);
  }
  if (stats) stats->stage_seconds[KARST_STAGE_SKELETON] += karst_i_now() - t;
  karst_rng_derive(&r_amp, seed, realisation, KARST_I_STREAM_AMPLIFICATION);
  const int G = karst_generation_count(sc);
  if (stats) stats->n_generations = G;
  const double lb = karst_conditioning_lower_bound_per_metre(sc, lb_per_metre);
  for (int gi = 1; gi <= G; gi++)
    if ((err = run_generation(ctx, geo, seed, realisation, gi, g, station_vertex, lb, &r_amp, &sk,
                              stats)))
      goto cleanup;

  karst_progress(ctx, "amplification", 0, 1);
  t = karst_i_now();
  karst_skeleton_mark_junctions(&sk);
  if ((err = karst_amplification_displace(ctx, geo, sc->tortuosity, &r_amp, NULL, &sk.net, &out)))
    goto cleanup;
  if (stats) stats->stage_seconds[KARST_STAGE_AMPLIFICATION] += karst_i_now() - t;

  karst_progress(ctx, "classification", 0, 1);
  t = karst_i_now();
  karst_rng_derive(&r_class, seed, realisation, KARST_I_STREAM_CLASSIFICATION);
  if ((err = karst_classification_run(ctx, geo, &r_class, &out))) goto cleanup;
  if (station_vertex &&
      (err = karst_conditioning_passage_radius(ctx, sc, station_vertex, &sk, &out)))
    goto cleanup;
  {
    /* What the integer codes of "zone" and "spring" stand for, as field data of network.vtp. */
    const char *zones[KARST_ZONE_COUNT], *springs[KARST_SCENARIO_MAX_SPRINGS];
    int ns = karst_geology_n_springs(geo);
    for (int z = 0; z < KARST_ZONE_COUNT; z++)
      zones[z] = karst_zone_name(z);
    for (int i = 0; i < ns && i < KARST_SCENARIO_MAX_SPRINGS; i++)
      springs[i] = sc->key_points[karst_geology_spring_key(geo, i)].name;
    if (karst_network_set_strings(&out, "zone_names", KARST_ZONE_COUNT, zones) ||
        karst_network_set_strings(&out, "spring_names",
                                  ns < KARST_SCENARIO_MAX_SPRINGS ? ns : KARST_SCENARIO_MAX_SPRINGS,
                                  springs)) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    if (sc->n_generations > 0) {
      const char *gens[KARST_SCENARIO_MAX_GENERATIONS + 1];
      gens[0] = "observed";
      for (int i = 0; i < sc->n_generations && i < KARST_SCENARIO_MAX_GENERATIONS; i++)
        gens[i + 1] = sc->generations[i].name;
      if (karst_network_set_strings(&out, "generation_names", sc->n_generations + 1, gens)) {
        err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
        goto cleanup;
      }
    }
  }
  if (sc->name && !out.title) {
    out.title = strdup(sc->name);
    if (!out.title) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
  }
  if (sc->crs && karst_network_set_crs(&out, sc->crs)) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  if (stats) {
    stats->stage_seconds[KARST_STAGE_CLASSIFICATION] = karst_i_now() - t;
    stats->n_key_points = n;
    stats->n_nodes = out.n_nodes;
    stats->n_edges = out.n_edges;
    stats->total_length = total_length(&out);
    const karst_attr_t *obs = karst_network_attr_find(&out, KARST_ATTR_EDGE, "observed");
    stats->n_observed_edges = 0;
    stats->observed_length = 0;
    for (karst_int_t e = 0; obs && e < out.n_edges; e++)
      if (obs->data[e] != 0)
        stats->n_observed_edges++, stats->observed_length += karst_network_edge_length(&out, e);
  }
  karst_network_destroy(net);
  *net = out;
  karst_network_init(&out);
  karst_progress(ctx, "classification", 1, 1);
cleanup:
  if (sk_ready) karst_skeleton_destroy(&sk);
  karst_network_destroy(&out);
  return err;
}

/* The pipeline after the graph on a graph without surveyed legs (tests and benchmarks). */
karst_error_t karst_i_generate_from_graph(karst_ctx_t *ctx, const karst_geology_t *geo,
                                          uint64_t seed, uint64_t realisation, karst_graph_t *g,
                                          double lb_per_metre, karst_network_t *net,
                                          karst_generate_stats_t *stats) {
  return karst_i_generate_network(ctx, geo, seed, realisation, g, NULL, lb_per_metre, net, stats);
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
  karst_geology_t *geo = NULL;
  karst_int_t *station_vertex = NULL;
  const karst_survey_set_t *survey = sc ? sc->conditioning.data : NULL;
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
  if ((err = karst_geology_create(ctx, sc, seed, realisation, &geo))) goto cleanup;
  karst_rng_derive(&r, seed, realisation, KARST_I_STREAM_SAMPLING);
  if ((err = karst_sampling_run(ctx, geo, &r, smp))) goto cleanup;
  smp->crs = sc->crs;
  if (survey) {
    /* The surveyed stations among the samples (src/conditioning/). */
    station_vertex =
        malloc((size_t)(survey->n_stations > 0 ? survey->n_stations : 1) * sizeof *station_vertex);
    if (!station_vertex) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory for the surveyed stations");
      goto cleanup;
    }
    if ((err = karst_conditioning_add_samples(ctx, sc, smp, station_vertex))) goto cleanup;
  }
  if (stats) stats->stage_seconds[KARST_STAGE_SAMPLING] = karst_i_now() - t;

  karst_progress(ctx, "graph", 0, 1);
  t = karst_i_now();
  /* karst_graph_build computes the kNN graph and the edge costs together: one stage, "graph". */
  if ((err = karst_graph_build(ctx, geo, smp, &g))) goto cleanup;
  if (stats) {
    stats->stage_seconds[KARST_STAGE_GRAPH] = karst_i_now() - t;
    stats->n_samples = smp->n;
    stats->n_points_kept = 0;
    for (karst_int_t i = 0; i < smp->n; i++)
      stats->n_points_kept += smp->source[i] == KARST_SAMPLE_POINTS;
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
  if (survey) {
    t = karst_i_now();
    if ((err = karst_conditioning_add_legs(ctx, sc, station_vertex, lb, &g))) goto cleanup;
    if (stats) stats->stage_seconds[KARST_STAGE_GRAPH] += karst_i_now() - t;
  }
  if ((err = karst_i_generate_network(ctx, geo, seed, realisation, &g, station_vertex, lb, net,
                                      stats)))
    goto cleanup;
  if (stats) stats->peak_bytes = karst_i_peak_bytes();
cleanup:
  karst_graph_destroy(&g);
  karst_geology_free(geo);
  free(station_vertex);
  karst_samples_destroy(&own);
  if (err && samples) {
    karst_samples_destroy(samples);
    karst_samples_init(samples);
  }
  return err;
}
