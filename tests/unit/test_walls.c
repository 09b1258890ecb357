/* Conduit walls from a network (src/implicit/build.c with morph.c,
 * details.c, speleothem.c): blending at junctions (continuous field, closed
 * manifold mesh, the rounded flare), sections interpolating along edges and
 * across nodes and junctions (monotone area), details with amplitude 0 equal
 * to none, speleothems that never cross the floor nor leave their conduit,
 * byte-identical meshes on 1 and 2 threads, and the scenario's geometry
 * section. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "implicit/implicit_internal.h"
#include "karst.h"
#include "mesh/mesh_internal.h"
#include "sdf_check.h"
#include "test_util.h"

/* A network of @p n nodes and @p m edges with radius and tunnel_type. */
static void network(karst_network_t *net, const double (*P)[3], int n, const int (*E)[2], int m,
                    const double *r, const int *type) {
  karst_network_init(net);
  for (int i = 0; i < n; i++)
    karst_network_add_node(net, P[i][0], P[i][1], P[i][2], NULL);
  for (int e = 0; e < m; e++)
    karst_network_add_edge(net, E[e][0], E[e][1], NULL);
  double *rad, *typ;
  karst_network_attr_add(net, KARST_ATTR_EDGE, "radius", 1, 0, &rad);
  karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &typ);
  for (int e = 0; e < m; e++)
    rad[e] = r[e], typ[e] = type[e];
}

static karst_sdf_t *build_on(const karst_network_t *net, const karst_implicit_params_t *par,
                             karst_implicit_stats_t *st, int nthreads) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = nthreads;
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_error_t err = karst_implicit_build(&ctx, net, par, NULL, t, st);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  return t;
}

static karst_sdf_t *build(const karst_network_t *net, const karst_implicit_params_t *par,
                          karst_implicit_stats_t *st) {
  return build_on(net, par, st, 1);
}

/* The conduits of @p net without details or speleothems, with speleothem rules (@p g, in @p par)
 * of the given densities (per m²) in chambers and passages. */
static karst_sdf_t *bare_conduits(const karst_network_t *net, double chamber, double passage,
                                  karst_geometry_t *g, karst_implicit_params_t *par) {
  karst_geometry_init(g);
  g->speleothems[KARST_TUNNEL_CHAMBER].density = chamber;
  g->speleothems[KARST_TUNNEL_PASSAGE].density = passage;
  karst_implicit_params_init(par);
  par->geometry = g;
  par->details = 0;
  par->speleothems = 0;
  return build(net, par, NULL);
}

static void assert_closed(const karst_mesh_t *m) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_mesh_check_t chk;
  assert_int_equal(karst_mesh_check(&ctx, m, &chk), KARST_SUCCESS);
  assert_int_equal(chk.boundary_edges, 0);
  assert_int_equal(chk.nonmanifold_edges, 0);
  assert_int_equal(chk.degenerate, 0);
  karst_i_cgal_report_t rep;
  char err[256] = "";
  assert_int_equal(
      karst_i_cgal_check_mesh(m->xyz, m->n_vertices, m->tri, m->n_triangles, &rep, err, sizeof err),
      0);
  assert_true(rep.is_polygon_mesh && rep.closed && rep.outward);
}

/* A T-junction: a tube of radius 1.5 m along x through node 0, a tube of
 * radius 1.2 m branching off along y. With the default blend (the smallest
 * radius, 1.2 m) the field is 1-Lipschitz (continuous), the mesh closed and
 * manifold for CGAL and by our edge count, and the re-entrant corner between
 * the branches is rounded (a point 0.15 m into the rock from both walls is
 * in the void); the blended volume exceeds the hard one, by less than 10 %.
 * geometry.blend = 0 (--blend 0) builds the hard union, without blend nodes. */
static void test_t_junction(void **state) {
  (void)state;
  double P[4][3] = {{0, 0, 0}, {-12, 0, 0}, {12, 0, 0}, {0, 12, 0}};
  int E[3][2] = {{1, 0}, {0, 2}, {0, 3}}, type[3] = {0, 0, 0};
  double r[3] = {1.5, 1.5, 1.2};
  karst_network_t net;
  network(&net, P, 4, E, 3, r, type);
  karst_geometry_t g;
  karst_geometry_init(&g);
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.details = par.speleothems = 0;
  par.geometry = &g;
  karst_implicit_stats_t st;
  karst_sdf_t *blend = build(&net, &par, &st);
  assert_int_equal(st.n_blends, 1);
  assert_int_equal(st.n_continuations, 1); /* the two halves of the x tube */
  g.blend = 0;
  karst_sdf_t *hard = build(&net, &par, &st);
  assert_int_equal(st.n_blends, 0);
  /* 0.15 m into the rock from both walls near the crease (x = 1.2, y = 1.5): by hand,
   * min(ball, smin(min(left, right), branch)) with k = 1.2 of the values 0.63, 1.36, 0.15 and
   * 0.15 is min(0.63, 0.15 - k/4) = -0.15 */
  double corner[3] = {1.35, 1.65, 0};
  double fh = karst_sdf_eval(hard, corner, NULL), fb = karst_sdf_eval(blend, corner, NULL);
  printf("T-junction corner (1.35, 1.65, 0): hard union %.4f m, blended %.4f m\n", fh, fb);
  assert_close(fh, 0.15, 0.01); /* the tube's quadratics bulge by up to 0.3 % of r */
  assert_close(fb, -0.15, 0.01);
  assert_lipschitz(blend, karst_sdf_root(blend), 3, 4000, "blended T-junction");
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  double box[6] = {-11, -3, -3, 11, 11, 3};
  karst_mesh_t mb, mh;
  karst_mesh_init(&mb);
  karst_mesh_init(&mh);
  assert_int_equal(karst_mesh_polygonize(&ctx, blend, box, 0.15, &mb, NULL), KARST_SUCCESS);
  assert_int_equal(karst_mesh_polygonize(&ctx, hard, box, 0.15, &mh, NULL), KARST_SUCCESS);
  assert_closed(&mb);
  assert_closed(&mh);
  double vb = karst_mesh_volume(&mb), vh = karst_mesh_volume(&mh);
  printf("T-junction volumes: blended %.3f m3, hard %.3f m3\n", vb, vh);
  assert_true(vb > vh + 0.05);
  assert_true(vb < 1.1 * vh);
  karst_mesh_destroy(&mb);
  karst_mesh_destroy(&mh);
  karst_sdf_free(blend);
  karst_sdf_free(hard);
  karst_network_destroy(&net);
}

/* Area of the section of the root in the plane x = @p x (a grid of h). */
static double area_at_x(const karst_sdf_t *t, double x, double ext, double h) {
  long in = 0;
  int n = (int)(2 * ext / h);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double p[3] = {x, -ext + (i + 0.5) * h, -ext + (j + 0.5) * h};
      in += karst_sdf_eval(t, p, NULL) < 0;
    }
  return in * h * h;
}

/* A tube (r = 1 m) turning into a canyon (r = 1.5 m) at a straight node, and
 * a keyhole continuing into a passage across a junction (a third edge
 * branching off): along each path the section area, counted in planes across
 * the axis (grid of 3 cm: ±0.3 m² allowed for the counting error), varies monotonically
 * from one end's area to the other's, through the node or junction. */
static void test_sections_along_paths(void **state) {
  (void)state;
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.details = par.speleothems = 0;
  karst_geometry_t g;
  karst_geometry_init(&g);
  g.blend = 0; /* the junction's ball and blend would add area there */
  par.geometry = &g;
  karst_section_t tube, canyon, keyhole, passage;
  karst_section_for_type(NULL, KARST_TUNNEL_TUBE, &tube);
  karst_section_for_type(NULL, KARST_TUNNEL_CANYON, &canyon);
  karst_section_for_type(NULL, KARST_TUNNEL_KEYHOLE, &keyhole);
  karst_section_for_type(NULL, KARST_TUNNEL_PASSAGE, &passage);
  for (int c = 0; c < 2; c++) {
    double P[4][3] = {{-10, 0, 0}, {0, 0, 0}, {10, 0, 0}, {0, 0, 10}};
    int E[3][2] = {{0, 1}, {1, 2}, {1, 3}};
    int type[3] = {KARST_TUNNEL_TUBE, KARST_TUNNEL_CANYON, KARST_TUNNEL_TUBE};
    double r[3] = {1.0, 1.5, 0.5};
    if (c) type[0] = KARST_TUNNEL_KEYHOLE, type[1] = KARST_TUNNEL_PASSAGE, r[0] = 1.5, r[1] = 1.2;
    karst_network_t net;
    network(&net, P, c ? 4 : 3, E, c ? 3 : 2, r, type);
    karst_implicit_stats_t st;
    karst_sdf_t *t = build(&net, &par, &st);
    assert_int_equal(st.n_morphs, 2);
    /* the joint's plane x = 0 lies inside both sweeps (they overlap by
     * KARST_I_JOINT_OVERLAP): no point inside has field 0 there */
    double centre[3] = {0, 0.3, -0.2};
    assert_true(karst_sdf_eval(t, centre, NULL) <= -0.5 * KARST_I_JOINT_OVERLAP);
    const karst_section_t *sa = c ? &keyhole : &tube, *sb = c ? &passage : &canyon;
    double Aa = r[0] * r[0] * karst_section_area(sa), Ab = r[1] * r[1] * karst_section_area(sb);
    double prev = 0, first = 0, last = 0;
    int rising = Ab > Aa;
    for (int i = 0; i <= 16; i++) {
      double x = -9.5 + 19.0 * i / 16;
      if (c && fabs(x) < 0.8) continue; /* the branch itself */
      double A = area_at_x(t, x, 3.5, 0.03);
      if (i == 0) first = A;
      last = A;
      if (i > 0 && prev > 0) assert_true(rising ? A >= prev - 0.3 : A <= prev + 0.3);
      prev = A;
    }
    printf("%s -> %s: end areas %.3f, %.3f m2 (expected %.3f, %.3f)\n", c ? "keyhole" : "tube",
           c ? "passage" : "canyon", first, last, Aa, Ab);
    assert_rel(first, Aa, 0.03);
    assert_rel(last, Ab, 0.03);
    karst_sdf_free(t);
    karst_network_destroy(&net);
  }
}

/* Details with every amplitude 0 give exactly the tree without details; with
 * details the surface stays within the largest amplitude of it. */
static void test_details_off_and_on(void **state) {
  (void)state;
  double P[4][3] = {{0, 0, 0}, {-12, 0, 0}, {12, 2, 0}, {0, 10, 1}};
  int E[3][2] = {{1, 0}, {0, 2}, {0, 3}};
  int type[3] = {KARST_TUNNEL_CANYON, KARST_TUNNEL_KEYHOLE, KARST_TUNNEL_TUBE};
  double r[3] = {1.5, 1.5, 1.0};
  karst_network_t net;
  network(&net, P, 4, E, 3, r, type);
  karst_geometry_t g;
  karst_geometry_init(&g);
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.speleothems = 0;
  par.geometry = &g;
  par.details = 0;
  karst_sdf_t *off = build(&net, &par, NULL);
  par.details = 1;
  karst_implicit_stats_t st;
  karst_sdf_t *on = build(&net, &par, &st);
  assert_true(st.details_lipschitz > 1);
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++)
    g.details[k].amplitude = 0;
  karst_sdf_t *zero = build(&net, &par, &st);
  assert_true(st.details_lipschitz == 0);
  karst_rng_t r0;
  karst_rng_init(&r0, 1, 0);
  int changed = 0;
  for (int i = 0; i < 20000; i++) {
    double p[3] = {karst_rng_uniform_range(&r0, -12, 12), karst_rng_uniform_range(&r0, -3, 11),
                   karst_rng_uniform_range(&r0, -3, 3)};
    double f0 = karst_sdf_eval(off, p, NULL);
    assert_true(karst_sdf_eval(zero, p, NULL) == f0);
    if (i % 2) { /* half of the points near the wall: moved along the field until |f| < 0.05 */
      for (int it = 0; it < 40 && fabs(f0) > 0.02; it++) {
        p[2] += f0 > 0 ? -0.5 * f0 : 0.5 * f0;
        f0 = karst_sdf_eval(off, p, NULL);
      }
      assert_true(karst_sdf_eval(zero, p, NULL) == f0);
    }
    double f1 = karst_sdf_eval(on, p, NULL);
    if (fabs(f0) > 0.05 * (1 + 1e-9)) assert_true((f1 < 0) == (f0 < 0));
    changed += (f1 < 0) != (f0 < 0);
  }
  printf("details: %d of 20000 points changed side\n", changed);
  assert_true(changed > 20);
  assert_lipschitz(on, karst_sdf_root(on), 2, 4000, "detailed junction");
  karst_sdf_free(off);
  karst_sdf_free(on);
  karst_sdf_free(zero);
  karst_network_destroy(&net);
}

/* A chamber (ellipsoid 12 x 5 x 3 m) between two passages: speleothems are
 * placed; each stalactite's lowest point is at least the clearance above the
 * floor and each stalagmite's top as much below the ceiling (computed from
 * the round cones, not from the placement); every point sampled inside a
 * speleothem is in the conduit's void, or in the rock over (under) its own
 * root; the mesh carries feature 1 on speleothem triangles and is closed;
 * the same seed and realisation place the same speleothems, another
 * realisation others. */
static void test_speleothems(void **state) {
  (void)state;
  double P[4][3] = {{-20, 0, 0}, {-6, 0, 0}, {6, 0, 0}, {20, 0, 0}};
  int E[3][2] = {{0, 1}, {1, 2}, {2, 3}};
  int type[3] = {KARST_TUNNEL_PASSAGE, KARST_TUNNEL_CHAMBER, KARST_TUNNEL_PASSAGE};
  double r[3] = {2.0, 5.0, 2.0};
  karst_network_t net;
  network(&net, P, 4, E, 3, r, type);
  karst_geometry_t g;
  karst_implicit_params_t par;
  karst_sdf_t *bare = bare_conduits(&net, 0.3, 0.2, &g, &par);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_speleothem_t *s = NULL, *s2 = NULL, *s3 = NULL;
  karst_int_t n = 0, n2 = 0, n3 = 0;
  assert_int_equal(
      karst_speleothems_place(&ctx, bare, karst_sdf_root(bare), &net, &g, 1, 0.05, 7, 0, &s, &n),
      KARST_SUCCESS);
  assert_int_equal(
      karst_speleothems_place(&ctx, bare, karst_sdf_root(bare), &net, &g, 1, 0.05, 7, 0, &s2, &n2),
      KARST_SUCCESS);
  assert_int_equal(
      karst_speleothems_place(&ctx, bare, karst_sdf_root(bare), &net, &g, 1, 0.05, 7, 1, &s3, &n3),
      KARST_SUCCESS);
  assert_int_equal(n, n2);
  assert_memory_equal(s, s2, (size_t)n * sizeof *s);
  printf("speleothems: %lld for realisation 0, %lld for realisation 1\n", (long long)n,
         (long long)n3);
  assert_true(n3 > 0 && (n3 != n || memcmp(s, s3, (size_t)n * sizeof *s) != 0));
  int stalagmites = 0;
  karst_rng_t rr;
  karst_rng_init(&rr, 3, 0);
  for (karst_int_t i = 0; i < n; i++) {
    const karst_speleothem_t *q = &s[i];
    double clear = g.speleothems[q->type].clearance;
    if (q->kind == KARST_STALACTITE) {
      assert_true(q->tip[2] - q->tip_radius >= q->floor + clear - 1e-9);
    } else {
      stalagmites++;
      assert_true(q->tip[2] + q->tip_radius <= q->ceiling - clear + 1e-9);
    }
    /* points of the round cone: balls interpolated along the axis */
    for (int k = 0; k < 300; k++) {
      double u = karst_rng_uniform(&rr), d[3], p[3];
      karst_rng_unit_vector(&rr, d);
      double rad =
          (q->root_radius + u * (q->tip_radius - q->root_radius)) * cbrt(karst_rng_uniform(&rr));
      for (int c = 0; c < 3; c++)
        p[c] = q->root[c] + u * (q->tip[c] - q->root[c]) + rad * d[c];
      double f = karst_sdf_eval(bare, p, NULL);
      if (f < 0) continue; /* in the void */
      /* in rock: only where the root merges with the ceiling (floor): within the root ball,
       * sunk embed (0.05 m) plus its radius, or the root zone (the balls within a root radius
       * of the wall's level, plus the 2 cm spacing of the checks) */
      double wall = q->kind == KARST_STALACTITE ? q->ceiling : q->floor;
      double dc[3] = {p[0] - q->root[0], p[1] - q->root[1], p[2] - wall};
      assert_true(sqrt(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]) <=
                  3 * q->root_radius + 0.05 + 0.03);
    }
  }
  printf("speleothems: %lld placed, %d stalagmites\n", (long long)n, stalagmites);
  assert_true(n >= 10 && stalagmites > 0);
  /* the built tree and its mesh */
  par.speleothems = 1;
  karst_implicit_stats_t st;
  karst_sdf_t *t = build(&net, &par, &st);
  assert_true(st.n_stalactites > 0);
  assert_lipschitz(t, karst_sdf_root(t), 1, 3000, "conduits minus speleothems");
  ctx.nthreads = 2;
  double box[6] = {-19, -6, -4, 19, 6, 4};
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.12, &m, NULL), KARST_SUCCESS);
  assert_closed(&m);
  long feat = 0;
  for (karst_int_t i = 0; i < m.n_triangles; i++) {
    assert_true(m.tri_feature[i] == KARST_SDF_FEATURE_WALL ||
                m.tri_feature[i] == KARST_SDF_FEATURE_SPELEOTHEM || m.tri_feature[i] == -1);
    if (m.tri_feature[i] == KARST_SDF_FEATURE_SPELEOTHEM) {
      feat++;
      assert_true(m.tri_label[i] == KARST_TUNNEL_CHAMBER || m.tri_label[i] == KARST_TUNNEL_PASSAGE);
    }
  }
  printf("chamber mesh: %lld triangles, %ld on speleothems\n", (long long)m.n_triangles, feat);
  assert_true(feat > 1000);
  karst_mesh_destroy(&m);
  free(s);
  free(s2);
  free(s3);
  karst_sdf_free(bare);
  karst_sdf_free(t);
  karst_network_destroy(&net);
}

/* Speleothems are examined on several threads by edges, in batches of a few thousand
 * candidates, and accepted in edge order: the list is the same, byte for byte, on 1 and 3
 * threads, here over 4 edges with 4 353 candidates (two batches). */
static void test_speleothems_threads(void **state) {
  (void)state;
  double P[5][3] = {{0, 0, 0}, {40, 0, 0}, {80, 2, 0}, {120, 2, 1}, {160, 0, 1}};
  int E[4][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 4}};
  int type[4] = {KARST_TUNNEL_PASSAGE, KARST_TUNNEL_PASSAGE, KARST_TUNNEL_CHAMBER,
                 KARST_TUNNEL_PASSAGE};
  double r[4] = {2.0, 2.5, 4.0, 2.0};
  karst_network_t net;
  network(&net, P, 5, E, 4, r, type);
  karst_geometry_t g;
  karst_implicit_params_t par;
  karst_sdf_t *bare = bare_conduits(&net, 4, 6, &g, &par);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_speleothem_t *s1 = NULL, *s3 = NULL;
  karst_int_t n1 = 0, n3 = 0;
  ctx.nthreads = 1;
  assert_int_equal(karst_speleothems_place(&ctx, bare, karst_sdf_root(bare), &net, &g, 1, 0.05, 11,
                                           0, &s1, &n1),
                   KARST_SUCCESS);
  ctx.nthreads = 3;
  assert_int_equal(karst_speleothems_place(&ctx, bare, karst_sdf_root(bare), &net, &g, 1, 0.05, 11,
                                           0, &s3, &n3),
                   KARST_SUCCESS);
  printf("speleothems over 4 edges: %lld placed on 1 thread, %lld on 3\n", (long long)n1,
         (long long)n3);
  assert_true(n1 > 100); /* dense: the spacing rejects many, and it depends on the order */
  assert_int_equal(n1, n3);
  assert_memory_equal(s1, s3, (size_t)n1 * sizeof *s1);
  for (karst_int_t i = 1; i < n1; i++) /* in edge order */
    assert_true(s1[i].edge >= s1[i - 1].edge);
  free(s1);
  free(s3);
  karst_sdf_free(bare);
  karst_network_destroy(&net);
}

/* With everything on (blending, sections, details, speleothems) the mesh is
 * the same, array for array, on 1 and 2 threads; and so is the tree built on 1 and on 3 threads
 * (its sections' mixtures are integrated, and its speleothems examined, on the threads). */
static void test_deterministic(void **state) {
  (void)state;
  double P[5][3] = {{-15, 0, 0}, {0, 0, 0}, {12, 3, 1}, {0, 14, 0}, {20, 10, 1}};
  int E[4][2] = {{0, 1}, {1, 2}, {1, 3}, {2, 4}};
  int type[4] = {KARST_TUNNEL_CANYON, KARST_TUNNEL_PASSAGE, KARST_TUNNEL_TUBE,
                 KARST_TUNNEL_CHAMBER};
  double r[4] = {1.5, 2.0, 1.0, 4.0};
  karst_network_t net;
  network(&net, P, 5, E, 4, r, type);
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.voxel = 0.2;
  karst_implicit_stats_t st;
  karst_sdf_t *t = build(&net, &par, &st);
  double box[6];
  karst_sdf_node_box(t, karst_sdf_root(t), box);
  karst_mesh_t m1, m2;
  karst_mesh_init(&m1);
  karst_mesh_init(&m2);
  assert_same_on_1_and_2_threads(t, box, 0.2, &m1, &m2);
  assert_closed(&m1);
  printf("all on: %lld triangles, %lld stalactites, %lld morphs, %lld blends\n",
         (long long)m1.n_triangles, (long long)st.n_stalactites, (long long)st.n_morphs,
         (long long)st.n_blends);
  assert_true(st.n_morphs > 0 && st.n_stalactites > 0);
  karst_implicit_stats_t st3;
  karst_sdf_t *t3 = build_on(&net, &par, &st3, 3);
  assert_memory_equal(&st, &st3, sizeof st);
  karst_mesh_t m3;
  karst_mesh_init(&m3);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  assert_int_equal(karst_mesh_polygonize(&ctx, t3, box, 0.2, &m3, NULL), KARST_SUCCESS);
  assert_int_equal(m1.n_vertices, m3.n_vertices);
  assert_int_equal(m1.n_triangles, m3.n_triangles);
  assert_memory_equal(m1.xyz, m3.xyz, (size_t)m1.n_vertices * 3 * sizeof(double));
  assert_memory_equal(m1.tri, m3.tri, (size_t)m1.n_triangles * 3 * sizeof(karst_int_t));
  karst_mesh_destroy(&m3);
  karst_sdf_free(t3);
  karst_mesh_destroy(&m1);
  karst_mesh_destroy(&m2);
  karst_sdf_free(t);
  karst_network_destroy(&net);
}

/* Round cones (speleothems' primitive): outside, the distance to the union
 * of the balls interpolated along the axis is the minimum over the balls of
 * |p - c(t)| - r(t) (brute force over 20001 values of t, to 1e-6); inside,
 * negative; 1-Lipschitz; bad radii refused. */
static void test_round_cone(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  const double a[3] = {0.5, -1, 2}, b[3] = {1.5, 0.5, -1.5}, ra = 0.8, rb = 0.15;
  karst_int_t c;
  assert_int_equal(karst_sdf_round_cone(&ctx, t, a, ra, b, rb, 3, &c), KARST_SUCCESS);
  karst_rng_t r;
  karst_rng_init(&r, 12, 0);
  for (int i = 0; i < 400; i++) {
    double p[3] = {karst_rng_uniform_range(&r, -3, 4), karst_rng_uniform_range(&r, -4, 3),
                   karst_rng_uniform_range(&r, -5, 5)};
    double best = INFINITY;
    for (int k = 0; k <= 20000; k++) {
      double u = k / 20000.0, d2 = 0;
      for (int j = 0; j < 3; j++)
        d2 += (p[j] - a[j] - u * (b[j] - a[j])) * (p[j] - a[j] - u * (b[j] - a[j]));
      best = fmin(best, sqrt(d2) - (ra + u * (rb - ra)));
    }
    double f = karst_sdf_eval_node(t, c, p, NULL, NULL);
    if (best > 0)
      assert_close(f, best, 1e-6);
    else
      assert_true(f <= 0);
  }
  assert_lipschitz(t, c, 1, 3000, "round cone");
  karst_int_t d;
  assert_int_equal(karst_sdf_round_cone(&ctx, t, a, 5, b, 0.1, 3, &d), KARST_EINVAL);
  assert_int_equal(karst_sdf_round_cone(&ctx, t, a, 0, b, 0.1, 3, &d), KARST_EINVAL);
  karst_sdf_free(t);
}

/* The scenario's geometry section: values read, "auto" blend, and bad input
 * named with its line and column. */
static karst_error_t load_text(karst_ctx_t *ctx, const char *text, karst_scenario_t *sc,
                               char *path) {
  strcpy(path, "/tmp/karst_geometry_XXXXXX");
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  FILE *f = fdopen(fd, "w");
  fprintf(f,
          "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
          "key_points:\n  - {type: spring, position: [50, 50, 10]}\n"
          "%s",
          text);
  fclose(f);
  karst_error_t err = karst_scenario_load(ctx, path, sc);
  remove(path);
  return err;
}

static void test_geometry_section(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  char path[64];
  assert_int_equal(load_text(&ctx,
                             "geometry:\n"
                             "  blend: 0.75\n"
                             "  details:\n"
                             "    canyon: {amplitude: 0.07, wavelength: 0.6, orientation: -30}\n"
                             "  speleothems:\n"
                             "    passage: {density: 0.1, min_length: 0.2, max_length: 0.4}\n"
                             "  fracture_relief: 0.1\n",
                             &sc, path),
                   KARST_SUCCESS);
  assert_close(sc.geometry.blend, 0.75, 0);
  assert_close(sc.geometry.details[KARST_TUNNEL_CANYON].amplitude, 0.07, 0);
  assert_close(sc.geometry.details[KARST_TUNNEL_CANYON].orientation, -30, 0);
  assert_close(sc.geometry.details[KARST_TUNNEL_CANYON].bandwidth, 1.5, 0); /* default kept */
  assert_close(sc.geometry.speleothems[KARST_TUNNEL_PASSAGE].max_length, 0.4, 0);
  assert_close(sc.geometry.fracture_relief, 0.1, 0);
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_SUCCESS);
  karst_scenario_destroy(&sc);
  karst_scenario_init(&sc);
  assert_int_equal(load_text(&ctx, "geometry: {blend: auto}\n", &sc, path), KARST_SUCCESS);
  assert_true(sc.geometry.blend < 0);
  karst_scenario_destroy(&sc);
  struct {
    const char *text, *msg;
  } bad[] = {
      {"geometry: {blend: -1}\n", ":4:19: geometry.blend must be auto or a width >= 0 m, got -1"},
      {"geometry: {blend: wide}\n", ":4:19: geometry.blend must be a number, got 'wide'"},
      {"geometry: {blen: 1}\n", ":4:12: unknown key 'blen' in geometry (did you mean 'blend'?)"},
      {"geometry:\n  details:\n    canyon: {orientation: 120}\n",
       ":6:27: geometry.details.canyon.orientation must be within [-90, 90] degrees, got 120"},
      {"geometry:\n  details:\n    cave: {amplitude: 1}\n",
       ":6:5: unknown key 'cave' in geometry.details"},
      {"geometry:\n  speleothems:\n    chamber: {min_length: 2, max_length: 1}\n",
       ":6:14: geometry.speleothems.chamber: min_length (2 m) must be <= max_length (1 m)"},
      {"geometry:\n  speleothems:\n    chamber: {density: -0.1}\n",
       ":6:24: geometry.speleothems.chamber.density must be >= 0 per m², got -0.1"},
      {"geometry: [1, 2]\n", ":4:11: geometry must be a map of keys, got a list"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    karst_scenario_init(&sc);
    karst_error_t err = load_text(&ctx, bad[i].text, &sc, path);
    if (err == KARST_SUCCESS || !strstr(ctx.errmsg, bad[i].msg) || !strstr(ctx.errmsg, path)) {
      print_error("case %zu: got \"%s\", expected \"%s\"\n", i, ctx.errmsg, bad[i].msg);
      fail();
    }
    karst_scenario_destroy(&sc);
  }
  /* a scenario built in code is checked too */
  karst_scenario_init(&sc);
  sc.geometry.details[KARST_TUNNEL_TUBE].anisotropy = 2;
  assert_int_equal(karst_scenario_check(&ctx, &sc), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "geometry.details.tube.anisotropy must be within [0, 1]"));
  karst_scenario_destroy(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_t_junction),         cmocka_unit_test(test_sections_along_paths),
      cmocka_unit_test(test_details_off_and_on), cmocka_unit_test(test_speleothems),
      cmocka_unit_test(test_speleothems_threads),
      cmocka_unit_test(test_deterministic),      cmocka_unit_test(test_round_cone),
      cmocka_unit_test(test_geometry_section),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
