/* Gradient-based warping (Paris et al. 2020, §4.3, Fig. 9-10): a child field
 * c evaluated at ω⁻¹(p) = p + δ(p), with δ the tri-planar relief along the
 * child's normalised gradient, and its proven Lipschitz bound.
 *
 * The bound. Let c be 1-Lipschitz. Its gradient is taken by the tetrahedral
 * finite difference G(p) = (1/4ε) Σ_k v_k c(p + ε v_k), v_k the four vertices
 * (±1, ±1, ±1) with an even number of minus signs. The 3 x 4 matrix M of the
 * v_k has orthogonal rows of norm 2, and with the row (1, 1, 1, 1) it forms a
 * Hadamard basis, so |M x|² = 4|x|² - (Σ x_k)² <= 16 for x in [-1, 1]⁴: since
 * |c(p + ε v_k) - c(q + ε v_k)| <= |p - q|, |G(p) - G(q)| <= |p - q| / ε.
 * g = G / max(|G|, m) = P(G) / m with P the projection onto the ball of radius
 * m (1-Lipschitz), hence |g| <= 1 and g is L_g = 1/(ε m)-Lipschitz.
 *
 * Tri-planar relief: D(p) = Σ_i |g_i(p)| d(γ_i(p)) with |d| <= A and d
 * L_d-Lipschitz in the plane. |D| <= A Σ|g_i| <= √3 A, and
 *   |D(p) - D(q)| <= A Σ_i |g_i(p) - g_i(q)| + L_d Σ_i |g_i(q)| |γ_i(p - q)|
 *                 <= (√3 A L_g + √2 L_d) |p - q|
 * (Cauchy-Schwarz twice; Σ_i |γ_i(x)|² = 2|x|²). So δ = g D has
 *   L_δ <= |D| L_g + L_D <= 2√3 A L_g + √2 L_d,   |δ| <= √3 A.
 * A 3-D relief r (fractures) gives δ = g r: L_δ <= A L_g + L_r, |δ| <= A.
 * Then |c(p + δ(p)) - c(q + δ(q))| <= (1 + L_δ) |p - q|: the warped field
 * divided by 1 + L_δ is 1-Lipschitz, and its zero set is the warped surface.
 *
 * Band mode. δ is multiplied by ψ(c(p)/band), ψ(x) = (1 - x²)² on |x| < 1 and
 * 0 beyond (|ψ'| <= 8/(3√3)), which adds (8/(3√3)) max|δ| / band to L_δ; then
 * f = c(p + δ(p)) equals c where |c| >= band, hence is locally 1-Lipschitz
 * wherever |f| > rc = band + max|δ| (there |c| > band). The rescaling
 * s(x) = x / L on |x| <= rc, x - sign(x) rc (1 - 1/L) beyond, with
 * L = 1 + L_δ, is monotone, so s∘f has the zero set of f; along any segment,
 * |d/dt s(f)| <= (1/L) L where |f| < rc and <= 1 elsewhere, so s∘f is
 * 1-Lipschitz, and far from the surface it is the distance bound c shifted by
 * at most rc. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "implicit/implicit_internal.h"

/* Largest |ψ'| of the band window ψ(x) = (1 - x²)² (at x = 1/√3). */
#define PSI_LIP (8.0 / (3.0 * 1.7320508075688772))
/* Largest |b'| of the groove profile b(x) = (1 - x²)² (the same polynomial). */
#define GROOVE_LIP PSI_LIP
/* Largest |s'| of the smoothstep 3t² - 2t³ of the value noise. */
#define SMOOTHSTEP_LIP 1.5
/* Rotation between successive noise octaves (the golden angle, radians), so
 * that the lattices of the octaves are not aligned. */
#define OCTAVE_TURN 2.399963229728653
/* Widest groove accepted, in fracture spacings (bounds the work per point). */
#define MAX_GROOVE_SPACINGS 4.0

static const double TET[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};

/** Defaults of a relief (see implicit.h). O(1). */
void karst_relief_init(karst_relief_t *r, karst_relief_kind_t kind) {
  memset(r, 0, sizeof *r);
  r->kind = kind;
  r->amplitude = 0.05;
  r->wavelength = 1.0;
  r->octaves = 3;
  r->tile = 1.0;
  r->spacing = 2.0;
  r->width = 0.3;
}

/** Defaults of the warp node (see implicit.h). O(1). */
void karst_warp_params_init(karst_warp_params_t *p) {
  p->epsilon = 0.2;
  p->grad_floor = 0.5;
  p->band = INFINITY;
}

void karst_i_fd_gradient(const karst_sdf_t *t, karst_int_t child, const double p[3], double eps,
                         double G[3], karst_int_t *touched) {
  G[0] = G[1] = G[2] = 0;
  for (int k = 0; k < 4; k++) {
    double q[3] = {p[0] + eps * TET[k][0], p[1] + eps * TET[k][1], p[2] + eps * TET[k][2]};
    double f = karst_i_sdf_eval(t, child, q, INFINITY, NULL, touched);
    for (int c = 0; c < 3; c++)
      G[c] += TET[k][c] * f;
  }
  for (int c = 0; c < 3; c++)
    G[c] *= 0.25 / eps;
}

/* ---------------------------------------------------------------------- */
/* Reliefs: values in [-1, 1] and their Lipschitz constants.               */
/* ---------------------------------------------------------------------- */

static uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/* A pure function of (seed, a, b, c), uniform in [0, 1). */
static double hash_unit(uint64_t seed, uint64_t a, int64_t b, int64_t c) {
  uint64_t h =
      mix64(seed ^ mix64(a * 0x9E3779B97F4A7C15ULL ^ mix64((uint64_t)b * 0xC2B2AE3D27D4EB4FULL ^
                                                           (uint64_t)c * 0x165667B19E3779F9ULL)));
  return (double)(h >> 11) * 0x1p-53;
}

/* Value noise of one octave at lattice coordinates (x, y): smoothstep
 * interpolation of lattice values in [-1, 1]. |n| <= 1 and, per lattice unit,
 * |∂n/∂x| <= 1.5 max|v_10 - v_00| <= 3 (and the same for y): |∇n| <= 3√2. */
static double value_noise(uint64_t seed, int octave, double x, double y) {
  double fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
  int64_t i = (int64_t)fx, j = (int64_t)fy;
  double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  double v00 = 2 * hash_unit(seed, (uint64_t)octave, i, j) - 1;
  double v10 = 2 * hash_unit(seed, (uint64_t)octave, i + 1, j) - 1;
  double v01 = 2 * hash_unit(seed, (uint64_t)octave, i, j + 1) - 1;
  double v11 = 2 * hash_unit(seed, (uint64_t)octave, i + 1, j + 1) - 1;
  return (1 - sy) * ((1 - sx) * v00 + sx * v10) + sy * ((1 - sx) * v01 + sx * v11);
}

/* fBm: Σ_o 2^-o n_o(R_o (u, v) 2^o / λ) / Σ_o 2^-o, each octave's lattice
 * turned by o golden angles. */
static double noise2(const karst_i_warp_t *w, double u, double v) {
  double sum = 0, norm = 0, a = 1, f = 1.0 / w->wavelength;
  for (int o = 0; o < w->octaves; o++) {
    double c = cos(o * OCTAVE_TURN), s = sin(o * OCTAVE_TURN);
    sum += a * value_noise(w->seed, o, (c * u - s * v) * f, (s * u + c * v) * f);
    norm += a;
    a *= 0.5;
    f *= 2;
  }
  return sum / norm;
}

/* Lipschitz constant (1/m) of noise2: Σ_o 2^-o 3√2 2^o / λ / Σ_o 2^-o. */
static double noise2_lipschitz(double wavelength, int octaves) {
  double norm = 0, a = 1;
  for (int o = 0; o < octaves; o++, a *= 0.5)
    norm += a;
  return SMOOTHSTEP_LIP * 2 * sqrt(2.0) * octaves / (wavelength * norm);
}

/* Bilinear, tiled grey level of image @p im at pixel coordinates (x, y). */
static double image_grey(const karst_i_image_t *im, double x, double y) {
  double fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
  int64_t i = (int64_t)fx % im->w, j = (int64_t)fy % im->h;
  if (i < 0) i += im->w;
  if (j < 0) j += im->h;
  int64_t i1 = (i + 1) % im->w, j1 = (j + 1) % im->h;
  double z00 = im->v[j * im->w + i], z10 = im->v[j * im->w + i1];
  double z01 = im->v[j1 * im->w + i], z11 = im->v[j1 * im->w + i1];
  return (1 - ty) * ((1 - tx) * z00 + tx * z10) + ty * ((1 - tx) * z01 + tx * z11);
}

/* 2 grey - 1 at plane coordinates (u, v) metres: the image's width spans
 * w->tile metres along u, its rows run down against v (north up). */
static double image2(const karst_sdf_t *t, const karst_i_warp_t *w, double u, double v) {
  const karst_i_image_t *im = &t->images[w->image];
  double per_m = im->w / w->tile;
  return 2 * image_grey(im, u * per_m, -v * per_m) - 1;
}

/* Largest gradient of the tiled bilinear image, grey levels per pixel: on a
 * cell ∂x is affine in y and ∂y in x, so |∇|² is convex and largest at a
 * corner (the argument of the terrain's λ). O(pixels). */
static double image_lipschitz(const karst_i_image_t *im) {
  double lip = 0;
  for (int j = 0; j < im->h; j++)
    for (int i = 0; i < im->w; i++) {
      int i1 = (i + 1) % im->w, j1 = (j + 1) % im->h;
      double z00 = im->v[j * im->w + i], z10 = im->v[j * im->w + i1];
      double z01 = im->v[j1 * im->w + i], z11 = im->v[j1 * im->w + i1];
      double gx0 = z10 - z00, gx1 = z11 - z01, gy0 = z01 - z00, gy1 = z11 - z10;
      double g2 = fmax(fmax(gx0 * gx0 + gy0 * gy0, gx0 * gx0 + gy1 * gy1),
                       fmax(gx1 * gx1 + gy0 * gy0, gx1 * gx1 + gy1 * gy1));
      lip = fmax(lip, sqrt(g2));
    }
  return lip;
}

/* The 2-D relief in [-1, 1] at (u, v). */
static double relief2(const karst_sdf_t *t, const karst_i_warp_t *w, double u, double v) {
  switch (w->kind) {
  case KARST_RELIEF_NOISE:
    return noise2(w, u, v);
  case KARST_RELIEF_IMAGE:
    return image2(t, w, u, v);
  case KARST_RELIEF_FUNCTION:
    return w->fn(w->user, u, v);
  default:
    return 0;
  }
}

/* Fracture grooves in [-1, 0] at p: -Σ_k w_k max_i b((t_k - c_ki)/h) / Σ_k w_k
 * with t_k = n_k.p / spacing, c_ki = i + U(seed, k, i), h = width / spacing.
 * A max of (GROOVE_LIP / width)-Lipschitz functions, averaged. */
static double fractures3(const karst_i_warp_t *w, const double p[3]) {
  double h = w->width / w->spacing, sum = 0, W = 0;
  for (int k = 0; k < w->n_planes; k++) {
    const double *n = w->normal[k];
    double tk = (n[0] * p[0] + n[1] * p[1] + n[2] * p[2]) / w->spacing, m = 0;
    int64_t i0 = (int64_t)floor(tk - h) - 1, i1 = (int64_t)floor(tk + h);
    for (int64_t i = i0; i <= i1; i++) {
      double x = (tk - (double)i - hash_unit(w->seed, (uint64_t)k + 1, i, 0)) / h;
      if (fabs(x) < 1) m = fmax(m, (1 - x * x) * (1 - x * x));
    }
    sum += w->weight[k] * m;
    W += w->weight[k];
  }
  return -sum / W;
}

/* D(p) = A Σ_i |g_i| d(γ_i(p)) (tri-planar), or A r(p). */
static double displacement(const karst_sdf_t *t, const karst_i_warp_t *w, const double p[3],
                           const double g[3]) {
  if (w->kind == KARST_RELIEF_FRACTURES) return w->amp * fractures3(w, p);
  return w->amp * (fabs(g[0]) * relief2(t, w, p[1], p[2]) + fabs(g[1]) * relief2(t, w, p[0], p[2]) +
                   fabs(g[2]) * relief2(t, w, p[0], p[1]));
}

/* ---------------------------------------------------------------------- */
/* The node.                                                               */
/* ---------------------------------------------------------------------- */

/* The rescaling s of the file comment, and its inverse. */
static double squash(const karst_i_warp_t *w, double x) {
  if (!isfinite(w->band)) return x / w->lip;
  if (fabs(x) <= w->rc) return x / w->lip;
  double off = w->rc * (1 - 1 / w->lip);
  return x > 0 ? x - off : x + off;
}

static double unsquash(const karst_i_warp_t *w, double y) {
  if (!isfinite(w->band)) return y * w->lip;
  if (fabs(y) * w->lip <= w->rc) return y * w->lip;
  double off = w->rc * (1 - 1 / w->lip);
  return y > 0 ? y + off : y - off;
}

double karst_i_warp_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                         double ub, int *label, karst_int_t *touched) {
  const karst_i_warp_t *w = &t->warps[nd->u.warp.index];
  int lab = nd->label;
  /* c(p + δ) >= c(p) - max|δ|: one evaluation decides far points */
  double cub = isfinite(ub) ? unsquash(w, ub) + w->dmax : INFINITY;
  double c0 = karst_i_sdf_eval(t, w->child, p, cub, &lab, touched);
  double v;
  if (w->dmax == 0) {
    v = squash(w, c0);
  } else if (c0 >= cub) {
    v = squash(w, c0 - w->dmax); /* >= ub: valid under the contract */
  } else {
    double win = 1;
    if (isfinite(w->band)) {
      double x = c0 / w->band;
      win = fabs(x) >= 1 ? 0 : (1 - x * x) * (1 - x * x);
    }
    if (win == 0) {
      v = squash(w, c0);
    } else {
      double G[3];
      karst_i_fd_gradient(t, w->child, p, w->eps, G, touched);
      double gn = sqrt(G[0] * G[0] + G[1] * G[1] + G[2] * G[2]);
      double s = 1.0 / (gn > w->gfloor ? gn : w->gfloor);
      double g[3] = {G[0] * s, G[1] * s, G[2] * s};
      double D = win * displacement(t, w, p, g);
      double q[3] = {p[0] + D * g[0], p[1] + D * g[1], p[2] + D * g[2]};
      double c = karst_i_sdf_eval(t, w->child, q, isfinite(ub) ? unsquash(w, ub) : INFINITY, &lab,
                                  touched);
      v = squash(w, c);
    }
  }
  if (label) *label = lab;
  return v;
}

static karst_error_t check_relief(karst_ctx_t *ctx, const karst_relief_t *r, karst_rng_t *rng) {
  if (!r) return karst_set_error(ctx, KARST_EINVAL, "warp: no relief given");
  if (!isfinite(r->amplitude))
    return karst_set_error(ctx, KARST_EINVAL, "warp: relief amplitude %g is not finite",
                           r->amplitude);
  switch (r->kind) {
  case KARST_RELIEF_NOISE:
    if (!(r->wavelength > 0) || !isfinite(r->wavelength))
      return karst_set_error(ctx, KARST_EINVAL, "warp: noise wavelength %g must be > 0 m",
                             r->wavelength);
    if (r->octaves < 1 || r->octaves > KARST_RELIEF_MAX_OCTAVES)
      return karst_set_error(ctx, KARST_EINVAL, "warp: noise octaves %d must be in 1..%d",
                             r->octaves, KARST_RELIEF_MAX_OCTAVES);
    if (!rng) return karst_set_error(ctx, KARST_EINVAL, "warp: a noise relief needs a generator");
    break;
  case KARST_RELIEF_IMAGE:
    if (!r->image || !r->image->v || r->image->width < 1 || r->image->height < 1)
      return karst_set_error(ctx, KARST_EINVAL, "warp: the relief image is empty");
    if (!(r->tile > 0) || !isfinite(r->tile))
      return karst_set_error(ctx, KARST_EINVAL, "warp: image tile %g must be > 0 m", r->tile);
    for (long long i = 0; i < (long long)r->image->width * r->image->height; i++)
      if (!(r->image->v[i] >= 0 && r->image->v[i] <= 1))
        return karst_set_error(ctx, KARST_EINVAL,
                               "warp: image pixel %lld is %g, grey levels must be in [0, 1]", i,
                               (double)r->image->v[i]);
    break;
  case KARST_RELIEF_FUNCTION:
    if (!r->fn) return karst_set_error(ctx, KARST_EINVAL, "warp: no relief function given");
    if (!(r->fn_lipschitz >= 0) || !isfinite(r->fn_lipschitz))
      return karst_set_error(ctx, KARST_EINVAL,
                             "warp: relief function Lipschitz constant %g must be >= 0",
                             r->fn_lipschitz);
    break;
  case KARST_RELIEF_FRACTURES: {
    if (r->n_planes < 1 || r->n_planes > KARST_RELIEF_MAX_PLANES)
      return karst_set_error(ctx, KARST_EINVAL, "warp: %d fracture families, expected 1..%d",
                             r->n_planes, KARST_RELIEF_MAX_PLANES);
    double W = 0;
    for (int k = 0; k < r->n_planes; k++) {
      const double *n = r->normals[k];
      double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (!(l > 0) || !isfinite(l))
        return karst_set_error(ctx, KARST_EINVAL,
                               "warp: fracture family %d has normal (%g, %g, %g)", k, n[0], n[1],
                               n[2]);
      if (!(r->weights[k] >= 0) || !isfinite(r->weights[k]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "warp: fracture family %d has weight %g, must be >= 0", k,
                               r->weights[k]);
      W += r->weights[k];
    }
    if (!(W > 0)) return karst_set_error(ctx, KARST_EINVAL, "warp: all fracture weights are 0");
    if (!(r->spacing > 0) || !isfinite(r->spacing))
      return karst_set_error(ctx, KARST_EINVAL, "warp: fracture spacing %g must be > 0 m",
                             r->spacing);
    if (!(r->width > 0) || !(r->width <= MAX_GROOVE_SPACINGS * r->spacing))
      return karst_set_error(ctx, KARST_EINVAL,
                             "warp: groove width %g must be in (0, %g spacing = %g] m", r->width,
                             MAX_GROOVE_SPACINGS, MAX_GROOVE_SPACINGS * r->spacing);
    if (!rng)
      return karst_set_error(ctx, KARST_EINVAL, "warp: a fracture relief needs a generator");
    break;
  }
  default:
    return karst_set_error(ctx, KARST_EINVAL, "warp: unknown relief kind %d", (int)r->kind);
  }
  return KARST_SUCCESS;
}

/**
 * Gradient-based warping node (Paris et al. 2020, §4.3); see implicit.h and
 * the bound in the comment of this file.
 * @return KARST_SUCCESS; KARST_EINVAL naming the bad field; KARST_ENOMEM.
 * Time complexity: O(1), or O(pixels) to copy an image and compute its
 * Lipschitz constant.
 */
karst_error_t karst_sdf_warp(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child,
                             const karst_relief_t *relief, const karst_warp_params_t *par,
                             karst_rng_t *rng, karst_int_t *node) {
  karst_warp_params_t defaults;
  if (!par) {
    karst_warp_params_init(&defaults);
    par = &defaults;
  }
  if (!t || child < 0 || child >= t->n_nodes)
    return karst_set_error(ctx, KARST_EINVAL, "warp: node %lld does not exist (tree has %lld)",
                           (long long)child, t ? (long long)t->n_nodes : 0LL);
  karst_error_t err = check_relief(ctx, relief, rng);
  if (err) return err;
  if (!(par->epsilon > 0) || !isfinite(par->epsilon))
    return karst_set_error(ctx, KARST_EINVAL, "warp: gradient step %g must be > 0 m", par->epsilon);
  if (!(par->grad_floor > 0 && par->grad_floor <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "warp: grad_floor %g must be in (0, 1]",
                           par->grad_floor);
  if (!(par->band > 0))
    return karst_set_error(ctx, KARST_EINVAL, "warp: band %g must be > 0 m (INFINITY: everywhere)",
                           par->band);
  karst_i_warp_t w;
  memset(&w, 0, sizeof w);
  w.child = child;
  w.kind = relief->kind;
  w.amp = relief->amplitude;
  w.eps = par->epsilon;
  w.gfloor = par->grad_floor;
  w.band = par->band;
  w.image = -1;
  double A = fabs(relief->amplitude), unit_lip = 0;
  switch (relief->kind) {
  case KARST_RELIEF_NOISE:
    w.wavelength = relief->wavelength;
    w.octaves = relief->octaves;
    w.seed = karst_rng_u64(rng);
    unit_lip = noise2_lipschitz(w.wavelength, w.octaves);
    break;
  case KARST_RELIEF_IMAGE: {
    karst_int_t need = t->n_images + 1;
    if (karst_i_grow((void **)&t->images, &t->cap_images, need, sizeof *t->images))
      return karst_set_error(ctx, KARST_ENOMEM, "warp: out of memory for the image");
    karst_i_image_t im = {relief->image->width, relief->image->height, NULL, 0};
    size_t np = (size_t)im.w * (size_t)im.h;
    im.v = malloc(np * sizeof *im.v);
    if (!im.v) return karst_set_error(ctx, KARST_ENOMEM, "warp: out of memory for %zu pixels", np);
    memcpy(im.v, relief->image->v, np * sizeof *im.v);
    im.lip = image_lipschitz(&im);
    w.tile = relief->tile;
    /* d = 2 grey - 1: twice the grey gradient, in pixels per metre */
    unit_lip = 2 * im.lip * im.w / relief->tile;
    w.image = (int)t->n_images;
    t->images[t->n_images++] = im;
    break;
  }
  case KARST_RELIEF_FUNCTION:
    w.fn = relief->fn;
    w.user = relief->user;
    unit_lip = relief->fn_lipschitz;
    break;
  case KARST_RELIEF_FRACTURES:
    w.n_planes = relief->n_planes;
    for (int k = 0; k < relief->n_planes; k++) {
      const double *n = relief->normals[k];
      double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int c = 0; c < 3; c++)
        w.normal[k][c] = n[c] / l;
      w.weight[k] = relief->weights[k];
    }
    w.spacing = relief->spacing;
    w.width = relief->width;
    w.seed = karst_rng_u64(rng);
    unit_lip = GROOVE_LIP / relief->width;
    break;
  default:
    break;
  }
  w.rlip = A * unit_lip;
  double Lg = 1.0 / (w.eps * w.gfloor), Ld;
  if (relief->kind == KARST_RELIEF_FRACTURES) {
    w.dmax = A;
    Ld = A * Lg + w.rlip;
  } else {
    w.dmax = sqrt(3.0) * A;
    Ld = 2 * sqrt(3.0) * A * Lg + sqrt(2.0) * w.rlip;
  }
  if (isfinite(w.band)) Ld += PSI_LIP * w.dmax / w.band;
  w.lip = A > 0 ? 1 + Ld : 1;
  w.rc = isfinite(w.band) ? w.band + w.dmax : INFINITY;
  if (karst_i_grow((void **)&t->warps, &t->cap_warps, t->n_warps + 1, sizeof *t->warps))
    return karst_set_error(ctx, KARST_ENOMEM, "warp: out of memory");
  karst_i_node_t *nd = NULL;
  if ((err = karst_i_sdf_new_node(ctx, t, KARST_SDF_WARP, &nd, node))) return err;
  const karst_i_node_t *c = &t->nodes[child];
  nd->u.warp.index = t->n_warps;
  nd->label = c->label;
  /* the solid moves by at most max|δ|: grow the child's box by it */
  nd->finite = c->finite;
  for (int i = 0; i < 3; i++) {
    nd->box[i] = c->box[i] - w.dmax;
    nd->box[i + 3] = c->box[i + 3] + w.dmax;
  }
  if (nd->finite) karst_i_pad_box(nd->box);
  t->warps[t->n_warps++] = w;
  return KARST_SUCCESS;
}

/** Relief of a warp node at @p p (see implicit.h); 0 for other nodes. O(1). */
double karst_sdf_warp_relief(const karst_sdf_t *t, karst_int_t node, const double p[3]) {
  if (!t || node < 0 || node >= t->n_nodes || t->nodes[node].kind != KARST_SDF_WARP) return 0;
  const karst_i_warp_t *w = &t->warps[t->nodes[node].u.warp.index];
  if (w->kind == KARST_RELIEF_FRACTURES) return w->amp * fractures3(w, p);
  return w->amp * relief2(t, w, p[0], p[1]);
}

/** The factor 1 + L_δ of a warp node (see implicit.h); 0 for other nodes. O(1). */
double karst_sdf_warp_lipschitz(const karst_sdf_t *t, karst_int_t node) {
  if (!t || node < 0 || node >= t->n_nodes || t->nodes[node].kind != KARST_SDF_WARP) return 0;
  return t->warps[t->nodes[node].u.warp.index].lip;
}
