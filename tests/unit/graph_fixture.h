/* Graphs built inside the path-stage tests (test_paths, test_skeleton,
 * test_amplification, test_generate), independent of the sampling and graph
 * modules: a CSR builder, brute-force k-nearest-neighbour graphs and a
 * midpoint-rule line integral of the cost of Paris et al. 2021, §4.2, written
 * here from the paper so the tests do not test the library against itself. */
#ifndef KARST_TEST_GRAPH_FIXTURE_H
#define KARST_TEST_GRAPH_FIXTURE_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "karst.h"

/* Cost of segment a-b, user data. */
typedef double (*fx_cost_fn)(const double *a, const double *b, void *user);

/* Free a graph made here (the library's destroy belongs to the graph module). */
static inline void fx_graph_free(karst_graph_t *g) {
  karst_graph_destroy(g);
}

/* CSR from an undirected edge list (both directions, same cost), neighbours
 * in insertion order; duplicates are kept (the searches cope). */
static inline void fx_graph_from_edges(karst_graph_t *g, karst_int_t n, const double *xyz,
                                       karst_int_t m, const karst_int_t *u, const karst_int_t *v,
                                       const double *cost) {
  karst_graph_init(g);
  karst_int_t *offsets = calloc((size_t)n + 1, sizeof *offsets);
  int32_t *adj = malloc((size_t)(2 * m + 1) * sizeof *adj);
  karst_arc_cost_t *c = malloc((size_t)(2 * m + 1) * sizeof *c);
  for (karst_int_t e = 0; e < m; e++)
    offsets[u[e] + 1]++, offsets[v[e] + 1]++;
  for (karst_int_t i = 0; i < n; i++)
    offsets[i + 1] += offsets[i];
  karst_int_t *fill = calloc((size_t)n + 1, sizeof *fill);
  for (karst_int_t e = 0; e < m; e++) {
    karst_int_t a = offsets[u[e]] + fill[u[e]]++;
    adj[a] = (int32_t)v[e];
    c[a] = karst_arc_cost_round(cost[e]);
    karst_int_t b = offsets[v[e]] + fill[v[e]]++;
    adj[b] = (int32_t)u[e];
    c[b] = karst_arc_cost_round(cost[e]);
  }
  free(fill);
  /* The library keeps the rows as given (unsorted, duplicates included). */
  if (karst_graph_from_rows(NULL, g, n, xyz, offsets, adj, c) != KARST_SUCCESS) abort();
  free(offsets), free(adj), free(c);
}

/* Undirected k-nearest-neighbour graph by brute force (ties by index). */
static inline void fx_knn_graph(karst_graph_t *g, karst_int_t n, const double *xyz, int k,
                                fx_cost_fn cost, void *user) {
  karst_int_t cap = n * k, m = 0;
  karst_int_t *u = malloc((size_t)(cap + 1) * sizeof *u),
              *v = malloc((size_t)(cap + 1) * sizeof *v);
  double *c = malloc((size_t)(cap + 1) * sizeof *c);
  karst_int_t *best = malloc((size_t)(k + 1) * sizeof *best);
  double *bd = malloc((size_t)(k + 1) * sizeof *bd);
  for (karst_int_t i = 0; i < n; i++) {
    int nb = 0;
    for (karst_int_t j = 0; j < n; j++) {
      if (j == i) continue;
      double dx = xyz[3 * i] - xyz[3 * j], dy = xyz[3 * i + 1] - xyz[3 * j + 1],
             dz = xyz[3 * i + 2] - xyz[3 * j + 2];
      double d = dx * dx + dy * dy + dz * dz;
      int pos = nb;
      while (pos > 0 && bd[pos - 1] > d)
        pos--;
      if (pos >= k) continue;
      int last = nb < k ? nb : k - 1;
      for (int q = last; q > pos; q--)
        bd[q] = bd[q - 1], best[q] = best[q - 1];
      bd[pos] = d;
      best[pos] = j;
      if (nb < k) nb++;
    }
    for (int q = 0; q < nb; q++) {
      karst_int_t j = best[q];
      /* keep each undirected edge once: i<j always; j<i only if i is not among j's k nearest
       * (cheap approximation: duplicates are harmless for the searches) */
      u[m] = i < j ? i : j;
      v[m] = i < j ? j : i;
      c[m] = cost(&xyz[3 * u[m]], &xyz[3 * v[m]], user);
      m++;
    }
  }
  fx_graph_from_edges(g, n, xyz, m, u, v, c);
  free(u), free(v), free(c), free(best), free(bd);
}

/* Points on a jittered grid nx × ny × nz with spacing h from origin o (jitter ± j·h). */
static inline double *fx_jittered_grid(int nx, int ny, int nz, double h, const double o[3],
                                       double j, karst_rng_t *rng) {
  double *p = malloc((size_t)nx * ny * nz * 3 * sizeof *p);
  karst_int_t i = 0;
  for (int z = 0; z < nz; z++)
    for (int y = 0; y < ny; y++)
      for (int x = 0; x < nx; x++, i++) {
        p[3 * i] = o[0] + h * (x + (nx > 1 ? j * (2 * karst_rng_uniform(rng) - 1) : 0));
        p[3 * i + 1] = o[1] + h * (y + (ny > 1 ? j * (2 * karst_rng_uniform(rng) - 1) : 0));
        p[3 * i + 2] = o[2] + h * (z + (nz > 1 ? j * (2 * karst_rng_uniform(rng) - 1) : 0));
      }
  return p;
}

static inline double fx_euclid_cost(const double *a, const double *b, void *user) {
  (void)user;
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

/* c(p, d) = w0 + wL g(|z − horizon|/r) + wF Σ w_k (n_k·d)² + wπ π(p), Paris et al. 2021
 * §4.2, from the scenario's weights, integrated along the segment with the midpoint rule on
 * `steps` pieces. */
typedef struct {
  const karst_scenario_t *sc;
  int steps;
} fx_cost_ctx_t;

static inline double fx_smoothstep(double x) {
  x = x < 0 ? 0 : (x > 1 ? 1 : x);
  return x * x * (3 - 2 * x);
}

static inline double fx_scenario_cost(const double *a, const double *b, void *user) {
  const fx_cost_ctx_t *cc = user;
  const karst_scenario_t *sc = cc->sc;
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (len == 0) return 0;
  for (int k = 0; k < 3; k++)
    d[k] /= len;
  double cf = 0, wmax = 0;
  const int use_min = sc->cost.fracture_combine == KARST_FRACTURE_MIN;
  for (int f = 0; f < sc->n_fractures; f++)
    if (sc->fractures[f].weight > wmax) wmax = sc->fractures[f].weight;
  if (use_min) cf = wmax; /* the brief's min form: min_k [W − w_k (1 − (n_k·d)^2)], W = max w_k */
  for (int f = 0; f < sc->n_fractures; f++) {
    double nrm[3];
    karst_plane_normal(sc->fractures[f].dip_direction, sc->fractures[f].dip, nrm);
    double c = nrm[0] * d[0] + nrm[1] * d[1] + nrm[2] * d[2];
    /* The paper's text (§4.2, Fig. 7): directions parallel to the fracture plane are cheaper
     * than orthogonal ones; with n the plane's normal that is w (n·d)^2 (its printed formula
     * w (1 − (n·d)^2) holds for n a direction in the plane). */
    if (use_min) {
      double t = wmax - sc->fractures[f].weight * (1 - c * c);
      if (t < cf) cf = t;
    } else {
      cf += sc->fractures[f].weight * c * c;
    }
  }
  double sum = 0;
  for (int s = 0; s < cc->steps; s++) {
    double t = (s + 0.5) / cc->steps;
    double p[3] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    double cl = 1.0;
    for (int h = 0; h < sc->n_horizons; h++) {
      double v = fx_smoothstep(fabs(p[2] - sc->horizons[h].elevation) / sc->horizons[h].radius);
      if (v < cl) cl = v;
    }
    if (sc->n_horizons == 0) cl = 0;
    sum += sc->cost.w0 + sc->cost.horizon * cl + sc->cost.fracture * cf +
           sc->cost.permeability * karst_permeability_eval(&sc->permeability, p);
  }
  return sum / cc->steps * len;
}

#endif
