/* Karst network metrics of Collon et al. 2017 exactly as Karstnet 1.2.0 computes them.
 *
 * Collon P., Bernasconi D., Vuilleumier C., Renard P. (2017, corrected 2021) Statistical metrics
 * for the characterization of karst network geometry and topology, Geomorphology 283:122-142.
 * Every rule that changes a number is listed in docs/metrics.md; the comments below say which. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "karst/metrics.h"
#include "metrics/metrics_internal.h"

/* numpy.degrees multiplies by this constant; using the same product keeps
 * azimuths bit-identical to Karstnet's. */
static const double rad2deg = 180.0 / M_PI;

/* Bins of the two entropies (Collon et al. 2017, §3.2): 10 bins on [0, 100] for
 * normalised branch lengths, 18 bins of 10 degrees on [0, 180] for azimuths. */
enum { LENGTH_BINS = 10, AZIMUTH_BINS = 18 };

void karst_metrics_options_init(karst_metrics_options_t *opt) {
  memset(opt, 0, sizeof *opt);
  opt->azimuth_rotation = 0.0;
}

#define F_INT(name, unit, label)                                                                   \
  { #name, offsetof(karst_metrics_t, name), 1, unit, label }
#define F_DBL(name, unit, label)                                                                   \
  { #name, offsetof(karst_metrics_t, name), 0, unit, label }
/* Units: "m", "count", "edges" (hop counts on Gs), "1" (dimensionless); docs/metrics.md. */
static const karst_metric_field_t fields[] = {
    F_INT(nodes, "count", "nodes of the full graph"),
    F_INT(edges, "count", "edges of the full graph"),
    F_DBL(mean_length, "m", "mean branch length"),
    F_DBL(cv_length, "1", "coefficient of variation of branch length"),
    F_DBL(length_entropy, "1", "branch-length entropy (0 to 1)"),
    F_DBL(tortuosity, "1", "mean branch tortuosity (length / chord)"),
    F_DBL(orientation_entropy, "1", "orientation entropy (0 to 1)"),
    F_DBL(aspl, "edges", "average shortest path length on Gs"),
    F_DBL(cpd, "1", "central point dominance"),
    F_DBL(mean_degree, "1", "mean node degree on Gs"),
    F_DBL(cv_degree, "1", "coefficient of variation of degree"),
    F_DBL(correlation_vertex_degree, "1", "degree correlation of adjacent nodes"),
    F_INT(reduced_nodes, "count", "nodes of Gs"),
    F_INT(reduced_edges, "count", "edges of Gs"),
    F_INT(components, "count", "connected components"),
    F_INT(cycles, "count", "independent cycles"),
    F_DBL(howard_alpha, "1", "Howard's alpha"),
    F_DBL(howard_beta, "1", "Howard's beta"),
    F_DBL(howard_gamma, "1", "Howard's gamma"),
    F_INT(extremities, "count", "extremities (nodes of degree 1)"),
    F_INT(junctions, "count", "junctions (nodes of degree 3 or more)"),
    F_INT(branches, "count", "branches"),
    F_DBL(total_length, "m", "total conduit length"),
    F_DBL(vertical_extent, "m", "vertical extent"),
};
#undef F_INT
#undef F_DBL

const karst_metric_field_t *karst_metric_fields(int *n) {
  if (n) *n = (int)(sizeof fields / sizeof fields[0]);
  return fields;
}

double karst_metric_value(const karst_metrics_t *m, const karst_metric_field_t *f) {
  const char *p = (const char *)m + f->offset;
  if (f->is_int) {
    karst_int_t v;
    memcpy(&v, p, sizeof v);
    return (double)v;
  }
  double d;
  memcpy(&d, p, sizeof d);
  return d;
}

/* ------------------------------------------------------------------------ */
/* Simple graph                                                              */
/* ------------------------------------------------------------------------ */

static void sort_small(karst_int_t *a, karst_int_t n) {
  for (karst_int_t i = 1; i < n; i++) {
    karst_int_t x = a[i], j = i;
    while (j > 0 && a[j - 1] > x) {
      a[j] = a[j - 1];
      j--;
    }
    a[j] = x;
  }
}

static int cmp_int(const void *a, const void *b) {
  karst_int_t x = *(const karst_int_t *)a, y = *(const karst_int_t *)b;
  return (x > y) - (x < y);
}

/* Each unordered pair of @p pairs once, as (u <= v), sorted by (u, v): what
 * networkx.Graph.add_edges_from keeps (a repeated edge, in either direction,
 * counts once; a self-loop is kept). Counting sort on u, O(m + n). */
static karst_error_t dedupe_pairs(karst_ctx_t *ctx, karst_int_t n, karst_int_t m,
                                  const karst_int_t *pairs, karst_int_t **out, karst_int_t *mout) {
  karst_error_t err = KARST_SUCCESS;
  karst_int_t *start = calloc((size_t)n + 1, sizeof *start);
  karst_int_t *vs = malloc((size_t)(m > 0 ? m : 1) * sizeof *vs);
  karst_int_t *res = malloc((size_t)(m > 0 ? m : 1) * 2 * sizeof *res);
  if (!start || !vs || !res) {
    err = karst_set_error(ctx, KARST_ENOMEM, "%lld edges: out of memory", (long long)m);
    free(res);
    goto cleanup;
  }
  for (karst_int_t e = 0; e < m; e++) {
    karst_int_t a = pairs[2 * e], b = pairs[2 * e + 1];
    start[(a < b ? a : b) + 1]++;
  }
  for (karst_int_t v = 0; v < n; v++)
    start[v + 1] += start[v];
  for (karst_int_t e = 0; e < m; e++) {
    karst_int_t a = pairs[2 * e], b = pairs[2 * e + 1];
    karst_int_t u = a < b ? a : b;
    vs[start[u]++] = a < b ? b : a;
  }
  /* start[u] now ends bucket u; bucket u begins at start[u-1] (0 for u = 0). */
  karst_int_t k = 0, begin = 0;
  for (karst_int_t u = 0; u < n; u++) {
    karst_int_t end = start[u], len = end - begin;
    if (len > 16)
      qsort(vs + begin, (size_t)len, sizeof *vs, cmp_int);
    else
      sort_small(vs + begin, len);
    for (karst_int_t i = begin; i < end; i++) {
      if (i > begin && vs[i] == vs[i - 1]) continue;
      res[2 * k] = u;
      res[2 * k + 1] = vs[i];
      k++;
    }
    begin = end;
  }
  *out = res;
  *mout = k;
cleanup:
  free(start);
  free(vs);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Histogram entropy (numpy.histogram + scipy.stats.entropy)                */
/* ------------------------------------------------------------------------ */

/* numpy.histogram's bin of x for nb bins of width w on [0, nb*w]; the edges
 * i*w are exact here (w = 10), a value on an edge goes to the upper bin and the
 * last bin is closed. -1 when outside. */
static int bin_of(double x, int nb, double w) {
  if (!(x >= 0.0) || !(x <= nb * w)) return -1;
  int i = (int)(x / w);
  if (i >= nb) i = nb - 1;
  if (x < i * w)
    i--;
  else if (i < nb - 1 && x >= (i + 1) * w)
    i++;
  return i;
}

/* H = -sum p ln p / ln nb with p the normalised bin weights (scipy.stats.entropy with base nb). */
static double entropy_of(const double *count, int nb) {
  double tot = 0.0, h = 0.0;
  for (int i = 0; i < nb; i++)
    tot += count[i];
  if (!(tot > 0.0)) return NAN;
  for (int i = 0; i < nb; i++) {
    double p = count[i] / tot;
    if (p > 0.0) h -= p * log(p);
  }
  return h / log((double)nb);
}

/* Azimuth of a horizontal direction (dx east, dy north) as Karstnet 1.2.0
 * computes it (KGraph._set_graph_orientations): arcsin in the NE/SW quadrants,
 * 90 + arccos elsewhere, folded by fmod(., 180) so that north-south gives 0,
 * never 180. Same operations in the same order, hence the same bits. */
static double karstnet_azimuth(double dx, double dy, double l2d) {
  double az;
  if (dx * dy > 0)
    az = asin(fabs(dx) / l2d) * rad2deg;
  else
    az = 90.0 + acos(fabs(dx) / l2d) * rad2deg;
  return fmod(az, 180.0);
}

/* ------------------------------------------------------------------------ */
/* Branches                                                                  */
/* ------------------------------------------------------------------------ */

typedef struct {
  karst_int_t n, m; /* all network nodes; simple-graph edges */
  const double *xyz;
  karst_int_t *ed;              /* 2m, u <= v */
  double *elen;                 /* m 3-D lengths */
  karst_int_t *deg;             /* n, a self-loop adds 2 */
  karst_int_t *off, *nbr, *eid; /* incidence lists, a self-loop stored once */
  /* branches: nodes of branch b are bnode[boff[b] .. boff[b+1]-1] */
  karst_int_t nb, nb_cap, nn_cap;
  karst_int_t *boff, *bnode;
  double *blen;
  unsigned char *used;
} full_graph_t;

static karst_error_t push_node(full_graph_t *g, karst_int_t v) {
  karst_int_t k = g->boff[g->nb + 1];
  if (k == g->nn_cap) return KARST_ENOMEM; /* cannot happen: capacity is m + branches bound */
  g->bnode[k] = v;
  g->boff[g->nb + 1] = k + 1;
  return KARST_SUCCESS;
}

/* Follow one branch from node s along incidence slot k through degree-2
 * nodes until a node of degree != 2 or s again (Karstnet's _getbranch). */
static karst_error_t walk(full_graph_t *g, karst_int_t s, karst_int_t k) {
  karst_error_t err;
  g->boff[g->nb + 1] = g->boff[g->nb];
  if ((err = push_node(g, s))) return err;
  double len = 0.0;
  karst_int_t e = g->eid[k], x = g->nbr[k];
  for (;;) {
    g->used[e] = 1;
    len += g->elen[e];
    if ((err = push_node(g, x))) return err;
    if (x == s || g->deg[x] != 2) break;
    /* x has degree 2 and no self-loop (else it would be isolated, i.e. x == s): take the other
     * edge. */
    karst_int_t k2 = g->off[x];
    if (g->eid[k2] == e) k2++;
    e = g->eid[k2];
    x = g->nbr[k2];
  }
  g->blen[g->nb] = len;
  g->nb++;
  return KARST_SUCCESS;
}

/* Every branch: first from each node of degree != 2 along each unused edge,
 * then one walk per ring (a component made only of degree-2 nodes). Each edge
 * belongs to exactly one branch. O(n + m). */
static karst_error_t all_branches(full_graph_t *g) {
  karst_error_t err = KARST_SUCCESS;
  for (int pass = 0; pass < 2; pass++)
    for (karst_int_t s = 0; s < g->n; s++) {
      if (g->deg[s] == 0 || ((g->deg[s] == 2) != (pass == 1))) continue;
      for (karst_int_t k = g->off[s]; k < g->off[s + 1]; k++)
        if (!g->used[g->eid[k]] && (err = walk(g, s, k))) return err;
    }
  return err;
}

/* ------------------------------------------------------------------------ */
/* Reduced graph Gs                                                           */
/* ------------------------------------------------------------------------ */

typedef struct {
  karst_int_t a, b, idx;
} bkey_t;

static int cmp_bkey(const void *p, const void *q) {
  const bkey_t *x = p, *y = q;
  if (x->a != y->a) return (x->a > y->a) - (x->a < y->a);
  if (x->b != y->b) return (x->b > y->b) - (x->b < y->b);
  return (x->idx > y->idx) - (x->idx < y->idx);
}

/* Karstnet's _split_branches: a loop branch of m listed nodes is cut into 3 at
 * k = floor(m/3) and 2k (m = 3: in 2 at 1; m = 2, a self-loop, stays whole);
 * when several branches share their end nodes each one with intermediate nodes
 * is cut in 2 at floor(m/2). The pieces' end nodes become the edges of Gs. */
static void cut_branch(const full_graph_t *g, karst_int_t b, int shared, karst_int_t *pairs,
                       karst_int_t *np) {
  const karst_int_t *p = g->bnode + g->boff[b];
  karst_int_t m = g->boff[b + 1] - g->boff[b];
  karst_int_t cut[4], nc = 0;
  cut[nc++] = 0;
  if (p[0] == p[m - 1]) {
    if (m == 3)
      cut[nc++] = 1;
    else if (m > 3) {
      cut[nc++] = m / 3;
      cut[nc++] = 2 * (m / 3);
    }
  } else if (shared && m > 2) {
    cut[nc++] = m / 2;
  }
  cut[nc++] = m - 1;
  for (karst_int_t i = 0; i + 1 < nc; i++) {
    pairs[2 * *np] = p[cut[i]];
    pairs[2 * *np + 1] = p[cut[i + 1]];
    (*np)++;
  }
}

/* ------------------------------------------------------------------------ */

static void metrics_init_undefined(karst_metrics_t *out) {
  memset(out, 0, sizeof *out);
  out->total_length = 0.0;
  out->vertical_extent = NAN;
  out->mean_length = out->cv_length = out->length_entropy = out->tortuosity = NAN;
  out->orientation_entropy = out->aspl = out->cpd = NAN;
  out->mean_degree = out->cv_degree = out->correlation_vertex_degree = NAN;
  out->howard_alpha = out->howard_beta = out->howard_gamma = NAN;
}

/* Branch statistics: mean and cv of lengths (all branches), length entropy
 * (branches of length > 0), tortuosity (branches with distinct end points). */
static void branch_metrics(const full_graph_t *g, karst_metrics_t *out) {
  karst_int_t nb = g->nb;
  out->branches = nb;
  if (nb == 0) return;
  double sum = 0.0, maxlen = 0.0, tsum = 0.0;
  karst_int_t nt = 0;
  for (karst_int_t b = 0; b < nb; b++) {
    sum += g->blen[b];
    if (g->blen[b] > maxlen) maxlen = g->blen[b];
    const double *p = g->xyz + 3 * g->bnode[g->boff[b]];
    const double *q = g->xyz + 3 * g->bnode[g->boff[b + 1] - 1];
    /* Karstnet: the chord is computed only when the end coordinates differ. */
    if (p[0] != q[0] || p[1] != q[1] || p[2] != q[2]) {
      double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
      double chord = sqrt(dx * dx + dy * dy + dz * dz);
      if (chord != 0.0) {
        tsum += g->blen[b] / chord;
        nt++;
      }
    }
  }
  double mean = sum / (double)nb;
  out->mean_length = mean;
  if (nb > 1) {
    double ss = 0.0;
    for (karst_int_t b = 0; b < nb; b++)
      ss += (g->blen[b] - mean) * (g->blen[b] - mean);
    out->cv_length = sqrt(ss / (double)(nb - 1)) / mean;
  }
  out->tortuosity = nt > 0 ? tsum / (double)nt : NAN;
  double count[LENGTH_BINS] = {0};
  karst_int_t npos = 0;
  for (karst_int_t b = 0; b < nb; b++)
    if (g->blen[b] != 0.0) {
      int i = bin_of(g->blen[b] / maxlen * 100.0, LENGTH_BINS, 100.0 / LENGTH_BINS);
      if (i >= 0) count[i] += 1.0;
      npos++;
    }
  out->length_entropy = npos > 1 ? entropy_of(count, LENGTH_BINS) : 0.0;
}

/* Orientation entropy of the full graph's edges with a horizontal projection,
 * weighted by that projected length. */
static void orientation_metric(const full_graph_t *g, double rotation, karst_metrics_t *out) {
  double count[AZIMUTH_BINS] = {0};
  karst_int_t nh = 0;
  for (karst_int_t e = 0; e < g->m; e++) {
    const double *p = g->xyz + 3 * g->ed[2 * e], *q = g->xyz + 3 * g->ed[2 * e + 1];
    double dx = p[0] - q[0], dy = p[1] - q[1];
    double l2d = sqrt(dx * dx + dy * dy);
    if (l2d == 0.0) continue; /* vertical: no azimuth */
    double az = karstnet_azimuth(dx, dy, l2d);
    if (rotation != 0.0) {
      az = fmod(az + rotation, 180.0);
      if (az < 0.0) az += 180.0;
      if (az >= 180.0) az -= 180.0;
    }
    int i = bin_of(az, AZIMUTH_BINS, 180.0 / AZIMUTH_BINS);
    if (i >= 0) count[i] += l2d;
    nh++;
  }
  out->orientation_entropy = nh > 1 ? entropy_of(count, AZIMUTH_BINS) : 0.0;
}

/* Everything measured on Gs: counts, degrees, assortativity, aspl, cpd, Howard. */
static karst_error_t reduced_metrics(karst_ctx_t *ctx, karst_int_t n, karst_int_t S,
                                     const karst_int_t *ge, karst_metrics_t *out) {
  karst_error_t err = KARST_SUCCESS;
  karst_i_csr_t csr;
  memset(&csr, 0, sizeof csr);
  karst_int_t *deg = calloc((size_t)(n > 0 ? n : 1), sizeof *deg);
  karst_int_t *comp = malloc((size_t)(n > 0 ? n : 1) * sizeof *comp);
  karst_int_t *queue = malloc((size_t)(n > 0 ? n : 1) * sizeof *queue);
  karst_int_t *dsum = malloc((size_t)(n > 0 ? n : 1) * sizeof *dsum);
  double *bc = malloc((size_t)(n > 0 ? n : 1) * sizeof *bc);
  long long *csum = NULL;
  karst_int_t *csize = NULL;
  if (!deg || !comp || !queue || !dsum || !bc) goto nomem;
  out->reduced_nodes = n;
  out->reduced_edges = S;
  if (n == 0) goto cleanup;
  for (karst_int_t e = 0; e < S; e++) {
    deg[ge[2 * e]]++;
    deg[ge[2 * e + 1]]++; /* a self-loop adds 2, as networkx counts it */
  }
  for (karst_int_t v = 0; v < n; v++) {
    out->extremities += deg[v] == 1;
    out->junctions += deg[v] > 2;
  }
  if ((err = karst_i_csr_build(ctx, n, S, ge, &csr))) goto cleanup;
  /* connected components, numbered in order of their smallest node */
  karst_int_t p = 0;
  for (karst_int_t v = 0; v < n; v++)
    comp[v] = -1;
  for (karst_int_t s = 0; s < n; s++) {
    if (comp[s] >= 0) continue;
    karst_int_t head = 0, tail = 0;
    comp[s] = p;
    queue[tail++] = s;
    while (head < tail) {
      karst_int_t v = queue[head++];
      for (karst_int_t k = csr.off[v]; k < csr.off[v + 1]; k++)
        if (comp[csr.adj[k]] < 0) {
          comp[csr.adj[k]] = p;
          queue[tail++] = csr.adj[k];
        }
    }
    p++;
  }
  out->components = p;
  out->cycles = S - n + p;
  double N = (double)n;
  if (n >= 3) {
    /* Howard et al. 1970 as Karstnet's basic_analysis; undefined below 3 nodes. */
    out->howard_alpha = (double)out->cycles / (2.0 * N - 5.0);
    out->howard_gamma = (double)S / (3.0 * (N - 2.0));
  }
  out->howard_beta = (double)S / N;
  out->mean_degree = 2.0 * (double)S / N;
  if (n > 1) {
    double mean = out->mean_degree, ss = 0.0;
    for (karst_int_t v = 0; v < n; v++)
      ss += ((double)deg[v] - mean) * ((double)deg[v] - mean);
    out->cv_degree = sqrt(ss / (N - 1.0)) / mean;
  }
  if (out->cv_degree == 0.0) {
    out->correlation_vertex_degree = 1.0; /* Karstnet: all degrees equal */
  } else if (S > 0) {
    /* Pearson correlation of (deg u, deg v) over networkx's node_degree_xy pairs:
     * every edge in both directions, a self-loop once (Newman 2003). */
    double sx = 0.0, np_ = 0.0;
    for (karst_int_t e = 0; e < S; e++) {
      double du = (double)deg[ge[2 * e]], dv = (double)deg[ge[2 * e + 1]];
      if (ge[2 * e] == ge[2 * e + 1]) {
        sx += du;
        np_ += 1.0;
      } else {
        sx += du + dv;
        np_ += 2.0;
      }
    }
    double mx = sx / np_, cov = 0.0, var = 0.0;
    for (karst_int_t e = 0; e < S; e++) {
      double a = (double)deg[ge[2 * e]] - mx, b = (double)deg[ge[2 * e + 1]] - mx;
      if (ge[2 * e] == ge[2 * e + 1]) {
        cov += a * a;
        var += a * a;
      } else {
        cov += 2.0 * a * b;
        var += a * a + b * b;
      }
    }
    /* x and y have the same values (each pair also appears reversed), so var_x = var_y. */
    if (np_ >= 2.0 && var > 0.0) out->correlation_vertex_degree = cov / var;
  }
  /* One BFS per node gives both the betweenness (cpd) and the distance sums (aspl). */
  if ((err = karst_i_paths_all_sources(ctx, &csr, bc, dsum))) goto cleanup;
  csum = calloc((size_t)p, sizeof *csum);
  csize = calloc((size_t)p, sizeof *csize);
  if (!csum || !csize) goto nomem;
  for (karst_int_t v = 0; v < n; v++) {
    csum[comp[v]] += dsum[v];
    csize[comp[v]]++;
  }
  /* Karstnet's average_SPL: per component the mean over ordered pairs
   * (networkx, 0 for a single node), weighted by the component's size. */
  double acc = 0.0;
  for (karst_int_t c = 0; c < p; c++) {
    double nc = (double)csize[c];
    double mean_c = csize[c] > 1 ? (double)csum[c] / (nc * (nc - 1.0)) : 0.0;
    acc += mean_c * nc;
  }
  out->aspl = acc / N;
  /* networkx.betweenness_centrality(normalized=True): scale 1/((n-1)(n-2)) of the
   * both-directions sum, none for n <= 2 (all zero then). cpd: Freeman 1977. */
  if (n > 1) {
    double scale = n > 2 ? 1.0 / ((N - 1.0) * (N - 2.0)) : 1.0, bmax = 0.0, s = 0.0;
    for (karst_int_t v = 0; v < n; v++) {
      bc[v] *= scale;
      if (bc[v] > bmax) bmax = bc[v];
    }
    for (karst_int_t v = 0; v < n; v++)
      s += bmax - bc[v];
    out->cpd = s / (N - 1.0);
  }
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "reduced graph of %lld nodes: out of memory",
                        (long long)n);
cleanup:
  karst_i_csr_destroy(&csr);
  free(deg);
  free(comp);
  free(queue);
  free(dsum);
  free(bc);
  free(csum);
  free(csize);
  return err;
}

/**
 * Compute the metrics of Collon et al. 2017 on @p net, as Karstnet 1.2.0 does.
 *
 * The network's edge list is first reduced to a simple graph (repeated edges
 * once, self-loops kept, unused nodes dropped). Branches are walked between
 * nodes of degree != 2; the reduced graph Gs replaces each branch by one edge,
 * cutting loops in 3 and parallel branches in 2 (docs/metrics.md).
 *
 * @param ctx  context (errors, ctx->nthreads for the betweenness, interrupt, progress)
 * @param net  the network (coordinates in metres, x east, y north)
 * @param opt  options (NULL: defaults; azimuth_rotation for true north)
 * @param out  every value; undefined ones are NAN
 * @return KARST_SUCCESS, KARST_EINVAL for an edge index out of range or a
 *         non-finite coordinate, KARST_ENOMEM, KARST_EINTERRUPTED.
 *
 * Time complexity: O(n + m) for the full graph plus O(N·(N + S)) for the
 * exact betweenness and path lengths on Gs (N nodes, S edges), divided among
 * ctx->nthreads threads.
 * Sources: Collon et al. 2017 §3 (metrics), Howard et al. 1970 (alpha, beta,
 * gamma), Brandes 2001 (betweenness), Freeman 1977 (central point dominance),
 * Newman 2003 (degree assortativity).
 */
karst_error_t karst_metrics_compute(karst_ctx_t *ctx, const karst_network_t *net,
                                    const karst_metrics_options_t *opt, karst_metrics_t *out) {
  karst_error_t err = KARST_SUCCESS;
  full_graph_t g;
  memset(&g, 0, sizeof g);
  karst_int_t *gs_pairs = NULL, *gs_edges = NULL, *gmap = NULL;
  bkey_t *keys = NULL;
  if (!net || !out) return karst_set_error(ctx, KARST_EINVAL, "metrics: no network or no output");
  metrics_init_undefined(out);
  double rotation = opt ? opt->azimuth_rotation : 0.0;
  if (!isfinite(rotation))
    return karst_set_error(ctx, KARST_EINVAL, "metrics: azimuth rotation must be finite, got %g",
                           rotation);
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    karst_int_t u = net->edges[2 * e], v = net->edges[2 * e + 1];
    if (u < 0 || v < 0 || u >= net->n_nodes || v >= net->n_nodes)
      return karst_set_error(ctx, KARST_EINVAL,
                             "metrics: edge %lld joins nodes %lld and %lld, but the network has "
                             "%lld nodes",
                             (long long)e, (long long)u, (long long)v, (long long)net->n_nodes);
    for (int c = 0; c < 3; c++)
      if (!isfinite(net->xyz[3 * u + c]) || !isfinite(net->xyz[3 * v + c]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "metrics: node %lld of edge %lld has a non-finite coordinate",
                               (long long)(isfinite(net->xyz[3 * u + c]) ? v : u), (long long)e);
  }
  g.n = net->n_nodes;
  g.xyz = net->xyz;
  if ((err = dedupe_pairs(ctx, g.n, net->n_edges, net->edges, &g.ed, &g.m))) goto cleanup;
  karst_int_t m = g.m, n = g.n;
  g.elen = malloc((size_t)(m > 0 ? m : 1) * sizeof *g.elen);
  g.deg = calloc((size_t)n + 1, sizeof *g.deg);
  g.off = calloc((size_t)n + 1, sizeof *g.off);
  g.nbr = malloc((size_t)(2 * m > 0 ? 2 * m : 1) * sizeof *g.nbr);
  g.eid = malloc((size_t)(2 * m > 0 ? 2 * m : 1) * sizeof *g.eid);
  g.used = calloc((size_t)(m > 0 ? m : 1), 1);
  /* branches: at most m of them, holding m + (number of branches) node entries */
  g.boff = calloc((size_t)m + 2, sizeof *g.boff);
  g.nn_cap = 2 * m + 1;
  g.bnode = malloc((size_t)g.nn_cap * sizeof *g.bnode);
  g.blen = malloc((size_t)(m > 0 ? m : 1) * sizeof *g.blen);
  if (!g.elen || !g.deg || !g.off || !g.nbr || !g.eid || !g.used || !g.boff || !g.bnode || !g.blen)
    goto nomem;
  /* full graph: lengths, degrees, incidence lists, counts */
  double zmin = INFINITY, zmax = -INFINITY, total = 0.0;
  karst_int_t nused = 0;
  for (karst_int_t e = 0; e < m; e++) {
    karst_int_t u = g.ed[2 * e], v = g.ed[2 * e + 1];
    const double *p = g.xyz + 3 * u, *q = g.xyz + 3 * v;
    double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
    g.elen[e] = sqrt(dx * dx + dy * dy + dz * dz);
    total += g.elen[e];
    g.deg[u]++;
    g.deg[v]++;
    g.off[u + 1]++;
    if (u != v) g.off[v + 1]++;
  }
  for (karst_int_t v = 0; v < n; v++) {
    g.off[v + 1] += g.off[v];
    if (g.deg[v] > 0) {
      nused++;
      double z = g.xyz[3 * v + 2];
      if (z < zmin) zmin = z;
      if (z > zmax) zmax = z;
    }
  }
  out->nodes = nused;
  out->edges = m;
  out->total_length = total;
  if (m == 0) goto cleanup; /* the empty network: every metric undefined */
  out->vertical_extent = zmax - zmin;
  {
    karst_int_t *cur = malloc((size_t)n * sizeof *cur);
    if (!cur) goto nomem;
    memcpy(cur, g.off, (size_t)n * sizeof *cur);
    for (karst_int_t e = 0; e < m; e++) {
      karst_int_t u = g.ed[2 * e], v = g.ed[2 * e + 1];
      g.nbr[cur[u]] = v;
      g.eid[cur[u]++] = e;
      if (u != v) {
        g.nbr[cur[v]] = u;
        g.eid[cur[v]++] = e;
      }
    }
    free(cur);
  }
  orientation_metric(&g, rotation, out);
  if ((err = all_branches(&g))) {
    err = karst_set_error(ctx, err, "metrics: internal error while walking branches");
    goto cleanup;
  }
  branch_metrics(&g, out);

  /* Gs: group branches by their (unordered) end nodes, cut loops and parallel branches. */
  keys = malloc((size_t)g.nb * sizeof *keys);
  gs_pairs = malloc((size_t)g.nb * 3 * 2 * sizeof *gs_pairs);
  if (!keys || !gs_pairs) goto nomem;
  for (karst_int_t b = 0; b < g.nb; b++) {
    karst_int_t a = g.bnode[g.boff[b]], z = g.bnode[g.boff[b + 1] - 1];
    keys[b].a = a < z ? a : z;
    keys[b].b = a < z ? z : a;
    keys[b].idx = b;
  }
  qsort(keys, (size_t)g.nb, sizeof *keys, cmp_bkey);
  karst_int_t np = 0;
  for (karst_int_t i = 0; i < g.nb;) {
    karst_int_t j = i;
    while (j < g.nb && keys[j].a == keys[i].a && keys[j].b == keys[i].b)
      j++;
    for (karst_int_t k = i; k < j; k++)
      cut_branch(&g, keys[k].idx, j - i > 1, gs_pairs, &np);
    i = j;
  }
  /* Gs nodes: the end nodes of the pieces, renumbered in increasing order. */
  gmap = malloc((size_t)n * sizeof *gmap);
  if (!gmap) goto nomem;
  for (karst_int_t v = 0; v < n; v++)
    gmap[v] = -1;
  for (karst_int_t i = 0; i < 2 * np; i++)
    gmap[gs_pairs[i]] = 0;
  karst_int_t N = 0;
  for (karst_int_t v = 0; v < n; v++)
    if (gmap[v] == 0) gmap[v] = N++;
  for (karst_int_t i = 0; i < 2 * np; i++)
    gs_pairs[i] = gmap[gs_pairs[i]];
  karst_int_t S = 0;
  if ((err = dedupe_pairs(ctx, N, np, gs_pairs, &gs_edges, &S))) goto cleanup;
  err = reduced_metrics(ctx, N, S, gs_edges, out);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "metrics of %lld nodes and %lld edges: out of memory",
                        (long long)net->n_nodes, (long long)net->n_edges);
cleanup:
  if (err) metrics_init_undefined(out);
  free(g.ed);
  free(g.elen);
  free(g.deg);
  free(g.off);
  free(g.nbr);
  free(g.eid);
  free(g.used);
  free(g.boff);
  free(g.bnode);
  free(g.blen);
  free(keys);
  free(gs_pairs);
  free(gs_edges);
  free(gmap);
  return err;
}
