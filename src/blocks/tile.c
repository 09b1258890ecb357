/* Block tiles (Paris et al. 2020, §4): fracture discs per block type, edges
 * cut by discs, clusters split until mutually visible, and one convex block
 * per cluster. See include/karst/blocks.h and docs/blocks.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "blocks/blocks_internal.h"
#include "core/parallel_internal.h"
#include "geometry/geometry_internal.h"
#include "implicit/implicit_internal.h"
#include "karst/image.h"
#include "karst/mesh.h"
#include "karst/sampling.h"

static const char *const type_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_BLOCK_TYPE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

const char *karst_block_type_name(int type) {
  return type >= 0 && type < KARST_BLOCK_TYPE_COUNT ? type_names[type] : "unknown";
}
int karst_block_type_from_name(const char *name) {
  for (int i = 0; name && i < KARST_BLOCK_TYPE_COUNT; i++)
    if (!strcmp(name, type_names[i])) return i;
  return -1;
}
const char *const *karst_block_type_names(void) {
  return type_names;
}

/* Random streams of a tile, derived from (seed, stream): one per stage so
 * that changing one stage's draws leaves the others alone. */
enum { STREAM_POINTS = 1, STREAM_DISCS = 2, STREAM_SPLITS = 3, STREAM_WARP = 4 };

/**
 * Defaults of a block type. Sizes follow §4 (s = 20 m, R = 0.25 m, disc
 * centres 2 m apart, 1 m for polyhedral, radii about 5 m, tabular bedding of
 * radius s and joints of s/10); the Poisson radius gives Table 1's ~14 500
 * points (the paper's "r ≈ 10 cm" would give millions in a 20 m tile); disc
 * counts follow Table 1 (docs/blocks.md). Time complexity: O(1).
 */
void karst_blocks_tile_params_init(karst_blocks_tile_params_t *p, int type) {
  memset(p, 0, sizeof *p);
  p->type = type;
  p->size = 20.0;
  p->poisson_radius = 0.69;
  p->graph_radius = 2 * 0.69;
  p->smooth_radius = 0.25;
  p->aperture = 0.1;
  p->hull_margin = 2 * 0.69;
  p->degenerate_radius = 0.69;
  p->dart_passes = KARST_SAMPLING_DART_PASSES;
  p->seed = 1;
  p->disc_spacing = 2.0;
  p->disc_radius_min = 4.0;
  p->disc_radius_max = 6.0;
  p->bedding_spacing = 0;
  p->warp.relief = KARST_BLOCKS_RELIEF_NONE;
  p->warp.amplitude = 0.15;
  p->warp.wavelength = 2.0;
  switch (type) {
  case KARST_BLOCK_EQUIDIMENSIONAL:
    p->n_discs = 15;
    break;
  case KARST_BLOCK_PRISMATIC:
    p->n_discs = 15;
    p->disc_radius_min = 3.0, p->disc_radius_max = 7.0;
    p->tilt = 12.0;
    break;
  case KARST_BLOCK_POLYHEDRAL:
    p->n_discs = 44;
    p->disc_spacing = 1.0;
    p->disc_radius_min = 2.0, p->disc_radius_max = 5.0;
    break;
  case KARST_BLOCK_RHOMBOHEDRAL:
    p->n_discs = 24;
    p->tilt = 25.0;
    break;
  case KARST_BLOCK_TABULAR:
    p->n_discs = 30;
    p->n_bedding = 9;
    p->bedding_spacing = 1.2;
    p->disc_radius_min = 1.5, p->disc_radius_max = 2.5; /* s/10 */
    break;
  case KARST_BLOCK_COLUMNAR:
    p->n_discs = 14;
    p->n_bedding = 3;
    p->bedding_spacing = 3.0;
    p->disc_radius_min = 10.0, p->disc_radius_max = 20.0; /* continuous: s/2 to s */
    break;
  default:
    break;
  }
}

void karst_blocks_tile_params_resize(karst_blocks_tile_params_t *p, double size,
                                     double poisson_radius) {
  double k = size / p->size;
  p->size = size;
  p->disc_spacing *= k;
  p->disc_radius_min *= k;
  p->disc_radius_max *= k;
  p->bedding_spacing *= k;
  p->poisson_radius = poisson_radius;
  p->graph_radius = p->hull_margin = 2 * poisson_radius;
  p->degenerate_radius = poisson_radius;
}

static karst_error_t bad(karst_ctx_t *ctx, const char *what, double v, const char *rule) {
  return karst_set_error(ctx, KARST_ERANGE, "blocks: %s must be %s, got %g", what, rule, v);
}

/**
 * Check every parameter before any work (finite and in range).
 * @return KARST_SUCCESS or KARST_ERANGE / KARST_EINVAL naming the field.
 * Time complexity: O(user discs).
 */
karst_error_t karst_blocks_tile_params_check(karst_ctx_t *ctx,
                                             const karst_blocks_tile_params_t *p) {
  if (p->type < 0 || p->type >= KARST_BLOCK_TYPE_COUNT)
    return karst_set_error(ctx, KARST_EINVAL, "blocks: unknown block type %d", p->type);
  double s = p->size;
  if (!(s > 0) || !isfinite(s) || s > 1e4) return bad(ctx, "tile_size", s, "within (0, 10000] m");
  if (!(p->poisson_radius >= s / 400) || !(p->poisson_radius < s / 6))
    return bad(ctx, "poisson_radius", p->poisson_radius, "within [s/400, s/6) m");
  if (!(p->graph_radius > p->poisson_radius) || !(p->graph_radius < s / 3))
    return bad(ctx, "graph_radius", p->graph_radius, "within (poisson_radius, s/3) m");
  if (!(p->smooth_radius >= 0) || !(p->smooth_radius <= s / 4))
    return bad(ctx, "smooth_radius", p->smooth_radius, "within [0, s/4] m");
  if (!(p->aperture >= 0) || !(p->aperture <= s / 10))
    return bad(ctx, "aperture", p->aperture, "within [0, s/10] m");
  if (!(p->hull_margin >= 0) || !(p->hull_margin <= s / 4))
    return bad(ctx, "hull_margin", p->hull_margin, "within [0, s/4] m");
  if (!(p->degenerate_radius > 0) || !(p->degenerate_radius <= s / 10))
    return bad(ctx, "degenerate_radius", p->degenerate_radius, "within (0, s/10] m");
  if (p->n_discs < 0 || p->n_discs > 100000)
    return bad(ctx, "discs", p->n_discs, "within [0, 1e5]");
  if (!(p->disc_spacing >= 0) || !(p->disc_spacing <= s))
    return bad(ctx, "disc_spacing", p->disc_spacing, "within [0, s] m");
  if (!(p->disc_radius_min > 0) || !(p->disc_radius_max >= p->disc_radius_min) ||
      !(p->disc_radius_max <= 2 * s))
    return bad(ctx, "disc_radius", p->disc_radius_max,
               "a range 0 < min <= max <= 2 s m (min given too)");
  if (!(p->tilt >= 0) || !(p->tilt <= 60))
    return bad(ctx, "tilt", p->tilt, "within [0, 60] degrees");
  if (p->n_bedding < 0 || p->n_bedding > p->n_discs)
    return bad(ctx, "bedding", p->n_bedding, "within [0, discs]");
  if (!(p->bedding_spacing >= 0) || !(p->bedding_spacing < s))
    return bad(ctx, "bedding_spacing", p->bedding_spacing, "within [0, s) m");
  if (p->dart_passes < 1 || p->dart_passes > 64)
    return bad(ctx, "dart_passes", p->dart_passes, "within [1, 64]");
  if (p->n_user_discs < 0 || (p->n_user_discs && !p->user_discs))
    return karst_set_error(ctx, KARST_EINVAL, "blocks: %d user discs announced, none given",
                           p->n_user_discs);
  for (int i = 0; i < p->n_user_discs; i++) {
    const karst_blocks_disc_t *d = &p->user_discs[i];
    double nn = d->n[0] * d->n[0] + d->n[1] * d->n[1] + d->n[2] * d->n[2];
    for (int a = 0; a < 3; a++)
      if (!isfinite(d->c[a]) || !isfinite(d->n[a]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "blocks: disc %d has a non-finite centre or normal", i);
    if (!(nn > 0))
      return karst_set_error(ctx, KARST_EINVAL, "blocks: disc %d has a zero normal", i);
    if (!(d->radius > 0) || !isfinite(d->radius) || d->radius > 4 * s)
      return karst_set_error(ctx, KARST_ERANGE,
                             "blocks: disc %d radius must be within (0, 4 s] m, got %g", i,
                             d->radius);
  }
  if (p->n_authored < 0 || (p->n_authored && (!p->authored || !p->authored_nodes)))
    return karst_set_error(ctx, KARST_EINVAL, "blocks: authored blocks announced, no tree given");
  for (int i = 0; i < p->n_authored; i++) {
    double b[6];
    if (p->authored_nodes[i] < 0 || p->authored_nodes[i] >= p->authored->n_nodes)
      return karst_set_error(ctx, KARST_EINVAL, "blocks: authored block %d is not a node", i);
    karst_sdf_node_box(p->authored, p->authored_nodes[i], b);
    for (int a = 0; a < 6; a++)
      if (!isfinite(b[a]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "blocks: authored block %d is unbounded; a block must be bounded",
                               i);
  }
  if (p->warp.relief != KARST_BLOCKS_RELIEF_NONE) {
    if (!(p->warp.amplitude >= 0) || !(p->warp.amplitude <= s / 10))
      return bad(ctx, "warp.amplitude", p->warp.amplitude, "within [0, s/10] m");
    if (!(p->warp.wavelength > 0) || !(p->warp.wavelength <= 10 * s))
      return bad(ctx, "warp.wavelength", p->warp.wavelength, "within (0, 10 s] m");
    if (p->warp.relief == KARST_BLOCKS_RELIEF_IMAGE && !p->warp.image)
      return karst_set_error(ctx, KARST_EINVAL, "blocks: warp relief 'image' needs an image file");
  }
  return KARST_SUCCESS;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void normalize3(double *v) {
  double l = sqrt(dot3(v, v));
  v[0] /= l, v[1] /= l, v[2] /= l;
}

/* ---------------------------------------------------------------------- */
/* Discs (§4.1).                                                           */
/* ---------------------------------------------------------------------- */

/* A unit vector within @p deg degrees of @p axis (uniform angle, uniform azimuth). */
static void tilted(karst_rng_t *rng, const double axis[3], double deg, double out[3]) {
  double a = karst_rng_uniform(rng) * deg * M_PI / 180.0, phi = 2 * M_PI * karst_rng_uniform(rng);
  double e1[3] = {0, 0, 0}, e2[3];
  e1[fabs(axis[0]) < 0.9 ? 0 : 1] = 1;
  double h = dot3(e1, axis);
  for (int k = 0; k < 3; k++)
    e1[k] -= h * axis[k];
  normalize3(e1);
  e2[0] = axis[1] * e1[2] - axis[2] * e1[1];
  e2[1] = axis[2] * e1[0] - axis[0] * e1[2];
  e2[2] = axis[0] * e1[1] - axis[1] * e1[0];
  for (int k = 0; k < 3; k++)
    out[k] = cos(a) * axis[k] + sin(a) * (cos(phi) * e1[k] + sin(phi) * e2[k]);
  normalize3(out);
}

/* Periodic minimum-image squared distance. */
static double torus_d2(const double *a, const double *b, double s) {
  double d2 = 0;
  for (int k = 0; k < 3; k++) {
    double d = fabs(a[k] - b[k]);
    d = fmod(d, s);
    if (d > 0.5 * s) d = s - d;
    d2 += d * d;
  }
  return d2;
}

/* Attempts per disc centre before the dart throwing gives up on it. */
#define DISC_TRIES 1000

/* Draw the type's random discs (§4.1) into d (capacity n_discs); returns the count. */
static int draw_discs(const karst_blocks_tile_params_t *p, karst_rng_t *rng,
                      karst_blocks_disc_t *d) {
  double s = p->size;
  int n = 0,
      nb = (p->type == KARST_BLOCK_TABULAR || p->type == KARST_BLOCK_COLUMNAR) ? p->n_bedding : 0;
  /* tabular bedding planes / columnar cross joints: horizontal, spaced in z */
  for (int i = 0; i < nb; i++) {
    for (int tries = 0; tries < DISC_TRIES; tries++) {
      double z = s * karst_rng_uniform(rng), x = s * karst_rng_uniform(rng),
             y = s * karst_rng_uniform(rng);
      int ok = 1;
      for (int j = 0; j < n && ok; j++) {
        double dz = fabs(z - d[j].c[2]);
        dz = fmin(dz, s - dz);
        if (dz < p->bedding_spacing) ok = 0;
      }
      if (!ok) continue;
      karst_blocks_disc_t *D = &d[n++];
      D->c[0] = x, D->c[1] = y, D->c[2] = z;
      D->n[0] = D->n[1] = 0, D->n[2] = 1;
      D->radius = p->type == KARST_BLOCK_TABULAR
                      ? s
                      : karst_rng_uniform_range(rng, 0.1 * s, 0.2 * s); /* columnar cross joints */
      break;
    }
  }
  int first = n;
  double rho_axes[3][3];
  if (p->type == KARST_BLOCK_RHOMBOHEDRAL) {
    /* the three axes tilted by `tilt` towards the diagonal: mutually oblique sets */
    double diag[3] = {1 / sqrt(3.0), 1 / sqrt(3.0), 1 / sqrt(3.0)}, a = p->tilt * M_PI / 180.0;
    for (int k = 0; k < 3; k++) {
      for (int c = 0; c < 3; c++)
        rho_axes[k][c] = cos(a) * (c == k) + sin(a) * diag[c];
      normalize3(rho_axes[k]);
    }
  }
  double col_az0 = 2 * M_PI * karst_rng_uniform(rng);
  for (int i = nb; i < p->n_discs; i++) {
    double c[3];
    int placed = 0;
    for (int tries = 0; tries < DISC_TRIES && !placed; tries++) {
      for (int k = 0; k < 3; k++)
        c[k] = s * karst_rng_uniform(rng);
      placed = 1;
      for (int j = first; j < n && placed; j++)
        if (torus_d2(c, d[j].c, s) < p->disc_spacing * p->disc_spacing) placed = 0;
    }
    if (!placed) break; /* the tile is full at this spacing */
    karst_blocks_disc_t *D = &d[n++];
    memcpy(D->c, c, sizeof c);
    double ax[3] = {0, 0, 0};
    switch (p->type) {
    case KARST_BLOCK_EQUIDIMENSIONAL:
      D->n[0] = D->n[1] = D->n[2] = 0;
      D->n[karst_rng_below(rng, 3)] = 1;
      break;
    case KARST_BLOCK_PRISMATIC:
      ax[karst_rng_below(rng, 3)] = 1;
      tilted(rng, ax, p->tilt, D->n);
      break;
    case KARST_BLOCK_POLYHEDRAL:
      karst_rng_unit_vector(rng, D->n);
      break;
    case KARST_BLOCK_RHOMBOHEDRAL:
      memcpy(D->n, rho_axes[karst_rng_below(rng, 3)], sizeof D->n);
      break;
    case KARST_BLOCK_TABULAR: /* non-persistent joints orthogonal to the bedding */
      D->n[0] = D->n[1] = D->n[2] = 0;
      D->n[karst_rng_below(rng, 2)] = 1;
      break;
    case KARST_BLOCK_COLUMNAR: { /* three vertical sets 60 degrees apart */
      double az = col_az0 + (double)karst_rng_below(rng, 3) * M_PI / 3.0;
      D->n[0] = cos(az), D->n[1] = sin(az), D->n[2] = 0;
      break;
    }
    default:
      break;
    }
    D->radius = karst_rng_uniform_range(rng, p->disc_radius_min, p->disc_radius_max);
  }
  return n;
}

/* ---------------------------------------------------------------------- */
/* Plane families and disc images.                                         */
/* ---------------------------------------------------------------------- */

/* A family of parallel planes n.x = d0 + s n.M over the lattice M in Z³: a
 * disc's plane (restricted to the disc and its copies) or a split plane. */
typedef struct fam {
  double n[3], d0;
  int disc; /* index into the tile's discs, -1 for a split plane */
} fam_t;

typedef struct image {
  int disc;
  int8_t M[3];
  double c[3];   /* centre of this copy */
  double box[6]; /* its bounding box */
} image_t;

typedef struct work {
  karst_ctx_t *ctx;
  const karst_blocks_tile_params_t *par;
  double s, rg;
  karst_int_t n;
  const double *x;
  karst_blocks_disc_t *discs;
  int n_discs;
  fam_t *fams;
  int n_fams, cap_fams;
  image_t *img;
  int n_img;
  /* edge test bins over [-rg, s + rg)³ */
  int nb;
  double bcell;
  int32_t *bstart, *bidx;
  karst_i_edge_t *e;
  karst_int_t ne;
  /* arcs: for point i, arcs astart[i] .. astart[i+1]: edge index and side */
  karst_int_t *astart;
  int32_t *aedge;
  uint8_t *aside;
  unsigned char *inside; /* point inside an authored block */
  karst_rng_t split_rng;
  karst_int_t n_splits;
} work_t;

/* Disc copies whose boxes meet [lo, hi]³ (every lattice translate). */
static karst_error_t make_images(work_t *W, double lo, double hi) {
  double s = W->s;
  int cap = 0;
  for (int d = 0; d < W->n_discs; d++) {
    const karst_blocks_disc_t *D = &W->discs[d];
    double ext[3];
    for (int a = 0; a < 3; a++)
      ext[a] = D->radius * sqrt(fmax(0.0, 1 - D->n[a] * D->n[a]));
    int mlo[3], mhi[3];
    for (int a = 0; a < 3; a++) {
      mlo[a] = (int)floor((lo - D->c[a] - ext[a]) / s) - 1;
      mhi[a] = (int)ceil((hi - D->c[a] + ext[a]) / s) + 1;
      if (mlo[a] < -100) mlo[a] = -100;
      if (mhi[a] > 100) mhi[a] = 100;
    }
    for (int mz = mlo[2]; mz <= mhi[2]; mz++)
      for (int my = mlo[1]; my <= mhi[1]; my++)
        for (int mx = mlo[0]; mx <= mhi[0]; mx++) {
          int M[3] = {mx, my, mz};
          double b[6];
          int ok = 1;
          for (int a = 0; a < 3; a++) {
            double c = D->c[a] + s * M[a];
            b[a] = c - ext[a], b[a + 3] = c + ext[a];
            if (b[a + 3] < lo || b[a] > hi) ok = 0;
          }
          if (!ok) continue;
          if (W->n_img == cap) {
            cap = cap ? 2 * cap : 256;
            image_t *q = realloc(W->img, (size_t)cap * sizeof *q);
            if (!q) return karst_set_error(W->ctx, KARST_ENOMEM, "blocks: out of memory (discs)");
            W->img = q;
          }
          image_t *I = &W->img[W->n_img++];
          I->disc = d;
          for (int a = 0; a < 3; a++) {
            I->M[a] = (int8_t)M[a];
            I->c[a] = D->c[a] + s * M[a];
          }
          memcpy(I->box, b, sizeof b);
        }
  }
  return KARST_SUCCESS;
}

static int add_fam(work_t *W, const double n[3], double d0, int disc) {
  if (W->n_fams == W->cap_fams) {
    int c = W->cap_fams ? 2 * W->cap_fams : 64;
    fam_t *q = realloc(W->fams, (size_t)c * sizeof *q);
    if (!q) return -1;
    W->fams = q, W->cap_fams = c;
  }
  fam_t *f = &W->fams[W->n_fams];
  memcpy(f->n, n, sizeof f->n);
  f->d0 = d0;
  f->disc = disc;
  return W->n_fams++;
}

/* Bins over [-rg, s + rg)³ listing the disc copies whose box, grown by rg, meets them. */
static karst_error_t bin_images(work_t *W) {
  double lo = -W->rg, span = W->s + 2 * W->rg;
  W->nb = (int)floor(span / fmax(W->rg, span / 64));
  if (W->nb < 1) W->nb = 1;
  W->bcell = span / W->nb;
  int nb = W->nb;
  size_t nbins = (size_t)nb * nb * nb;
  W->bstart = calloc(nbins + 1, sizeof *W->bstart);
  if (!W->bstart) return karst_set_error(W->ctx, KARST_ENOMEM, "blocks: out of memory (bins)");
  for (int pass = 0; pass < 2; pass++) {
    int32_t *fill = NULL;
    if (pass == 1) {
      for (size_t b = 0; b < nbins; b++)
        W->bstart[b + 1] += W->bstart[b];
      W->bidx = malloc((size_t)(W->bstart[nbins] ? W->bstart[nbins] : 1) * sizeof *W->bidx);
      fill = malloc(nbins * sizeof *fill);
      if (!W->bidx || !fill) {
        free(fill);
        return karst_set_error(W->ctx, KARST_ENOMEM, "blocks: out of memory (bins)");
      }
      memcpy(fill, W->bstart, nbins * sizeof *fill);
    }
    for (int i = 0; i < W->n_img; i++) {
      int b0[3], b1[3];
      for (int a = 0; a < 3; a++) {
        b0[a] = (int)floor((W->img[i].box[a] - W->rg - lo) / W->bcell);
        b1[a] = (int)floor((W->img[i].box[a + 3] + W->rg - lo) / W->bcell);
        if (b0[a] < 0) b0[a] = 0;
        if (b1[a] >= nb) b1[a] = nb - 1;
      }
      for (int z = b0[2]; z <= b1[2]; z++)
        for (int y = b0[1]; y <= b1[1]; y++)
          for (int x = b0[0]; x <= b1[0]; x++) {
            size_t b = (size_t)x + (size_t)nb * ((size_t)y + (size_t)nb * (size_t)z);
            if (pass == 0)
              W->bstart[b + 1]++;
            else
              W->bidx[fill[b]++] = i;
          }
    }
    free(fill);
  }
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* Cutting edges (parallel over edges, each writes its own record).        */
/* ---------------------------------------------------------------------- */

typedef struct cut_job {
  work_t *W;
} cut_job_t;

static void task_cut(void *arg, int tid, int nth) {
  work_t *W = ((cut_job_t *)arg)->W;
  double s = W->s, lo = -W->rg;
  int nb = W->nb;
  for (karst_int_t k = tid; k < W->ne; k += nth) {
    karst_i_edge_t *E = &W->e[k];
    if (E->cut) continue;
    const double *A = W->x + 3 * E->u;
    double B[3];
    for (int a = 0; a < 3; a++)
      B[a] = W->x[3 * E->v + a] + s * E->L[a];
    int bi[3];
    for (int a = 0; a < 3; a++) {
      bi[a] = (int)floor((A[a] - lo) / W->bcell);
      if (bi[a] < 0) bi[a] = 0;
      if (bi[a] >= nb) bi[a] = nb - 1;
    }
    size_t b = (size_t)bi[0] + (size_t)nb * ((size_t)bi[1] + (size_t)nb * (size_t)bi[2]);
    double tmin = INFINITY, tmax = -INFINITY;
    int imin = -1, imax = -1;
    for (int32_t q = W->bstart[b]; q < W->bstart[b + 1]; q++) {
      const image_t *I = &W->img[W->bidx[q]];
      const karst_blocks_disc_t *D = &W->discs[I->disc];
      double t;
      if (!karst_i_blocks_segment_disc(A, B, I->c, D->n, D->radius, &t)) continue;
      /* ties broken by the image index so the choice is one well-defined copy */
      if (t < tmin || (t == tmin && W->bidx[q] < imin)) tmin = t, imin = W->bidx[q];
      if (t > tmax || (t == tmax && W->bidx[q] < imax)) tmax = t, imax = W->bidx[q];
    }
    if (imin < 0) continue;
    E->cut = 1;
    E->fam[0] = W->img[imin].disc;
    E->fam[1] = W->img[imax].disc;
    for (int a = 0; a < 3; a++) {
      E->M[0][a] = W->img[imin].M[a];
      E->M[1][a] = (int8_t)(W->img[imax].M[a] - E->L[a]);
    }
  }
}

/* ---------------------------------------------------------------------- */
/* Authored blocks.                                                        */
/* ---------------------------------------------------------------------- */

static double authored_field(const karst_blocks_tile_params_t *p, int k, const double q[3]) {
  return karst_sdf_eval_node(p->authored, p->authored_nodes[k], q, NULL, NULL);
}

/* Sphere tracing along a b against authored block k: 1 when the segment enters it. */
static int segment_hits_authored(const karst_blocks_tile_params_t *p, int k, const double a[3],
                                 const double b[3]) {
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, len = sqrt(dot3(d, d));
  double eps = KARST_I_BLOCKS_TRACE_REL * p->poisson_radius, t = 0;
  double box[6];
  karst_sdf_node_box(p->authored, p->authored_nodes[k], box);
  for (int a2 = 0; a2 < 3; a2++) /* slab test first */
    if (fmax(a[a2], b[a2]) < box[a2] || fmin(a[a2], b[a2]) > box[a2 + 3]) return 0;
  while (t <= len) {
    double q[3];
    for (int c = 0; c < 3; c++)
      q[c] = a[c] + (len > 0 ? t / len : 0) * d[c];
    double f = authored_field(p, k, q);
    if (f <= eps) return 1;
    t += f;
  }
  return 0;
}

/* ---------------------------------------------------------------------- */
/* Clusters (§4.1–4.2).                                                    */
/* ---------------------------------------------------------------------- */

typedef struct cluster {
  karst_int_t first, n; /* into the members array */
} cluster_t;

typedef struct clusters {
  karst_int_t *mem; /* point indices */
  int32_t *off;     /* 3 per member: lattice offset of its unwrapped copy */
  karst_int_t n_mem, cap_mem;
  cluster_t *c;
  karst_int_t n, cap;
} clusters_t;

/* Scratch of the splitting. */
typedef struct split {
  int32_t *stamp; /* per point: piece marker */
  int32_t *off;   /* per point: offset in the current BFS */
  karst_int_t *queue;
  int32_t cur;
  /* the stack of pieces: point lists back to back */
  karst_int_t *stk;
  karst_int_t n_stk, cap_stk;
  karst_int_t *plen;
  karst_int_t n_p, cap_p;
} split_t;

static int push_piece(split_t *S, const karst_int_t *pts, karst_int_t n) {
  if (S->n_stk + n > S->cap_stk) {
    karst_int_t c = S->cap_stk ? S->cap_stk : 1024;
    while (c < S->n_stk + n)
      c *= 2;
    karst_int_t *q = realloc(S->stk, (size_t)c * sizeof *q);
    if (!q) return -1;
    S->stk = q, S->cap_stk = c;
  }
  if (S->n_p == S->cap_p) {
    karst_int_t c = S->cap_p ? 2 * S->cap_p : 256;
    karst_int_t *q = realloc(S->plen, (size_t)c * sizeof *q);
    if (!q) return -1;
    S->plen = q, S->cap_p = c;
  }
  memcpy(S->stk + S->n_stk, pts, (size_t)n * sizeof *pts);
  S->n_stk += n;
  S->plen[S->n_p++] = n;
  return 0;
}

/* Breadth-first search from @p root over kept edges through points stamped
 * @p mark, restamping them @p done; the points reached are S->queue[0 .. n). */
static karst_int_t bfs(work_t *W, split_t *S, karst_int_t root, int32_t mark, int32_t done) {
  karst_int_t *q = S->queue, h = 0, t = 0;
  q[t++] = root;
  S->stamp[root] = done;
  while (h < t) {
    karst_int_t u = q[h++];
    for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++) {
      const karst_i_edge_t *E = &W->e[W->aedge[a]];
      if (E->cut) continue;
      karst_int_t v = W->aside[a] ? E->u : E->v;
      if (S->stamp[v] != mark) continue;
      S->stamp[v] = done;
      q[t++] = v;
    }
  }
  return t;
}

/* Connected components (kept edges) of the points of P, pushed as pieces. */
static int push_components(work_t *W, split_t *S, karst_int_t *P, karst_int_t n) {
  int32_t mark = ++S->cur;
  for (karst_int_t i = 0; i < n; i++)
    S->stamp[P[i]] = mark;
  int32_t done = ++S->cur;
  for (karst_int_t i = 0; i < n; i++) {
    if (S->stamp[P[i]] != mark) continue;
    karst_int_t t = bfs(W, S, P[i], mark, done);
    if (push_piece(S, S->queue, t)) return -1;
  }
  return 0;
}

/* Lattice shift of the other end of arc a seen from its point. */
static void arc_shift(const work_t *W, karst_int_t a, int L[3]) {
  const karst_i_edge_t *E = &W->e[W->aedge[a]];
  for (int k = 0; k < 3; k++)
    L[k] = W->aside[a] ? -E->L[k] : E->L[k];
}

/* BFS of piece P (already a component) from P[0]: offsets in S->off; returns
 * the axis of a wrap (an edge whose ends' offsets disagree with it), or -1. */
static int unwrap(work_t *W, split_t *S, const karst_int_t *P, karst_int_t n) {
  int32_t mark = ++S->cur;
  for (karst_int_t i = 0; i < n; i++)
    S->stamp[P[i]] = mark;
  int32_t done = ++S->cur;
  karst_int_t *q = S->queue, h = 0, t = 0;
  q[t++] = P[0];
  S->stamp[P[0]] = done;
  S->off[3 * P[0]] = S->off[3 * P[0] + 1] = S->off[3 * P[0] + 2] = 0;
  int wrap = -1;
  while (h < t) {
    karst_int_t u = q[h++];
    for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++) {
      const karst_i_edge_t *E = &W->e[W->aedge[a]];
      if (E->cut) continue;
      karst_int_t v = W->aside[a] ? E->u : E->v;
      int L[3];
      arc_shift(W, a, L);
      if (S->stamp[v] == mark) {
        S->stamp[v] = done;
        for (int k = 0; k < 3; k++)
          S->off[3 * v + k] = S->off[3 * u + k] + L[k];
        q[t++] = v;
      } else if (S->stamp[v] == done && wrap < 0) {
        for (int k = 0; k < 3; k++)
          if (S->off[3 * v + k] != S->off[3 * u + k] + L[k]) wrap = k;
      }
    }
  }
  return wrap;
}

/* Points of P reachable from P[0] by kept edges. */
static karst_int_t reachable(work_t *W, split_t *S, const karst_int_t *P, karst_int_t n) {
  int32_t mark = ++S->cur;
  for (karst_int_t i = 0; i < n; i++)
    S->stamp[P[i]] = mark;
  return bfs(W, S, P[0], mark, ++S->cur);
}

static void unwrapped(const work_t *W, const split_t *S, karst_int_t i, double u[3]) {
  for (int k = 0; k < 3; k++)
    u[k] = W->x[3 * i + k] + W->s * S->off[3 * i + k];
}

/* Cut every kept edge inside P (unwrapped by S->off) that crosses the plane
 * n.x = d (unwrapped frame) of family f; returns how many were cut. */
static karst_int_t cut_by_plane(work_t *W, split_t *S, const karst_int_t *P, karst_int_t n, int f,
                                const double nrm[3], double d, const int M[3], const double *c,
                                double reach) {
  int32_t mark = ++S->cur;
  for (karst_int_t i = 0; i < n; i++)
    S->stamp[P[i]] = mark;
  karst_int_t cuts = 0;
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t u = P[i];
    double pu[3];
    unwrapped(W, S, u, pu);
    double hu = dot3(nrm, pu) - d;
    for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++) {
      karst_i_edge_t *E = &W->e[W->aedge[a]];
      if (E->cut || W->aside[a]) continue; /* each edge once, from its u end */
      karst_int_t v = E->v;
      if (S->stamp[v] != mark) continue;
      double pv[3];
      for (int k = 0; k < 3; k++)
        pv[k] = pu[k] + (W->x[3 * v + k] + W->s * E->L[k] - W->x[3 * u + k]);
      double hv = dot3(nrm, pv) - d;
      if ((hu > 0) == (hv > 0)) continue;
      if (c) { /* only where the plane is crossed within reach of c */
        double t = hu / (hu - hv), w[3];
        for (int k = 0; k < 3; k++)
          w[k] = pu[k] + t * (pv[k] - pu[k]) - c[k];
        if (dot3(w, w) > reach * reach) continue;
      }
      E->cut = 1;
      E->fam[0] = E->fam[1] = f;
      for (int k = 0; k < 3; k++) {
        E->M[0][k] = (int8_t)(M[k] - S->off[3 * u + k]);
        E->M[1][k] = (int8_t)(M[k] - S->off[3 * u + k] - E->L[k]);
      }
      cuts++;
    }
  }
  return cuts;
}

typedef struct xedge {
  double r2; /* squared distance from the disc centre to the crossing */
  karst_int_t e;
  karst_int_t u; /* the end inside P from which the edge is seen */
} xedge_t;

static int xedge_cmp(const void *pa, const void *pb) {
  const xedge_t *a = pa, *b = pb;
  if (a->r2 != b->r2) return a->r2 < b->r2 ? -1 : 1;
  return a->e < b->e ? -1 : a->e > b->e;
}

/* Cut the kept edges of P that cross the plane n.x = d (unwrapped frame),
 * nearest to c first, in rounds of growing reach, until P falls apart. */
static int grow_split(work_t *W, split_t *S, const karst_int_t *P, karst_int_t n, int f,
                      const double nrm[3], double d, const int M[3], const double c[3],
                      double radius) {
  int32_t mark = ++S->cur;
  for (karst_int_t i = 0; i < n; i++)
    S->stamp[P[i]] = mark;
  xedge_t *x = NULL;
  karst_int_t nx = 0, cap = 0;
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t u = P[i];
    double pu[3];
    unwrapped(W, S, u, pu);
    double hu = dot3(nrm, pu) - d;
    for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++) {
      const karst_i_edge_t *E = &W->e[W->aedge[a]];
      if (E->cut || W->aside[a] || S->stamp[E->v] != mark) continue;
      double pv[3], w[3];
      for (int k = 0; k < 3; k++)
        pv[k] = pu[k] + (W->x[3 * E->v + k] + W->s * E->L[k] - W->x[3 * u + k]);
      double hv = dot3(nrm, pv) - d;
      if ((hu > 0) == (hv > 0)) continue;
      double t = hu / (hu - hv);
      for (int k = 0; k < 3; k++)
        w[k] = pu[k] + t * (pv[k] - pu[k]) - c[k];
      if (nx == cap) {
        cap = cap ? 2 * cap : 256;
        xedge_t *q = realloc(x, (size_t)cap * sizeof *q);
        if (!q) {
          free(x);
          return -1;
        }
        x = q;
      }
      x[nx].r2 = dot3(w, w), x[nx].e = W->aedge[a], x[nx].u = u;
      nx++;
    }
  }
  if (nx > 1) qsort(x, (size_t)nx, sizeof *x, xedge_cmp);
  double reach = radius;
  karst_int_t k = 0;
  while (k < nx) {
    reach *= KARST_I_BLOCKS_GROWTH;
    for (; k < nx && x[k].r2 <= reach * reach; k++) {
      karst_i_edge_t *E = &W->e[x[k].e];
      karst_int_t u = x[k].u;
      E->cut = 1;
      E->fam[0] = E->fam[1] = f;
      for (int j = 0; j < 3; j++) {
        E->M[0][j] = (int8_t)(M[j] - S->off[3 * u + j]);
        E->M[1][j] = (int8_t)(M[j] - S->off[3 * u + j] - E->L[j]);
      }
    }
    if (k < nx && reachable(W, S, P, n) < n) break;
  }
  free(x);
  return 0;
}

/* Does some segment between two points of P (unwrapped) cross disc copy I?
 * Points projecting into the disc on both sides prove it at once (the
 * crossing point is a convex combination of the two projections); otherwise
 * every pair across the plane is tested. */
static int crosses(const work_t *W, const split_t *S, const karst_int_t *P, karst_int_t n,
                   const double c[3], const karst_blocks_disc_t *D, karst_int_t *pos,
                   karst_int_t *neg, int quick) {
  karst_int_t np = 0, nn = 0;
  int in_p = 0, in_n = 0;
  for (karst_int_t i = 0; i < n; i++) {
    double u[3], w[3];
    unwrapped(W, S, P[i], u);
    for (int k = 0; k < 3; k++)
      w[k] = u[k] - c[k];
    double h = dot3(w, D->n);
    if (h == 0) continue;
    double r2 = dot3(w, w) - h * h;
    int in = r2 <= D->radius * D->radius;
    if (h > 0)
      pos[np++] = P[i], in_p |= in;
    else
      neg[nn++] = P[i], in_n |= in;
  }
  if (!np || !nn) return 0;
  if (in_p && in_n) return 1;
  if (quick) return 0;
  for (karst_int_t i = 0; i < np; i++) {
    double a[3];
    unwrapped(W, S, pos[i], a);
    for (karst_int_t j = 0; j < nn; j++) {
      double b[3];
      unwrapped(W, S, neg[j], b);
      if (karst_i_blocks_segment_disc(a, b, c, D->n, D->radius, NULL)) return 1;
    }
  }
  return 0;
}

/* Split pieces until every piece is mutually visible and wraps around no
 * face of the torus; final pieces are appended to @p C. */
static karst_error_t make_clusters(work_t *W, clusters_t *C) {
  karst_error_t err = KARST_SUCCESS;
  split_t S;
  memset(&S, 0, sizeof S);
  karst_int_t n = W->n, *pos = NULL, *neg = NULL, *all = NULL;
  S.stamp = calloc((size_t)n + 1, sizeof *S.stamp);
  S.off = calloc(3 * (size_t)n + 3, sizeof *S.off);
  S.queue = malloc(((size_t)n + 1) * sizeof *S.queue);
  pos = malloc(((size_t)n + 1) * sizeof *pos);
  neg = malloc(((size_t)n + 1) * sizeof *neg);
  all = malloc(((size_t)n + 1) * sizeof *all);
  if (!S.stamp || !S.off || !S.queue || !pos || !neg || !all) goto nomem;
  karst_int_t m = 0;
  for (karst_int_t i = 0; i < n; i++)
    if (!W->inside[i]) all[m++] = i;
  if (push_components(W, &S, all, m)) goto nomem;
  while (S.n_p > 0) {
    if (karst_interrupted(W->ctx)) {
      err = karst_set_error(W->ctx, KARST_EINTERRUPTED, "blocks: interrupted");
      goto cleanup;
    }
    karst_int_t len = S.plen[--S.n_p];
    S.n_stk -= len;
    karst_int_t *P = all;
    memcpy(P, S.stk + S.n_stk, (size_t)len * sizeof *P);
    int wrap = unwrap(W, &S, P, len);
    if (wrap >= 0) {
      /* the piece closes on itself around the torus: cut it by a random plane
       * x_wrap = c (and its translates), as a joint would */
      double nrm[3] = {0, 0, 0};
      nrm[wrap] = 1;
      double d0 = W->s * karst_rng_uniform(&W->split_rng);
      int f = add_fam(W, nrm, d0, -1);
      if (f < 0) goto nomem;
      /* cut in the tile frame: every translate between the ends */
      int32_t mark = ++S.cur;
      for (karst_int_t i = 0; i < len; i++)
        S.stamp[P[i]] = mark;
      for (karst_int_t i = 0; i < len; i++) {
        karst_int_t u = P[i];
        for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++) {
          karst_i_edge_t *E = &W->e[W->aedge[a]];
          if (E->cut || W->aside[a] || S.stamp[E->v] != mark) continue;
          double xa = W->x[3 * u + wrap], xb = W->x[3 * E->v + wrap] + W->s * E->L[wrap];
          double kk = ceil((fmin(xa, xb) - d0) / W->s);
          if (!(d0 + W->s * kk <= fmax(xa, xb)) || (xa == xb)) continue;
          E->cut = 1;
          E->fam[0] = E->fam[1] = f;
          memset(E->M, 0, sizeof E->M);
          E->M[0][wrap] = (int8_t)kk;
          E->M[1][wrap] = (int8_t)(kk - E->L[wrap]);
        }
      }
      W->n_splits++;
      if (push_components(W, &S, P, len)) goto nomem;
      continue;
    }
    /* mutual visibility against every disc copy near the piece */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (karst_int_t i = 0; i < len; i++) {
      double u[3];
      unwrapped(W, &S, P[i], u);
      for (int k = 0; k < 3; k++)
        lo[k] = fmin(lo[k], u[k]), hi[k] = fmax(hi[k], u[k]);
    }
    int split = 0;
    /* two rounds: the O(n) proof first for every disc copy, then the pair test */
    for (int quick = 1; quick >= 0 && !split; quick--)
      for (int d = 0; d < W->n_discs && !split; d++) {
        const karst_blocks_disc_t *D = &W->discs[d];
        double ext[3];
        for (int a = 0; a < 3; a++)
          ext[a] = D->radius * sqrt(fmax(0.0, 1 - D->n[a] * D->n[a]));
        int mlo[3], mhi[3];
        for (int a = 0; a < 3; a++) {
          mlo[a] = (int)floor((lo[a] - D->c[a] - ext[a]) / W->s);
          mhi[a] = (int)ceil((hi[a] - D->c[a] + ext[a]) / W->s);
        }
        for (int mz = mlo[2]; mz <= mhi[2] && !split; mz++)
          for (int my = mlo[1]; my <= mhi[1] && !split; my++)
            for (int mx = mlo[0]; mx <= mhi[0] && !split; mx++) {
              int M[3] = {mx, my, mz};
              double c[3];
              int ok = 1;
              for (int a = 0; a < 3; a++) {
                c[a] = D->c[a] + W->s * M[a];
                if (c[a] + ext[a] < lo[a] || c[a] - ext[a] > hi[a]) ok = 0;
              }
              if (ok) { /* the piece's box must straddle the plane */
                int sp = 0, sn = 0;
                for (int corner = 0; corner < 8; corner++) {
                  double h = -dot3(D->n, c);
                  for (int a = 0; a < 3; a++)
                    h += D->n[a] * ((corner >> a) & 1 ? hi[a] : lo[a]);
                  sp |= h > 0, sn |= h < 0;
                }
                ok = sp && sn;
              }
              if (!ok || !crosses(W, &S, P, len, c, D, pos, neg, quick)) continue;
              /* the fracture runs on in its plane, growing from the disc until
               * the piece falls apart (it ends against other fractures, the
               * T-terminations of joint sets); the whole plane at the latest */
              if (grow_split(W, &S, P, len, d, D->n, dot3(D->n, c), M, c, D->radius)) goto nomem;
              split = 1;
            }
      }
    for (int k = 0; k < W->par->n_authored && !split; k++) {
      /* an authored block between two points: cut through its centre across
       * the piece's longest extent */
      double box[6];
      karst_sdf_node_box(W->par->authored, W->par->authored_nodes[k], box);
      int hit = 0;
      for (int a = 0; a < 3; a++)
        if (box[a + 3] < lo[a] || box[a] > hi[a]) hit = -1;
      for (karst_int_t i = 0; i < len && hit == 0; i++) {
        double a[3];
        unwrapped(W, &S, P[i], a);
        for (karst_int_t j = i + 1; j < len && !hit; j++) {
          double b[3];
          unwrapped(W, &S, P[j], b);
          hit = segment_hits_authored(W->par, k, a, b);
        }
      }
      if (hit != 1) continue;
      int ax = 0;
      for (int a = 1; a < 3; a++)
        if (hi[a] - lo[a] > hi[ax] - lo[ax]) ax = a;
      double nrm[3] = {0, 0, 0}, d = 0.5 * (box[ax] + box[ax + 3]);
      nrm[ax] = 1;
      int f = add_fam(W, nrm, d, -1), M[3] = {0, 0, 0};
      if (f < 0) goto nomem;
      if (cut_by_plane(W, &S, P, len, f, nrm, d, M, NULL, 0) > 0) split = 1;
    }
    if (split) {
      W->n_splits++;
      if (push_components(W, &S, P, len)) goto nomem;
      continue;
    }
    /* final: keep it with its offsets */
    if (C->n == C->cap) {
      karst_int_t c = C->cap ? 2 * C->cap : 128;
      cluster_t *q = realloc(C->c, (size_t)c * sizeof *q);
      if (!q) goto nomem;
      C->c = q, C->cap = c;
    }
    if (C->n_mem + len > C->cap_mem) {
      karst_int_t c = C->cap_mem ? C->cap_mem : 1024;
      while (c < C->n_mem + len)
        c *= 2;
      karst_int_t *q = realloc(C->mem, (size_t)c * sizeof *q);
      if (!q) goto nomem;
      C->mem = q;
      int32_t *o = realloc(C->off, 3 * (size_t)c * sizeof *o);
      if (!o) goto nomem;
      C->off = o, C->cap_mem = c;
    }
    C->c[C->n].first = C->n_mem, C->c[C->n].n = len;
    for (karst_int_t i = 0; i < len; i++) {
      C->mem[C->n_mem + i] = P[i];
      for (int k = 0; k < 3; k++)
        C->off[3 * (C->n_mem + i) + k] = S.off[3 * P[i] + k];
    }
    C->n_mem += len;
    C->n++;
  }
  goto cleanup;
nomem:
  err = karst_set_error(W->ctx, KARST_ENOMEM, "blocks: out of memory while clustering");
cleanup:
  free(S.stamp);
  free(S.off);
  free(S.queue);
  free(S.stk);
  free(S.plen);
  free(pos);
  free(neg);
  free(all);
  return err;
}

/* ---------------------------------------------------------------------- */
/* Blocks (§4.2), one per cluster, in parallel.                            */
/* ---------------------------------------------------------------------- */

typedef struct bres {
  int kind;    /* KARST_BLOCK_CONVEX or KARST_BLOCK_THICK */
  double *pts; /* thick: the points */
  karst_int_t n_pts;
  karst_i_polytope_t poly;
  double anchor[3];
  double box[6];
  int failed;
  char msg[512];
} bres_t;

typedef struct block_job {
  work_t *W;
  clusters_t *C;
  bres_t *res;
} block_job_t;

typedef struct pkey {
  int f;
  int M[3];
  double u[3], d;
} pkey_t;

/* Keys order by family, then plane offset: translates of a family along
 * its plane (M orthogonal to n) are the same plane and end up adjacent. */
static int pkey_cmp(const void *pa, const void *pb) {
  const pkey_t *a = pa, *b = pb;
  if (a->f != b->f) return a->f < b->f ? -1 : 1;
  if (a->d != b->d || a->u[0] != b->u[0]) {
    double sa = a->u[0] + a->u[1] + a->u[2], sb = b->u[0] + b->u[1] + b->u[2];
    if (sa != sb) return sa < sb ? -1 : 1;
    if (a->d != b->d) return a->d < b->d ? -1 : 1;
  }
  for (int k = 0; k < 3; k++)
    if (a->M[k] != b->M[k]) return a->M[k] < b->M[k] ? -1 : 1;
  return 0;
}

static int same_plane(const pkey_t *a, const pkey_t *b, double tol) {
  return a->f == b->f && fabs(a->d - b->d) <= tol && dot3(a->u, b->u) > 0;
}

/* Whether the points span a volume (not within tol of a plane). */
static int spans_volume(const double *p, karst_int_t n, double tol) {
  if (n < 4) return 0;
  karst_int_t i1 = 0, i2 = 0, i3 = 0;
  double best = 0;
  for (karst_int_t i = 1; i < n; i++) {
    double d[3] = {p[3 * i] - p[0], p[3 * i + 1] - p[1], p[3 * i + 2] - p[2]};
    if (dot3(d, d) > best) best = dot3(d, d), i1 = i;
  }
  if (sqrt(best) <= tol) return 0;
  double e[3] = {p[3 * i1] - p[0], p[3 * i1 + 1] - p[1], p[3 * i1 + 2] - p[2]};
  normalize3(e);
  best = 0;
  double nrm[3] = {0, 0, 0};
  for (karst_int_t i = 1; i < n; i++) {
    double d[3] = {p[3 * i] - p[0], p[3 * i + 1] - p[1], p[3 * i + 2] - p[2]}, c[3];
    c[0] = e[1] * d[2] - e[2] * d[1], c[1] = e[2] * d[0] - e[0] * d[2],
    c[2] = e[0] * d[1] - e[1] * d[0];
    if (dot3(c, c) > best) best = dot3(c, c), i2 = i, memcpy(nrm, c, sizeof c);
  }
  if (sqrt(best) <= tol) return 0;
  normalize3(nrm);
  best = 0;
  for (karst_int_t i = 1; i < n; i++) {
    double d[3] = {p[3 * i] - p[0], p[3 * i + 1] - p[1], p[3 * i + 2] - p[2]};
    double h = fabs(dot3(d, nrm));
    if (h > best) best = h, i3 = i;
  }
  (void)i2, (void)i3;
  return best > tol;
}

static void build_one(block_job_t *J, karst_int_t ci) {
  work_t *W = J->W;
  const karst_blocks_tile_params_t *par = W->par;
  const cluster_t *cl = &J->C->c[ci];
  bres_t *R = &J->res[ci];
  double s = W->s, tol = KARST_I_BLOCKS_PLANE_TOL * s;
  double flat = KARST_I_BLOCKS_FLAT_REL * par->poisson_radius;
  karst_int_t n = cl->n;
  const karst_int_t *mem = J->C->mem + cl->first;
  int32_t *off = J->C->off + 3 * cl->first;
  /* centre the cluster's copy on the tile: its centroid inside [0, s)³ */
  double cen[3] = {0, 0, 0};
  for (karst_int_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++)
      cen[k] += (W->x[3 * mem[i] + k] + s * off[3 * i + k]) / (double)n;
  int shift[3];
  for (int k = 0; k < 3; k++) {
    shift[k] = -(int)floor(cen[k] / s);
    cen[k] += s * shift[k];
    if (!(cen[k] < s)) cen[k] = nextafter(s, 0);
  }
  for (karst_int_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++)
      off[3 * i + k] += shift[k];
  memcpy(R->anchor, cen, sizeof cen);
  /* bounding planes and cut points from the cut edges around the cluster */
  karst_int_t cap_keys = 0, n_keys = 0, n_pts = n;
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t u = mem[i];
    for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++)
      if (W->e[W->aedge[a]].cut == 1) cap_keys++;
  }
  pkey_t *keys = malloc((size_t)(cap_keys + 1) * sizeof *keys);
  double *pts = malloc(3 * (size_t)(n + cap_keys + 1) * sizeof *pts);
  double *planes = NULL, *hp = NULL;
  karst_int_t n_hp = 0;
  if (!keys || !pts) goto nomem;
  for (karst_int_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++)
      pts[3 * i + k] = W->x[3 * mem[i] + k] + s * off[3 * i + k];
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t u = mem[i];
    const double *pu = pts + 3 * i;
    for (karst_int_t a = W->astart[u]; a < W->astart[u + 1]; a++) {
      const karst_i_edge_t *E = &W->e[W->aedge[a]];
      if (E->cut != 1) continue;
      int side = W->aside[a], f = E->fam[side], L[3];
      arc_shift(W, a, L);
      const fam_t *F = &W->fams[f];
      pkey_t *K = &keys[n_keys];
      K->f = f;
      for (int k = 0; k < 3; k++)
        K->M[k] = E->M[side][k] + off[3 * i + k];
      double dd = F->d0 + s * (F->n[0] * K->M[0] + F->n[1] * K->M[1] + F->n[2] * K->M[2]);
      double sg = dot3(F->n, pu) - dd > 0 ? -1 : 1;
      for (int k = 0; k < 3; k++)
        K->u[k] = sg * F->n[k];
      K->d = sg * dd;
      n_keys++;
      /* the cut point: where the segment to the neighbour meets the plane */
      const karst_int_t v = side ? E->u : E->v;
      double pv[3];
      for (int k = 0; k < 3; k++)
        pv[k] = pu[k] + (W->x[3 * v + k] + s * L[k] - W->x[3 * u + k]);
      double hu = dot3(K->u, pu) - K->d, hv = dot3(K->u, pv) - K->d;
      if (hu != hv) {
        double t = hu / (hu - hv);
        if (t >= 0 && t <= 1) {
          for (int k = 0; k < 3; k++)
            pts[3 * n_pts + k] = pu[k] + t * (pv[k] - pu[k]);
          n_pts++;
        }
      }
    }
  }
  for (int k = 0; k < 3; k++)
    R->box[k] = INFINITY, R->box[k + 3] = -INFINITY;
  for (karst_int_t i = 0; i < n_pts; i++)
    for (int k = 0; k < 3; k++)
      R->box[k] = fmin(R->box[k], pts[3 * i + k]),
      R->box[k + 3] = fmax(R->box[k + 3], pts[3 * i + k]);
  if (!spans_volume(pts, n_pts, flat)) {
    R->kind = KARST_BLOCK_THICK;
    R->pts = pts, R->n_pts = n_pts;
    pts = NULL;
    goto cleanup;
  }
  /* distinct bounding planes that leave every point of the cluster inside */
  qsort(keys, (size_t)n_keys, sizeof *keys, pkey_cmp);
  karst_int_t nk = 0;
  for (karst_int_t i = 0; i < n_keys; i++) {
    if (nk > 0 && same_plane(&keys[nk - 1], &keys[i], tol)) continue;
    int ok = 1;
    for (karst_int_t j = 0; j < n && ok; j++)
      if (dot3(keys[i].u, pts + 3 * j) - keys[i].d > tol) ok = 0;
    if (ok) keys[nk++] = keys[i];
  }
  char msg[200];
  if (karst_i_cgal_hull_planes(pts, n_pts, &hp, &n_hp, msg, sizeof msg)) {
    snprintf(R->msg, sizeof R->msg, "block %lld: convex hull: %s", (long long)ci, msg);
    R->failed = 1;
    goto cleanup;
  }
  planes = malloc(4 * (size_t)(nk + n_hp + 1) * sizeof *planes);
  if (!planes) goto nomem;
  karst_int_t np = 0;
  double inner[3] = {0, 0, 0};
  for (karst_int_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++)
      inner[k] += pts[3 * i + k] / (double)n;
  for (karst_int_t i = 0; i < nk; i++) {
    if (!(dot3(keys[i].u, inner) - keys[i].d < -tol)) continue;
    memcpy(planes + 4 * np, keys[i].u, 3 * sizeof *planes);
    planes[4 * np + 3] = keys[i].d;
    np++;
  }
  for (karst_int_t i = 0; i < n_hp; i++) {
    memcpy(planes + 4 * np, hp + 4 * i, 4 * sizeof *planes);
    planes[4 * np + 3] += par->hull_margin;
    if (dot3(planes + 4 * np, inner) - planes[4 * np + 3] < -tol) np++;
  }
  if (karst_i_cgal_halfspaces(planes, np, inner, 1e3 * tol, &R->poly, msg, sizeof msg)) {
    /* numerically hopeless cells (near-parallel planes meeting far away):
     * fall back to the grown hull alone, then to a thick primitive */
    karst_int_t nh = 0;
    for (karst_int_t i = 0; i < n_hp; i++) {
      memcpy(planes + 4 * nh, hp + 4 * i, 4 * sizeof *planes);
      planes[4 * nh + 3] += par->hull_margin;
      nh++;
    }
    if (karst_i_cgal_halfspaces(planes, nh, inner, 1e3 * tol, &R->poly, msg, sizeof msg)) {
      R->kind = KARST_BLOCK_THICK;
      R->pts = pts, R->n_pts = n_pts;
      pts = NULL;
      goto cleanup;
    }
  }
  R->kind = KARST_BLOCK_CONVEX;
  for (int k = 0; k < 3; k++)
    R->box[k] = INFINITY, R->box[k + 3] = -INFINITY;
  for (karst_int_t i = 0; i < R->poly.n_vertices; i++)
    for (int k = 0; k < 3; k++) {
      R->box[k] = fmin(R->box[k], R->poly.xyz[3 * i + k]);
      R->box[k + 3] = fmax(R->box[k + 3], R->poly.xyz[3 * i + k]);
    }
  goto cleanup;
nomem:
  R->failed = 1;
  snprintf(R->msg, sizeof R->msg, "block %lld: out of memory", (long long)ci);
cleanup:
  free(keys);
  free(pts);
  free(planes);
  free(hp);
}

static void task_blocks(void *arg, int tid, int nth) {
  block_job_t *J = arg;
  for (karst_int_t i = tid; i < J->C->n; i += nth)
    build_one(J, i);
}

/* ---------------------------------------------------------------------- */
/* The tile.                                                               */
/* ---------------------------------------------------------------------- */

static double tri_volume(const karst_mesh_t *m) {
  double v = 0;
  for (karst_int_t t = 0; t < m->n_triangles; t++) {
    const double *a = m->xyz + 3 * m->tri[3 * t], *b = m->xyz + 3 * m->tri[3 * t + 1],
                 *c = m->xyz + 3 * m->tri[3 * t + 2];
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return v / 6.0;
}

/* b_i = c_i ∘ ω⁻¹ (§4.3): the block's field through the warp node of
 * src/implicit/warp.c, which divides by its Lipschitz factor so that the
 * block stays 1-Lipschitz. No-op without a relief. */
static karst_error_t warp_block(karst_ctx_t *ctx, karst_sdf_t *sdf,
                                const karst_blocks_tile_params_t *par, const karst_relief_t *relief,
                                karst_rng_t *rng, int label, karst_int_t *node) {
  if (par->warp.relief == KARST_BLOCKS_RELIEF_NONE || !(par->warp.amplitude > 0))
    return KARST_SUCCESS;
  karst_int_t w;
  karst_error_t err = karst_sdf_warp(ctx, sdf, *node, relief, NULL, rng, &w);
  if (err) return err;
  sdf->nodes[w].label = label;
  *node = w;
  return KARST_SUCCESS;
}

void karst_blocks_tile_free(karst_blocks_tile_t *t) {
  if (!t) return;
  free(t->xyz);
  free(t->discs);
  free(t->blocks);
  free(t->members);
  free(t->unwrapped);
  if (t->hulls)
    for (karst_int_t i = 0; i < t->n_blocks; i++)
      karst_mesh_destroy(&t->hulls[i]);
  free(t->hulls);
  karst_sdf_free(t->sdf);
  free(t);
}

static void free_work(work_t *W) {
  free(W->fams);
  free(W->img);
  free(W->bstart);
  free(W->bidx);
  free(W->e);
  free(W->astart);
  free(W->aedge);
  free(W->aside);
  free(W->inside);
}

/**
 * Make a tile (Paris et al. 2020, §4): see blocks.h.
 * @return KARST_SUCCESS; KARST_EINVAL / KARST_ERANGE for bad parameters;
 *         KARST_EEXTERNAL when CGAL fails on a cluster; KARST_ENOMEM;
 *         KARST_EINTERRUPTED. *out is NULL on failure.
 * Time complexity: O(N k + E D' + clusters × hull), see blocks.h.
 */
karst_error_t karst_blocks_tile_create(karst_ctx_t *ctx, const karst_blocks_tile_params_t *par,
                                       karst_blocks_tile_t **out) {
  *out = NULL;
  karst_error_t err = karst_blocks_tile_params_check(ctx, par);
  if (err) return err;
  double t0 = now_s();
  int nth = ctx && ctx->nthreads > 0 ? ctx->nthreads : 1;
  karst_blocks_tile_t *T = calloc(1, sizeof *T);
  work_t W;
  memset(&W, 0, sizeof W);
  clusters_t C;
  memset(&C, 0, sizeof C);
  bres_t *res = NULL;
  karst_int_t *kids = NULL;
  karst_image_t image;
  karst_image_init(&image);
  if (!T) return karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
  T->par = *par;
  double s = par->size;
  W.ctx = ctx, W.par = par, W.s = s, W.rg = par->graph_radius;
  /* 1. points */
  karst_rng_t rng;
  karst_rng_derive(&rng, par->seed, STREAM_POINTS, 0);
  karst_progress(ctx, "blocks", 0, 5);
  if ((err = karst_i_blocks_poisson(ctx, s, par->poisson_radius, par->dart_passes, &rng, &T->xyz,
                                    &T->n_points)))
    goto fail;
  W.n = T->n_points, W.x = T->xyz;
  /* 2. discs: the type's random ones, then the user's */
  T->discs = malloc((size_t)(par->n_discs + par->n_user_discs + 1) * sizeof *T->discs);
  if (!T->discs) goto nomem;
  karst_rng_derive(&rng, par->seed, STREAM_DISCS, 0);
  T->n_discs = draw_discs(par, &rng, T->discs);
  for (int i = 0; i < par->n_user_discs; i++) {
    karst_blocks_disc_t d = par->user_discs[i];
    normalize3(d.n);
    T->discs[T->n_discs++] = d;
  }
  W.discs = T->discs, W.n_discs = T->n_discs;
  for (int d = 0; d < T->n_discs; d++)
    if (add_fam(&W, T->discs[d].n, dot3(T->discs[d].n, T->discs[d].c), d) < 0) goto nomem;
  karst_rng_derive(&W.split_rng, par->seed, STREAM_SPLITS, 0);
  /* 3. graph and cuts */
  karst_progress(ctx, "blocks", 1, 5);
  if ((err = karst_i_blocks_radius_graph(ctx, T->xyz, T->n_points, s, W.rg, &W.e, &W.ne)))
    goto fail;
  W.inside = calloc((size_t)W.n + 1, 1);
  if (!W.inside) goto nomem;
  for (int k = 0; k < par->n_authored; k++)
    for (karst_int_t i = 0; i < W.n; i++)
      if (authored_field(par, k, W.x + 3 * i) < 0) W.inside[i] = 1;
  for (karst_int_t k = 0; k < W.ne; k++) {
    karst_i_edge_t *E = &W.e[k];
    if (W.inside[E->u] || W.inside[E->v]) {
      E->cut = 2;
      continue;
    }
    for (int a = 0; a < par->n_authored && !E->cut; a++) {
      double B[3];
      for (int c = 0; c < 3; c++)
        B[c] = W.x[3 * E->v + c] + s * E->L[c];
      if (segment_hits_authored(par, a, W.x + 3 * E->u, B)) E->cut = 2;
    }
  }
  if ((err = make_images(&W, -W.rg, s + W.rg)) || (err = bin_images(&W))) goto fail;
  cut_job_t cj = {&W};
  karst_i_parallel_run(nth, task_cut, &cj);
  /* arcs */
  W.astart = calloc((size_t)W.n + 1, sizeof *W.astart);
  W.aedge = malloc((size_t)(2 * W.ne + 1) * sizeof *W.aedge);
  W.aside = malloc((size_t)(2 * W.ne + 1) * sizeof *W.aside);
  if (!W.astart || !W.aedge || !W.aside) goto nomem;
  for (karst_int_t k = 0; k < W.ne; k++)
    W.astart[W.e[k].u + 1]++, W.astart[W.e[k].v + 1]++;
  for (karst_int_t i = 0; i < W.n; i++)
    W.astart[i + 1] += W.astart[i];
  {
    karst_int_t *fill = malloc((size_t)(W.n + 1) * sizeof *fill);
    if (!fill) goto nomem;
    memcpy(fill, W.astart, (size_t)(W.n + 1) * sizeof *fill);
    for (karst_int_t k = 0; k < W.ne; k++) {
      W.aedge[fill[W.e[k].u]] = (int32_t)k, W.aside[fill[W.e[k].u]++] = 0;
      W.aedge[fill[W.e[k].v]] = (int32_t)k, W.aside[fill[W.e[k].v]++] = 1;
    }
    free(fill);
  }
  /* 4. clusters */
  karst_progress(ctx, "blocks", 2, 5);
  if ((err = make_clusters(&W, &C))) goto fail;
  /* 5. blocks */
  karst_progress(ctx, "blocks", 3, 5);
  res = calloc((size_t)C.n + 1, sizeof *res);
  if (!res) goto nomem;
  block_job_t bj = {&W, &C, res};
  karst_i_parallel_run(nth, task_blocks, &bj);
  for (karst_int_t i = 0; i < C.n; i++)
    if (res[i].failed) {
      err = karst_set_error(ctx, KARST_EEXTERNAL, "blocks: %s tile, seed %llu: %s",
                            karst_block_type_name(par->type), (unsigned long long)par->seed,
                            res[i].msg);
      goto fail;
    }
  karst_int_t nb = C.n + par->n_authored;
  T->blocks = calloc((size_t)nb + 1, sizeof *T->blocks);
  T->hulls = calloc((size_t)nb + 1, sizeof *T->hulls);
  T->members = malloc((size_t)(C.n_mem + 1) * sizeof *T->members);
  T->unwrapped = malloc(3 * (size_t)(C.n_mem + 1) * sizeof *T->unwrapped);
  if (!T->blocks || !T->hulls || !T->members || !T->unwrapped) goto nomem;
  T->n_blocks = nb;
  if ((err = karst_sdf_create(ctx, &T->sdf))) goto fail;
  /* the warping of every block (§4.3): one relief for the tile */
  karst_relief_t relief;
  karst_rng_t wrng;
  karst_rng_derive(&wrng, par->seed, STREAM_WARP, 0);
  if (par->warp.relief != KARST_BLOCKS_RELIEF_NONE) {
    int img = par->warp.relief == KARST_BLOCKS_RELIEF_IMAGE;
    karst_relief_init(&relief, img ? KARST_RELIEF_IMAGE : KARST_RELIEF_NOISE);
    relief.amplitude = par->warp.amplitude;
    if (img) {
      if ((err = karst_image_read(ctx, par->warp.image, &image))) goto fail;
      relief.image = &image;
      relief.tile = par->warp.wavelength;
    } else {
      relief.wavelength = par->warp.wavelength;
    }
  }
  for (karst_int_t i = 0; i < C.n; i++) {
    karst_blocks_block_t *B = &T->blocks[i];
    bres_t *R = &res[i];
    B->first = C.c[i].first, B->n_points = C.c[i].n;
    for (karst_int_t j = 0; j < C.c[i].n; j++) {
      karst_int_t m = C.c[i].first + j, p = C.mem[m];
      T->members[m] = p;
      for (int k = 0; k < 3; k++)
        T->unwrapped[3 * m + k] = T->xyz[3 * p + k] + s * C.off[3 * m + k];
    }
    memcpy(B->anchor, R->anchor, sizeof B->anchor);
    karst_mesh_init(&T->hulls[i]);
    int label = KARST_BLOCKS_LABEL(par->type, i);
    if (R->kind == KARST_BLOCK_THICK) {
      B->kind = KARST_BLOCK_THICK;
      T->stats.n_thick++;
      if ((err = karst_sdf_thick(ctx, T->sdf, R->n_pts, R->pts, par->degenerate_radius,
                                 KARST_I_BLOCKS_FLAT_REL * par->poisson_radius, label, &B->node)))
        goto fail;
      if ((err = warp_block(ctx, T->sdf, par, &relief, &wrng, label, &B->node))) goto fail;
      karst_sdf_node_box(T->sdf, B->node, B->box);
      continue;
    }
    B->kind = KARST_BLOCK_CONVEX;
    karst_mesh_t *H = &T->hulls[i];
    H->n_vertices = R->poly.n_vertices, H->n_triangles = R->poly.n_triangles;
    H->xyz = R->poly.xyz, H->tri = R->poly.tri;
    R->poly.xyz = NULL, R->poly.tri = NULL;
    B->volume = tri_volume(H);
    B->cgal_volume = R->poly.volume;
    B->n_planes = R->poly.n_planes;
    free(kids);
    kids = malloc((size_t)(R->poly.n_planes + 1) * sizeof *kids);
    if (!kids) goto nomem;
    for (karst_int_t k = 0; k < R->poly.n_planes; k++) {
      const double *pl = R->poly.planes + 4 * k;
      double o[3];
      for (int c = 0; c < 3; c++)
        o[c] = pl[c] * (pl[3] - 0.5 * par->aperture);
      if ((err = karst_sdf_plane(ctx, T->sdf, o, pl, &kids[k]))) goto fail;
    }
    if ((err = karst_sdf_smooth_intersection(ctx, T->sdf, R->poly.n_planes, kids,
                                             par->smooth_radius, R->box, &B->node)))
      goto fail;
    T->sdf->nodes[B->node].label = label;
    if ((err = warp_block(ctx, T->sdf, par, &relief, &wrng, label, &B->node))) goto fail;
    karst_sdf_node_box(T->sdf, B->node, B->box);
  }
  for (int k = 0; k < par->n_authored; k++) {
    karst_blocks_block_t *B = &T->blocks[C.n + k];
    B->kind = KARST_BLOCK_AUTHORED;
    B->node = par->authored_nodes[k];
    B->first = C.n_mem, B->n_points = 0;
    karst_sdf_node_box(par->authored, B->node, B->box);
    for (int a = 0; a < 3; a++)
      B->anchor[a] = 0.5 * (B->box[a] + B->box[a + 3]);
    karst_mesh_init(&T->hulls[C.n + k]);
    for (karst_int_t i = 0; i < W.n; i++)
      B->n_points += W.inside[i];
  }
  for (karst_int_t k = 0; k < W.ne; k++)
    T->stats.n_cut += W.e[k].cut == 1;
  T->stats.n_points = T->n_points;
  T->stats.n_discs = T->n_discs;
  T->stats.n_blocks = T->n_blocks;
  T->stats.mean_points = C.n ? (double)C.n_mem / (double)C.n : 0;
  T->stats.n_edges = W.ne;
  T->stats.n_splits = W.n_splits;
  karst_progress(ctx, "blocks", 5, 5);
  T->stats.seconds = now_s() - t0;
  *out = T;
  T = NULL;
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
fail:
  karst_blocks_tile_free(T);
  T = NULL;
cleanup:
  free(kids);
  karst_image_destroy(&image);
  if (res)
    for (karst_int_t i = 0; i < C.n; i++) {
      free(res[i].pts);
      karst_i_polytope_destroy(&res[i].poly);
    }
  free(res);
  free(C.mem);
  free(C.off);
  free(C.c);
  free_work(&W);
  return err;
}

/* ---------------------------------------------------------------------- */
/* Evaluation.                                                             */
/* ---------------------------------------------------------------------- */

double karst_i_blocks_block_eval(const karst_blocks_tile_t *t, karst_int_t i, const double p[3],
                                 double ub, int *label) {
  const karst_blocks_block_t *B = &t->blocks[i];
  const karst_blocks_tile_params_t *par = &t->par;
  int lab = KARST_BLOCKS_LABEL(par->type, i);
  double v;
  if (B->kind == KARST_BLOCK_AUTHORED) {
    v = karst_i_sdf_eval(par->authored, B->node, p, ub, NULL, NULL);
  } else {
    v = karst_i_sdf_eval(t->sdf, B->node, p, ub, NULL, NULL);
    /* carve the authored blocks out of the generated ones (difference) */
    for (int k = 0; k < par->n_authored && v < ub; k++) {
      double box[6];
      karst_sdf_node_box(par->authored, par->authored_nodes[k], box);
      if (karst_i_sdbox(box, p) > -v) continue; /* -A(p) <= -sdbox < v: no change */
      double a = authored_field(par, k, p);
      if (-a > v) v = -a;
    }
  }
  if (label) *label = lab;
  return v;
}

/** Field of block @p i at @p p, tile coordinates (see blocks.h). O(planes). */
double karst_blocks_block_eval(const karst_blocks_tile_t *t, karst_int_t i, const double p[3]) {
  if (!t || i < 0 || i >= t->n_blocks) return INFINITY;
  return karst_i_blocks_block_eval(t, i, p, INFINITY, NULL);
}

/** Periodic field of the tile, min over blocks and lattice copies. O(blocks). */
double karst_blocks_tile_eval(const karst_blocks_tile_t *t, const double p[3]) {
  double s = t->par.size, best = INFINITY, q[3];
  for (int a = 0; a < 3; a++)
    q[a] = p[a] - s * floor(p[a] / s);
  for (int lz = -2; lz <= 2; lz++)
    for (int ly = -2; ly <= 2; ly++)
      for (int lx = -2; lx <= 2; lx++) {
        double x[3] = {q[0] - s * lx, q[1] - s * ly, q[2] - s * lz};
        for (karst_int_t i = 0; i < t->n_blocks; i++) {
          if (karst_i_sdbox(t->blocks[i].box, x) >= best) continue;
          double v = karst_i_blocks_block_eval(t, i, x, best, NULL);
          if (v < best) best = v;
        }
      }
  return best;
}

/** Brute-force visibility of a segment (see blocks.h). O(discs × copies). */
int karst_blocks_segment_visible(const karst_blocks_tile_t *t, const double a[3],
                                 const double b[3]) {
  double s = t->par.size;
  for (int d = 0; d < t->n_discs; d++) {
    const karst_blocks_disc_t *D = &t->discs[d];
    int mlo[3], mhi[3];
    for (int k = 0; k < 3; k++) {
      mlo[k] = (int)floor((fmin(a[k], b[k]) - D->c[k] - D->radius) / s) - 1;
      mhi[k] = (int)ceil((fmax(a[k], b[k]) - D->c[k] + D->radius) / s) + 1;
    }
    for (int mz = mlo[2]; mz <= mhi[2]; mz++)
      for (int my = mlo[1]; my <= mhi[1]; my++)
        for (int mx = mlo[0]; mx <= mhi[0]; mx++) {
          double c[3] = {D->c[0] + s * mx, D->c[1] + s * my, D->c[2] + s * mz};
          if (karst_i_blocks_segment_disc(a, b, c, D->n, D->radius, NULL)) return 0;
        }
  }
  for (int k = 0; k < t->par.n_authored; k++)
    if (segment_hits_authored(&t->par, k, a, b)) return 0;
  return 1;
}

typedef struct one_block {
  const karst_blocks_tile_t *t;
  karst_int_t i;
} one_block_t;

static double one_block_field(const void *arg, const double p[3], double ub, int *label) {
  const one_block_t *o = arg;
  return karst_i_blocks_block_eval(o->t, o->i, p, ub, label);
}

/**
 * Polygonize each block at @p voxel (see blocks.h); the polygonizer runs on
 * ctx->nthreads threads. Time: O(blocks × surface cells × planes).
 */
karst_error_t karst_blocks_tile_mesh(karst_ctx_t *ctx, const karst_blocks_tile_t *t, double voxel,
                                     karst_mesh_t *out) {
  karst_mesh_destroy(out);
  if (!(voxel > 0) || !isfinite(voxel))
    return karst_set_error(ctx, KARST_EINVAL, "blocks: voxel %g must be > 0", voxel);
  karst_error_t err = KARST_SUCCESS;
  karst_sdf_t *tree = NULL;
  karst_mesh_t m;
  karst_mesh_init(&m);
  karst_int_t cap_v = 0, cap_t = 0;
  if ((err = karst_sdf_create(ctx, &tree))) return err;
  karst_ctx_t quiet = *ctx;
  quiet.progress = NULL;
  for (karst_int_t i = 0; i < t->n_blocks; i++) {
    karst_progress(ctx, "block meshes", (double)i, (double)t->n_blocks);
    one_block_t ob = {t, i};
    karst_i_sdf_clear(tree);
    karst_int_t node;
    double box[6];
    for (int a = 0; a < 3; a++)
      box[a] = t->blocks[i].box[a] - 2 * voxel, box[a + 3] = t->blocks[i].box[a + 3] + 2 * voxel;
    if ((err = karst_sdf_external(ctx, tree, one_block_field, &ob, t->blocks[i].box, 0, &node)) ||
        (err = karst_sdf_set_root(ctx, tree, node)))
      goto cleanup;
    if ((err = karst_mesh_polygonize(&quiet, tree, box, voxel, &m, NULL))) {
      ctx->errcode = quiet.errcode;
      memcpy(ctx->errmsg, quiet.errmsg, sizeof ctx->errmsg);
      goto cleanup;
    }
    if (out->n_vertices + m.n_vertices > cap_v) {
      cap_v = 2 * (out->n_vertices + m.n_vertices);
      double *q = realloc(out->xyz, 3 * (size_t)cap_v * sizeof *q);
      if (!q) goto nomem;
      out->xyz = q;
    }
    if (out->n_triangles + m.n_triangles > cap_t) {
      cap_t = 2 * (out->n_triangles + m.n_triangles);
      karst_int_t *q = realloc(out->tri, 3 * (size_t)cap_t * sizeof *q);
      int *l = realloc(out->tri_label, (size_t)cap_t * sizeof *l);
      if (q) out->tri = q;
      if (l) out->tri_label = l;
      if (!q || !l) goto nomem;
    }
    if (m.n_vertices > 0) /* an empty block mesh has no arrays */
      memcpy(out->xyz + 3 * out->n_vertices, m.xyz, 3 * (size_t)m.n_vertices * sizeof *m.xyz);
    for (karst_int_t k = 0; k < m.n_triangles; k++) {
      for (int c = 0; c < 3; c++)
        out->tri[3 * (out->n_triangles + k) + c] = m.tri[3 * k + c] + out->n_vertices;
      out->tri_label[out->n_triangles + k] = (int)i;
    }
    out->n_vertices += m.n_vertices;
    out->n_triangles += m.n_triangles;
  }
  out->tri_label_name = "block_id";
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory for the tile mesh");
cleanup:
  if (err) karst_mesh_destroy(out);
  karst_mesh_destroy(&m);
  karst_sdf_free(tree);
  return err;
}

int karst_blocks_label_decode(int label, int *type, int *id) {
  if (label < KARST_BLOCKS_LABEL_BASE) {
    if (type) *type = -1;
    if (id) *id = -1;
    return 0;
  }
  int x = label - KARST_BLOCKS_LABEL_BASE;
  if (type) *type = x >> 20;
  if (id) *id = x & ((1 << 20) - 1);
  return 1;
}
