/* Rock blocks (src/blocks/, Paris et al. 2020 §4–5) and the block nodes of
 * src/implicit/ (smooth.c). Expected values are hand calculations (box
 * tiles, the smooth maximum's bounds), independent methods (brute-force
 * visibility, FLANN against the grid, CGAL's volume against ours) or exact
 * invariants (periodicity, thread independence). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "blocks/blocks_internal.h"
#include "implicit/implicit_internal.h"
#include "karst.h"
#include "karst/blocks.h"
#include "mesh/mesh_internal.h"
#include "test_util.h"

/* A small tile for the tests: side s, Poisson radius r, the type's disc
 * sizes scaled from the 20 m defaults. */
static void small_params(karst_blocks_tile_params_t *p, int type, double s, double r) {
  karst_blocks_tile_params_init(p, type);
  double k = s / p->size;
  karst_blocks_tile_params_resize(p, s, r);
  p->smooth_radius *= k;
  p->aperture *= k;
}

/* ---------------------------------------------------------------------- */
/* The smooth maximum (smooth.c).                                          */
/* ---------------------------------------------------------------------- */

/* Two half-spaces at angle theta and their smooth intersection. */
static karst_int_t two_planes(karst_sdf_t *t, double theta, double R) {
  karst_int_t k[2];
  double o[3] = {0, 0, 0}, u1[3] = {1, 0, 0}, u2[3] = {cos(theta), sin(theta), 0};
  assert_int_equal(karst_sdf_plane(NULL, t, o, u1, &k[0]), KARST_SUCCESS);
  assert_int_equal(karst_sdf_plane(NULL, t, o, u2, &k[1]), KARST_SUCCESS);
  karst_int_t n;
  assert_int_equal(karst_sdf_smooth_intersection(NULL, t, 2, k, R, NULL, &n), KARST_SUCCESS);
  return n;
}

static void test_smooth_max_values(void **state) {
  (void)state;
  /* hand values: |a-b| >= R gives max; a = b gives max + R/6; k = 1/2 gives + R/48 */
  assert_close(karst_sdf_smooth_max(1.0, -2.0, 0.25), 1.0, 0);
  assert_close(karst_sdf_smooth_max(0.5, 0.5, 0.25), 0.5 + 0.25 / 6, 1e-15);
  assert_close(karst_sdf_smooth_max(0.125, 0.0, 0.25), 0.125 + 0.25 / 48, 1e-15);
  assert_close(karst_sdf_smooth_max(0.0, 0.125, 0.25), 0.125 + 0.25 / 48, 1e-15);
  assert_close(karst_sdf_smooth_max(-1, 3, 0), 3, 0);
  karst_sdf_t *t;
  assert_int_equal(karst_sdf_create(NULL, &t), KARST_SUCCESS);
  karst_int_t bad = 7;
  assert_int_equal(karst_sdf_smooth_intersection(NULL, t, 1, &bad, 0.25, NULL, &bad), KARST_EINVAL);
  assert_int_equal(karst_sdf_smooth_intersection(NULL, t, 0, NULL, 0.25, NULL, &bad), KARST_EINVAL);
  karst_sdf_free(t);
}

/* 1-Lipschitz on random pairs, for planes at 10..170 degrees, and the
 * paper's literal max - R k³/6 is not (its gradient reaches 1 + k² at a = b
 * for opposite normals): the reason for the sign (smooth.c). */
static void test_smooth_lipschitz(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 5, 0);
  double worst = 0, worst_literal = 0;
  for (int deg = 10; deg <= 170; deg += 20) {
    karst_sdf_t *t;
    assert_int_equal(karst_sdf_create(NULL, &t), KARST_SUCCESS);
    double R = 0.25, th = deg * M_PI / 180;
    karst_int_t n = two_planes(t, th, R);
    for (int i = 0; i < 20000; i++) {
      double p[3], q[3], d[3];
      karst_rng_unit_vector(&r, d);
      double len = pow(10, karst_rng_uniform_range(&r, -4, 0));
      for (int a = 0; a < 3; a++)
        p[a] = karst_rng_uniform_range(&r, -0.5, 0.5), q[a] = p[a] + len * d[a];
      double fp = karst_sdf_eval_node(t, n, p, NULL, NULL),
             fq = karst_sdf_eval_node(t, n, q, NULL, NULL);
      worst = fmax(worst, fabs(fp - fq) / len);
      /* the literal formula on the same two half-spaces */
      double ap = p[0], bp = cos(th) * p[0] + sin(th) * p[1];
      double aq = q[0], bq = cos(th) * q[0] + sin(th) * q[1];
      double kp = fmax(1 - fabs(ap - bp) / R, 0), kq = fmax(1 - fabs(aq - bq) / R, 0);
      double lp = fmax(ap, bp) - R * kp * kp * kp / 6, lq = fmax(aq, bq) - R * kq * kq * kq / 6;
      worst_literal = fmax(worst_literal, fabs(lp - lq) / len);
    }
    karst_sdf_free(t);
  }
  assert_true(worst <= 1 + 1e-9);
  assert_true(worst_literal > 1.2); /* 170 degrees: sqrt((1+k²/2)² + ...) well above 1 */
}

/* C¹: the central-difference gradient is continuous across the blend's two
 * boundaries (|a - b| = R) and its middle (a = b): the jump of the gradient
 * over a step 2h straddling the boundary shrinks with h. A plain max jumps
 * by |u1 - u2| at a = b. */
static void test_smooth_c1(void **state) {
  (void)state;
  karst_sdf_t *t;
  assert_int_equal(karst_sdf_create(NULL, &t), KARST_SUCCESS);
  double R = 0.25, th = 100 * M_PI / 180;
  karst_int_t n = two_planes(t, th, R);
  /* points along the line a - b = c for c in {-R, 0, R}: a = x, b = cos x + sin y */
  for (int which = -1; which <= 1; which++) {
    double c = which * R, x = 0.3;
    double y = (x - c - cos(th) * x) / sin(th); /* a - b = c */
    double jump[2];
    for (int level = 0; level < 2; level++) {
      double h = level ? 1e-5 : 1e-3, g[2][3];
      for (int side = 0; side < 2; side++) {
        /* step across the line: along the gradient of a - b */
        double dir[3] = {1 - cos(th), -sin(th), 0}, l = sqrt(dir[0] * dir[0] + dir[1] * dir[1]);
        double p[3] = {x + (side ? 2 : -2) * h * dir[0] / l, y + (side ? 2 : -2) * h * dir[1] / l,
                       0};
        for (int a = 0; a < 3; a++) {
          double pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]};
          pp[a] += h * 1e-2, pm[a] -= h * 1e-2;
          g[side][a] = (karst_sdf_eval_node(t, n, pp, NULL, NULL) -
                        karst_sdf_eval_node(t, n, pm, NULL, NULL)) /
                       (2 * h * 1e-2);
        }
      }
      jump[level] =
          sqrt(pow(g[0][0] - g[1][0], 2) + pow(g[0][1] - g[1][1], 2) + pow(g[0][2] - g[1][2], 2));
    }
    assert_true(jump[1] < 1e-3);           /* continuous at this scale */
    assert_true(jump[1] < jump[0] + 1e-9); /* and shrinking with the step */
  }
  karst_sdf_free(t);
}

static void test_thick_primitives(void **state) {
  (void)state;
  karst_sdf_t *t;
  assert_int_equal(karst_sdf_create(NULL, &t), KARST_SUCCESS);
  double one[3] = {1, 2, 3}, seg[6] = {0, 0, 0, 2, 0, 0},
         sq[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  double vol[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  karst_int_t a, b, c, d;
  assert_int_equal(karst_sdf_thick(NULL, t, 1, one, 0.5, 1e-6, 3, &a), KARST_SUCCESS);
  assert_int_equal(karst_sdf_thick(NULL, t, 2, seg, 0.5, 1e-6, 3, &b), KARST_SUCCESS);
  assert_int_equal(karst_sdf_thick(NULL, t, 4, sq, 0.1, 1e-6, 3, &c), KARST_SUCCESS);
  assert_int_equal(karst_sdf_thick(NULL, t, 5, vol, 0.1, 1e-6, 3, &d), KARST_EINVAL);
  double p1[3] = {1, 2, 4};
  assert_close(karst_sdf_eval_node(t, a, p1, NULL, NULL), 0.5, 1e-12);
  double p2[3] = {1, 3, 0}, p3[3] = {3, 0, 0};
  assert_close(karst_sdf_eval_node(t, b, p2, NULL, NULL), 2.5, 1e-12);
  assert_close(karst_sdf_eval_node(t, b, p3, NULL, NULL), 0.5, 1e-12);
  double p4[3] = {0.5, 0.5, 1}, p5[3] = {2, 0.5, 0}, p6[3] = {0.5, 0.5, 0};
  assert_close(karst_sdf_eval_node(t, c, p4, NULL, NULL), 0.9, 1e-12);
  assert_close(karst_sdf_eval_node(t, c, p5, NULL, NULL), 0.9, 1e-12);
  assert_close(karst_sdf_eval_node(t, c, p6, NULL, NULL), -0.1, 1e-12);
  karst_sdf_free(t);
}

/* ---------------------------------------------------------------------- */
/* Tiles.                                                                  */
/* ---------------------------------------------------------------------- */

/* Three orthogonal families of tile-spanning discs at spacing s/4 cut the
 * periodic tile into exactly 4³ = 64 boxes of side s/4: each block is the
 * box (6 planes), and the volumes add up to s³ (hand calculation); CGAL's
 * volume agrees with the divergence-theorem sum of the block's triangles. */
static void test_box_tile(void **state) {
  (void)state;
  const double s = 8;
  karst_blocks_tile_params_t p;
  small_params(&p, KARST_BLOCK_EQUIDIMENSIONAL, s, 0.4);
  p.n_discs = 0;
  karst_blocks_disc_t d[12];
  for (int a = 0; a < 3; a++)
    for (int k = 0; k < 4; k++) {
      karst_blocks_disc_t *D = &d[4 * a + k];
      memset(D, 0, sizeof *D);
      D->c[0] = D->c[1] = D->c[2] = 0.37 * s;
      D->c[a] = s / 8 + k * s / 4;
      D->n[a] = 1;
      D->radius = s; /* with its periodic copies, it covers its whole plane */
    }
  p.user_discs = d;
  p.n_user_discs = 12;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_blocks_tile_t *T = NULL;
  assert_int_equal(karst_blocks_tile_create(&ctx, &p, &T), KARST_SUCCESS);
  assert_int_equal(T->n_blocks, 64);
  double sum = 0;
  for (karst_int_t i = 0; i < T->n_blocks; i++) {
    const karst_blocks_block_t *B = &T->blocks[i];
    assert_int_equal(B->kind, KARST_BLOCK_CONVEX);
    assert_int_equal(B->n_planes, 6);
    assert_rel(B->volume, pow(s / 4, 3), 1e-9);
    assert_rel(B->cgal_volume, B->volume, 1e-9);
    for (int a = 0; a < 3; a++) /* between two consecutive planes; node boxes are padded by
                                   KARST_I_BOX_PAD_ABS (1e-6 m) each side plus rounding */
      assert_close(B->box[a + 3] - B->box[a], s / 4, 1e-5);
    /* the CGAL check of the polytope's own mesh: closed, outward */
    karst_i_cgal_report_t rep;
    assert_int_equal(karst_i_cgal_check_mesh(T->hulls[i].xyz, T->hulls[i].n_vertices,
                                             T->hulls[i].tri, T->hulls[i].n_triangles, &rep, NULL,
                                             0),
                     0);
    assert_true(rep.is_polygon_mesh && rep.closed && rep.outward);
    sum += B->volume;
  }
  assert_rel(sum, s * s * s, 1e-9);
  karst_blocks_tile_free(T);
}

/* Brute force (§4.1): every two points of every cluster see each other, on
 * small tiles of every type. */
static void test_visibility(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (int type = 0; type < KARST_BLOCK_TYPE_COUNT; type++) {
    karst_blocks_tile_params_t p;
    small_params(&p, type, 4, 0.4); /* about 600 points: every pair checked under ASan too */
    p.seed = 11 + type;
    karst_blocks_tile_t *T = NULL;
    assert_int_equal(karst_blocks_tile_create(&ctx, &p, &T), KARST_SUCCESS);
    assert_true(T->n_blocks >= 2);
    karst_int_t pairs = 0, members = 0;
    for (karst_int_t b = 0; b < T->n_blocks; b++) {
      const karst_blocks_block_t *B = &T->blocks[b];
      members += B->n_points;
      for (karst_int_t i = 0; i < B->n_points; i++)
        for (karst_int_t j = i + 1; j < B->n_points; j++) {
          const double *u = T->unwrapped + 3 * (B->first + i),
                       *v = T->unwrapped + 3 * (B->first + j);
          if (!karst_blocks_segment_visible(T, u, v)) {
            print_error("%s: block %lld points %lld and %lld do not see each other\n",
                        karst_block_type_name(type), (long long)b, (long long)i, (long long)j);
            fail();
          }
          pairs++;
        }
    }
    assert_int_equal(members, T->n_points); /* every point is in exactly one block */
    assert_true(pairs > 0);
    karst_blocks_tile_free(T);
  }
}

/* The grid search and FLANN return the same periodic edge set. */
static void test_grid_flann_agree(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 3, 0);
  double *x = NULL;
  karst_int_t n = 0;
  assert_int_equal(karst_i_blocks_poisson(NULL, 6, 0.3, 8, &r, &x, &n), KARST_SUCCESS);
  assert_true(n > 3000);
  /* Poisson: no two points closer than r, across the faces too */
  karst_i_edge_t *e1 = NULL, *e2 = NULL, *e0 = NULL;
  karst_int_t n1 = 0, n2 = 0, n0 = 0;
  assert_int_equal(karst_i_blocks_radius_graph(NULL, x, n, 6, 0.3, &e0, &n0), KARST_SUCCESS);
  assert_int_equal(n0, 0);
  assert_int_equal(karst_i_blocks_radius_graph(NULL, x, n, 6, 0.6, &e1, &n1), KARST_SUCCESS);
  assert_int_equal(karst_i_blocks_radius_graph_flann(NULL, x, n, 6, 0.6, &e2, &n2), KARST_SUCCESS);
  assert_true(n1 > 5 * n);
  assert_int_equal(n1, n2);
  karst_int_t across = 0;
  for (karst_int_t i = 0; i < n1; i++) {
    assert_int_equal(e1[i].u, e2[i].u);
    assert_int_equal(e1[i].v, e2[i].v);
    assert_memory_equal(e1[i].L, e2[i].L, 3);
    across += e1[i].L[0] || e1[i].L[1] || e1[i].L[2];
  }
  assert_true(across > 0); /* the torus is joined */
  free(e0);
  free(e1);
  free(e2);
  free(x);
}

/* The tile field is periodic: f(p) = f(p + s e_i). */
static void test_tile_periodic(void **state) {
  (void)state;
  karst_blocks_tile_params_t p;
  small_params(&p, KARST_BLOCK_RHOMBOHEDRAL, 6, 0.35);
  karst_blocks_tile_t *T = NULL;
  assert_int_equal(karst_blocks_tile_create(NULL, &p, &T), KARST_SUCCESS);
  karst_rng_t r;
  karst_rng_init(&r, 9, 0);
  int inside = 0;
  for (int i = 0; i < 300; i++) {
    double q[3];
    for (int a = 0; a < 3; a++)
      q[a] = karst_rng_uniform_range(&r, 0, 6);
    double f = karst_blocks_tile_eval(T, q);
    inside += f < 0;
    for (int a = 0; a < 3; a++) {
      double q2[3] = {q[0], q[1], q[2]};
      q2[a] += 6;
      assert_close(karst_blocks_tile_eval(T, q2), f, 1e-9);
      q2[a] -= 12;
      assert_close(karst_blocks_tile_eval(T, q2), f, 1e-9);
    }
  }
  assert_true(inside > 100); /* mostly rock */
  karst_blocks_tile_free(T);
}

/* Every block's mesh is closed and manifold (directed-edge check, and CGAL's). */
static void test_block_meshes(void **state) {
  (void)state;
  karst_blocks_tile_params_t p;
  small_params(&p, KARST_BLOCK_TABULAR, 5, 0.4);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  karst_blocks_tile_t *T = NULL;
  assert_int_equal(karst_blocks_tile_create(&ctx, &p, &T), KARST_SUCCESS);
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_blocks_tile_mesh(&ctx, T, 0.1, &m), KARST_SUCCESS);
  assert_true(m.n_triangles > 1000);
  karst_mesh_check_t ck;
  assert_int_equal(karst_mesh_check(&ctx, &m, &ck), KARST_SUCCESS);
  assert_int_equal(ck.boundary_edges, 0);
  assert_int_equal(ck.nonmanifold_edges, 0);
  assert_int_equal(ck.degenerate, 0);
  /* each block separately, through CGAL */
  int blocks_seen = 0;
  for (karst_int_t b = 0; b < T->n_blocks; b++) {
    karst_int_t nt = 0;
    for (karst_int_t t = 0; t < m.n_triangles; t++)
      nt += m.tri_label[t] == (int)b;
    if (!nt) continue;
    /* the block's own vertices only (CGAL checks a soup without unused points) */
    karst_int_t *tri = malloc(3 * (size_t)nt * sizeof *tri), k = 0, nv = 0;
    karst_int_t *map = malloc((size_t)m.n_vertices * sizeof *map);
    double *xyz = malloc(3 * (size_t)m.n_vertices * sizeof *xyz);
    assert_true(tri && map && xyz);
    for (karst_int_t v = 0; v < m.n_vertices; v++)
      map[v] = -1;
    for (karst_int_t t = 0; t < m.n_triangles; t++) {
      if (m.tri_label[t] != (int)b) continue;
      for (int c = 0; c < 3; c++) {
        karst_int_t v = m.tri[3 * t + c];
        if (map[v] < 0) {
          map[v] = nv;
          memcpy(xyz + 3 * nv++, m.xyz + 3 * v, 3 * sizeof *xyz);
        }
        tri[3 * k + c] = map[v];
      }
      k++;
    }
    karst_i_cgal_report_t rep;
    char msg[256] = "";
    int rc = karst_i_cgal_check_mesh(xyz, nv, tri, nt, &rep, msg, sizeof msg);
    free(tri);
    free(map);
    free(xyz);
    if (rc) print_error("block %lld: %s\n", (long long)b, msg);
    assert_int_equal(rc, 0);
    assert_true(rep.is_polygon_mesh && rep.closed && rep.outward);
    blocks_seen++;
  }
  assert_true(blocks_seen >= T->n_blocks / 2);
  karst_mesh_destroy(&m);
  karst_blocks_tile_free(T);
}

/* The warped blocks (§4.3, the warp node of src/implicit/warp.c): within
 * their stated bound, 1-Lipschitz, on random pairs near and across block
 * surfaces, and really displaced (the field differs from the unwarped one). */
static void test_warped_lipschitz(void **state) {
  (void)state;
  karst_blocks_tile_t *T[2] = {NULL, NULL};
  for (int k = 0; k < 2; k++) {
    karst_blocks_tile_params_t p;
    small_params(&p, KARST_BLOCK_EQUIDIMENSIONAL, 5, 0.4);
    if (k) {
      p.warp.relief = KARST_BLOCKS_RELIEF_NOISE;
      p.warp.amplitude = 0.08;
      p.warp.wavelength = 0.5;
    }
    assert_int_equal(karst_blocks_tile_create(NULL, &p, &T[k]), KARST_SUCCESS);
  }
  assert_int_equal(T[0]->n_blocks, T[1]->n_blocks); /* the warp changes no cluster */
  karst_rng_t r;
  karst_rng_init(&r, 21, 0);
  double worst = 0, moved = 0;
  for (int i = 0; i < 4000; i++) {
    karst_int_t b = (karst_int_t)karst_rng_below(&r, (uint64_t)T[1]->n_blocks);
    const double *box = T[1]->blocks[b].box;
    double p[3], q[3], d[3];
    for (int a = 0; a < 3; a++)
      p[a] = karst_rng_uniform_range(&r, box[a] - 0.2, box[a + 3] + 0.2);
    karst_rng_unit_vector(&r, d);
    double len = pow(10, karst_rng_uniform_range(&r, -3, 0));
    for (int a = 0; a < 3; a++)
      q[a] = p[a] + len * d[a];
    double fp = karst_blocks_block_eval(T[1], b, p), fq = karst_blocks_block_eval(T[1], b, q);
    worst = fmax(worst, fabs(fp - fq) / len);
    moved = fmax(moved, fabs(fp - karst_blocks_block_eval(T[0], b, p)));
  }
  assert_true(worst <= 1 + 1e-9);
  assert_true(moved > 0.005);
  for (int k = 0; k < 2; k++)
    karst_blocks_tile_free(T[k]);
}

/* A user-authored block (§4.1): a sphere in a small tile. Its sample points are its own (counted
 * by hand against the sphere), no generated block enters it (their field >= 0 inside it, carved
 * by max(b, -A)), and it is the tile's last block with its own field. */
static void test_authored_block(void **state) {
  (void)state;
  karst_blocks_tile_params_t p;
  small_params(&p, KARST_BLOCK_EQUIDIMENSIONAL, 5, 0.4);
  karst_sdf_t *user;
  assert_int_equal(karst_sdf_create(NULL, &user), KARST_SUCCESS);
  const double c[3] = {2.5, 2.5, 2.5}, rad = 1;
  karst_int_t node;
  assert_int_equal(karst_sdf_sphere(NULL, user, c, rad, 0, &node), KARST_SUCCESS);
  p.authored = user, p.authored_nodes = &node, p.n_authored = 1;
  karst_blocks_tile_t *T = NULL;
  assert_int_equal(karst_blocks_tile_create(NULL, &p, &T), KARST_SUCCESS);
  const karst_blocks_block_t *A = &T->blocks[T->n_blocks - 1];
  assert_int_equal(A->kind, KARST_BLOCK_AUTHORED);
  karst_int_t inside = 0;
  for (karst_int_t i = 0; i < T->n_points; i++) {
    const double *x = T->xyz + 3 * i;
    inside += (x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                  (x[2] - c[2]) * (x[2] - c[2]) <
              rad * rad;
  }
  assert_true(inside > 20);
  assert_int_equal(A->n_points, inside);
  karst_rng_t r;
  karst_rng_init(&r, 17, 0);
  for (int k = 0; k < 500; k++) {
    double d[3], q[3], t = 0.95 * rad * cbrt(karst_rng_uniform(&r));
    karst_rng_unit_vector(&r, d);
    for (int a = 0; a < 3; a++)
      q[a] = c[a] + t * d[a];
    assert_close(karst_blocks_block_eval(T, T->n_blocks - 1, q), t - rad, 1e-12);
    for (karst_int_t b = 0; b + 1 < T->n_blocks; b++)
      assert_true(karst_blocks_block_eval(T, b, q) >= rad - t - 1e-9);
  }
  karst_blocks_tile_free(T);
  karst_sdf_free(user);
}

/* Same seed, 1 or 2 threads: the same tile, bit for bit. */
static void test_threads(void **state) {
  (void)state;
  karst_blocks_tile_t *T[2] = {NULL, NULL};
  karst_mesh_t m[2];
  for (int k = 0; k < 2; k++) {
    karst_blocks_tile_params_t p;
    small_params(&p, KARST_BLOCK_POLYHEDRAL, 5, 0.4);
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    ctx.nthreads = k + 1;
    assert_int_equal(karst_blocks_tile_create(&ctx, &p, &T[k]), KARST_SUCCESS);
    karst_mesh_init(&m[k]);
    assert_int_equal(karst_blocks_tile_mesh(&ctx, T[k], 0.1, &m[k]), KARST_SUCCESS);
  }
  assert_int_equal(T[0]->n_blocks, T[1]->n_blocks);
  assert_memory_equal(T[0]->members, T[1]->members, (size_t)T[0]->n_points * sizeof *T[0]->members);
  assert_int_equal(m[0].n_vertices, m[1].n_vertices);
  assert_int_equal(m[0].n_triangles, m[1].n_triangles);
  assert_memory_equal(m[0].xyz, m[1].xyz, 3 * (size_t)m[0].n_vertices * sizeof(double));
  assert_memory_equal(m[0].tri, m[1].tri, 3 * (size_t)m[0].n_triangles * sizeof(karst_int_t));
  for (int k = 0; k < 2; k++) {
    karst_mesh_destroy(&m[k]);
    karst_blocks_tile_free(T[k]);
  }
}

static void test_params_checked(void **state) {
  (void)state;
  karst_blocks_tile_params_t p;
  karst_blocks_tile_params_init(&p, KARST_BLOCK_TABULAR);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  assert_int_equal(karst_blocks_tile_params_check(&ctx, &p), KARST_SUCCESS);
  p.poisson_radius = NAN;
  assert_int_equal(karst_blocks_tile_params_check(&ctx, &p), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "poisson_radius"));
  karst_blocks_tile_params_init(&p, 99);
  assert_int_equal(karst_blocks_tile_params_check(&ctx, &p), KARST_EINVAL);
  assert_int_equal(karst_block_type_from_name("tabular"), KARST_BLOCK_TABULAR);
  assert_int_equal(karst_block_type_from_name("tabulr"), -1);
}

/* Segment–disc test by hand. */
static void test_segment_disc(void **state) {
  (void)state;
  double c[3] = {0, 0, 0}, n[3] = {0, 0, 1}, t;
  double a[3] = {0.5, 0, -1}, b[3] = {0.5, 0, 1}, e[3] = {1.5, 0, 1}, f[3] = {0.5, 0, 0};
  assert_int_equal(karst_i_blocks_segment_disc(a, b, c, n, 1, &t), 1);
  assert_close(t, 0.5, 1e-15);
  assert_int_equal(karst_i_blocks_segment_disc(a, e, c, n, 0.9, &t), 0); /* crosses at x = 1 */
  assert_int_equal(karst_i_blocks_segment_disc(a, e, c, n, 1.0, &t), 1);
  double g[3] = {0.2, 0, 0};
  assert_int_equal(karst_i_blocks_segment_disc(f, g, c, n, 1, &t), 0); /* in the plane */
  assert_int_equal(karst_i_blocks_segment_disc(a, f, c, n, 1, &t), 1); /* touches */
}

/* A wall z = h(y) invariant along x: steep (slope 2) for 0 < y < 20, flat
 * elsewhere. Stratum by elevation: below 30 m the tile. Replication (§5) is
 * periodic along x (f(p) = f(p + s e_x): the same copies are present in
 * both cells), blocks sit on the steep part only, and the field is 1-Lipschitz. */
static int below30(void *arg, const double p[3]) {
  (void)arg;
  return p[2] < 30 ? 0 : 1;
}
static void test_replication(void **state) {
  (void)state;
  const double s = 5;
  karst_blocks_tile_params_t p;
  small_params(&p, KARST_BLOCK_EQUIDIMENSIONAL, s, 0.4);
  karst_blocks_tile_t *T = NULL;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  assert_int_equal(karst_blocks_tile_create(&ctx, &p, &T), KARST_SUCCESS);
  karst_terrain_t tr;
  memset(&tr, 0, sizeof tr);
  tr.is_grid = 1;
  tr.ncols = 9, tr.nrows = 41, tr.cellsize = 1, tr.xll = -40, tr.yll = -10;
  double z[9 * 41];
  for (int j = 0; j < 41; j++)
    for (int i = 0; i < 9; i++) {
      double y = tr.yll + j;
      z[j * 9 + i] = y < 0 ? 0 : y > 20 ? 40 : 2 * y;
    }
  tr.ncols = 9;
  /* x from -40 to -32: make it wide enough by a coarse cellsize in x? keep it square: 10 m cells */
  tr.cellsize = 1;
  tr.z = z;
  karst_sdf_t *tree;
  assert_int_equal(karst_sdf_create(NULL, &tree), KARST_SUCCESS);
  karst_int_t tn, rn, un;
  assert_int_equal(karst_sdf_terrain(NULL, tree, &tr, &tn), KARST_SUCCESS);
  karst_blocks_presence_t pres;
  karst_blocks_presence_init(&pres);
  int table[2] = {0, -1};
  const karst_blocks_tile_t *tiles[1] = {T};
  double region[6] = {-39, -5, -5, -33, 25, 45};
  karst_blocks_replica_t *rep = NULL;
  assert_int_equal(karst_blocks_replicate(&ctx, tree, tn, tiles, 1, below30, NULL, table, 2, &pres,
                                          region, &rep),
                   KARST_SUCCESS);
  assert_true(karst_blocks_replica_count(rep) > 0);
  assert_int_equal(karst_blocks_replica_node(NULL, rep, tree, &rn), KARST_SUCCESS);
  karst_int_t kids[2] = {tn, rn};
  assert_int_equal(karst_sdf_union(NULL, tree, 2, kids, &un), KARST_SUCCESS);
  karst_rng_t r;
  karst_rng_init(&r, 4, 0);
  int blocks_hit = 0;
  for (int i = 0; i < 3000; i++) {
    double q[3] = {karst_rng_uniform_range(&r, -38, -34 - s), karst_rng_uniform_range(&r, -3, 23),
                   karst_rng_uniform_range(&r, -3, 43)};
    int lab;
    double f = karst_sdf_eval_node(tree, rn, q, &lab, NULL);
    double q2[3] = {q[0] + s, q[1], q[2]};
    assert_close(karst_sdf_eval_node(tree, rn, q2, NULL, NULL), f, 1e-9);
    if (f < 0) {
      blocks_hit++;
      int type, id;
      assert_int_equal(karst_blocks_label_decode(lab, &type, &id), 1);
      assert_int_equal(type, KARST_BLOCK_EQUIDIMENSIONAL);
      assert_true(q[2] < 30 + s);              /* only the lower stratum has blocks */
      assert_true(q[1] > -s && q[1] < 20 + s); /* on the wall */
    }
    double d[3], len = pow(10, karst_rng_uniform_range(&r, -3, 0.5));
    karst_rng_unit_vector(&r, d);
    double q3[3] = {q[0] + len * d[0], q[1] + len * d[1], q[2] + len * d[2]};
    double g = karst_sdf_eval_node(tree, un, q, NULL, NULL),
           g3 = karst_sdf_eval_node(tree, un, q3, NULL, NULL);
    assert_true(fabs(g - g3) <= len * (1 + 1e-9));
  }
  assert_true(blocks_hit > 10);
  karst_blocks_replica_free(rep);
  karst_sdf_free(tree);
  karst_blocks_tile_free(T);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_smooth_max_values), cmocka_unit_test(test_smooth_lipschitz),
      cmocka_unit_test(test_smooth_c1),         cmocka_unit_test(test_thick_primitives),
      cmocka_unit_test(test_segment_disc),      cmocka_unit_test(test_params_checked),
      cmocka_unit_test(test_grid_flann_agree),  cmocka_unit_test(test_box_tile),
      cmocka_unit_test(test_visibility),        cmocka_unit_test(test_tile_periodic),
      cmocka_unit_test(test_block_meshes),      cmocka_unit_test(test_threads),
      cmocka_unit_test(test_replication),       cmocka_unit_test(test_warped_lipschitz),
      cmocka_unit_test(test_authored_block),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
