/* What a scenario will cost before any work (include/karst/budget.h).
 *
 * Samples: Poisson spheres of radius r keep r from one another, so balls of radius r/2 around
 * them are disjoint and lie in the region grown by r/2; Kepler's bound (density pi/sqrt(18)
 * = 0.7405) gives at most 0.7405 V' / (pi r^3 / 6) = 1.4142 V' / r^3 samples in a region of
 * volume V' (the region grown by r/2 on every side). The fill is bounded by the whole domain
 * (bedrock fraction <= 1); the feature samples by each layer (horizons, water tables) of
 * thickness 2 feature_band + feature_radius over the domain's plan, with a factor 2 for the
 * surfaces' slopes, and by the whole domain when some rock is permeable enough to be sampled
 * at feature_radius; only the features sampling.refine names count. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "karst/budget.h"
#include "karst/routing.h"

/* Samples of radius r in a box of sides a, b, c: Kepler's bound on the box grown by r/2. */
static double packing(double a, double b, double c, double r) {
  return 1.4142135623730951 * (a + r) * (b + r) * (c + r) / (r * r * r);
}

void karst_budget_estimate(const karst_scenario_t *sc, int threads, karst_budget_t *b) {
  memset(b, 0, sizeof *b);
  if (threads < 1) threads = 1;
  double L[3];
  for (int a = 0; a < 3; a++)
    L[a] = sc->domain_max[a] - sc->domain_min[a];
  const karst_sampling_t *sp = &sc->sampling;
  double rc = sp->fill_radius, rf = sp->feature_radius;
  /* A point cloud (sampling.points) replaces the fill: at most all of its points are kept. */
  b->fill_samples = sp->points_xyz ? (double)sp->n_points : packing(L[0], L[1], L[2], rc);
  int springs = 0;
  for (int k = 0; k < sc->n_key_points; k++)
    springs += sc->key_points[k].type == KARST_KEYPOINT_SPRING;
  /* The layers sampling.refine names (horizons, each spring's water table), and one more. */
  double layers = ((sp->refine & KARST_REFINE_HORIZONS) ? sc->n_horizons : 0) +
                  ((sp->refine & KARST_REFINE_WATER_TABLE) ? springs : 0) + 1;
  double feature = 2 * layers * packing(L[0], L[1], 2 * sp->feature_band, rf);
  const karst_permeability_t *pm = &sc->permeability;
  if ((sp->refine & KARST_REFINE_PERMEABILITY) &&
      (pm->root || pm->background < sp->permeable_threshold))
    feature += packing(L[0], L[1], L[2], rf);
  b->feature_samples = feature;
  b->samples_needed = b->fill_samples + b->feature_samples + sc->n_key_points;
  double cap = (double)sp->max_samples;
  b->samples = fmin(b->samples_needed, cap);
  double k = fmin((double)sp->k, fmax(b->samples - 1, 0));
  b->edges = b->samples * k;
  b->amplification_points = karst_amplification_points_total(&sc->amplification, INFINITY, NULL);
  for (int g = 0; g < sc->n_generations; g++)
    b->amplification_points +=
        karst_amplification_points_total(&sc->generations[g].amplification, INFINITY, NULL);
  b->searches = (double)sc->n_key_points * (springs > 0 ? springs : 1) + sc->n_prescribed +
                b->amplification_points;
  b->threads = threads;
  double search_threads = fmin((double)threads, fmax(b->searches, 1));
  double m_samples = b->samples * KARST_BUDGET_BYTES_PER_SAMPLE;
  double m_edges = b->edges * KARST_BUDGET_BYTES_PER_EDGE;
  double m_search = search_threads * b->samples * KARST_BUDGET_BYTES_PER_SEARCH_SAMPLE;
  double m_amp = b->amplification_points * KARST_BUDGET_BYTES_PER_AMPLIFICATION_POINT;
  double m_route = fmin(b->edges * KARST_BUDGET_BYTES_PER_ROUTED_EDGE * (springs > 0 ? springs : 1),
                        (double)KARST_ROUTING_ARC_BUDGET);
  b->bytes = KARST_BUDGET_BYTES_BASE + m_samples + m_edges + m_search + m_amp + m_route;
  /* The key that drives the memory most. */
  double best = m_samples + m_search;
  if (b->samples_needed > cap) {
    b->driver = "sampling.max_samples", b->driver_pos = sc->pos_max_samples;
  } else if (b->feature_samples > b->fill_samples) {
    b->driver = "sampling.feature_radius", b->driver_pos = sc->pos_feature_radius;
  } else if (sp->points_xyz) {
    b->driver = "sampling.points", b->driver_pos = sc->pos_points;
  } else if (sc->pos_fill_radius.line > 0 || !(sc->pos_domain.line > 0)) {
    b->driver = "sampling.fill_radius", b->driver_pos = sc->pos_fill_radius;
  } else {
    b->driver = "domain", b->driver_pos = sc->pos_domain;
  }
  if (m_edges + m_route > best && (sc->pos_k.line > 0 || b->driver_pos.line == 0)) {
    best = m_edges + m_route;
    b->driver = "sampling.k", b->driver_pos = sc->pos_k;
  }
  if (m_amp > best && (sc->pos_amplification_points.line > 0 || b->driver_pos.line == 0)) {
    b->driver = "amplification.points", b->driver_pos = sc->pos_amplification_points;
  }
  if (!b->driver_pos.line) b->driver_pos = sc->pos_sampling;
}

double karst_budget_machine_memory(void) {
  long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  return pages > 0 && size > 0 ? (double)pages * (double)size : 0;
}

int karst_budget_parse_size(const char *s, double *bytes) {
  if (!s || !*s) return -1;
  char *end;
  double v = strtod(s, &end);
  if (end == s || !isfinite(v) || !(v > 0)) return -1;
  double unit = 1;
  switch (*end) {
  case 'k':
  case 'K':
    unit = 1024.0;
    end++;
    break;
  case 'm':
  case 'M':
    unit = 1024.0 * 1024;
    end++;
    break;
  case 'g':
  case 'G':
    unit = 1024.0 * 1024 * 1024;
    end++;
    break;
  case 't':
  case 'T':
    unit = 1024.0 * 1024 * 1024 * 1024;
    end++;
    break;
  default:
    break;
  }
  if (unit > 1 && *end == 'i') end++;
  if (*end == 'B' || *end == 'b') end++;
  if (*end) return -1;
  *bytes = v * unit;
  return 0;
}

const char *karst_budget_format_size(double bytes, char *buf, size_t size) {
  static const char *const unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (u < 6 && bytes >= 1024) {
    bytes /= 1024;
    u++;
  }
  if (!isfinite(bytes))
    snprintf(buf, size, "more than any machine has");
  else
    snprintf(buf, size, u ? "%.3g %s" : "%.0f %s", bytes, unit[u]);
  return buf;
}

/* FILE:LINE:COLUMN of the key at @p pos (karst_scenario_fail_at). */
#define refuse(ctx, sc, pos, ...)                                                                  \
  karst_scenario_fail_at((ctx), (sc), (pos).line, (pos).column, KARST_ERANGE, __VA_ARGS__)

karst_error_t karst_budget_check(karst_ctx_t *ctx, const karst_scenario_t *sc, int threads,
                                 double max_memory, karst_budget_t *out) {
  karst_budget_t b;
  karst_budget_estimate(sc, threads, &b);
  if (out) *out = b;
  char need[48], have[48];
  if (sc->amplification.steps > KARST_BUDGET_MAX_AMPLIFICATION_STEPS)
    return refuse(ctx, sc, sc->pos_amplification_steps,
                  "amplification.steps is %d, more than %d: each step is a round of path "
                  "searches on the whole graph",
                  sc->amplification.steps, KARST_BUDGET_MAX_AMPLIFICATION_STEPS);
  /* A sample count no run could reach: sampling would refuse it after allocating its grids
   * (or overflow them); refuse it here, where the key is known. */
  double cap = (double)sc->sampling.max_samples;
  if (!isfinite(b.samples_needed) || b.samples_needed > 1e15 || (b.samples_needed > 1000 * cap)) {
    int feat = b.feature_samples > b.fill_samples;
    karst_srcpos_t pos = feat ? sc->pos_feature_radius : sc->pos_fill_radius;
    if (!pos.line) pos = sc->pos_domain;
    return refuse(ctx, sc, pos,
                  "the domain (%.4g x %.4g x %.4g m) at %s %g m needs up to %.4g samples, "
                  "beyond any run (sampling.max_samples = %lld); raise the radius or shrink "
                  "the domain",
                  sc->domain_max[0] - sc->domain_min[0], sc->domain_max[1] - sc->domain_min[1],
                  sc->domain_max[2] - sc->domain_min[2],
                  feat ? "sampling.feature_radius" : "sampling.fill_radius",
                  feat ? sc->sampling.feature_radius : sc->sampling.fill_radius, b.samples_needed,
                  (long long)sc->sampling.max_samples);
  }
  double limit = max_memory > 0 ? max_memory : karst_budget_machine_memory();
  if (limit > 0 && !(b.bytes <= limit))
    return refuse(ctx, sc, b.driver_pos,
                  "%s: the run needs an estimated %s of memory (%.4g samples, %.4g graph edges, "
                  "%.4g path searches, %.4g amplification points), more than the limit of %s "
                  "(--max-memory)",
                  b.driver, karst_budget_format_size(b.bytes, need, sizeof need), b.samples,
                  b.edges, b.searches, b.amplification_points,
                  karst_budget_format_size(limit, have, sizeof have));
  return KARST_SUCCESS;
}
