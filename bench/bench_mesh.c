/* Benchmark: construction-tree size, memory and build time, and
 * polygonization time over the whole extent (0.5 m by default), with the
 * plain tree (hard unions, smooth walls: the geometry before issue 15) and
 * with the walls of issue 15 (blended junctions, sections interpolated along
 * the edges, Zanni et al. 2012 details, speleothems), for
 *  - "synthetic": a network the size of the "looping cave" of Paris et al.
 *    2021, Table 1 (0.5 x 0.7 x 0.2 km, 22 km of conduits; the paper: 67 k
 *    tree nodes, 7.4 MB, 7.5 s to build, about 2 minutes to polygonize a
 *    1 x 1 x 0.4 km region): 47 key points joined to their nearest neighbours
 *    by tortuous paths (midpoint displacement by up to 0.2 of the segment,
 *    down to 8 m segments), one radius in 0.5-4 m and one tunnel type per path;
 *  - "preset": datasets/scenarios/looping_cave.yaml as karst generate makes it;
 *  - "scenes": the close-ups of docs/geometry.md (a junction blended and
 *    not, a canyon with flutes, a chamber with speleothems) at their own
 *    voxels, the Table 1 of Zanni et al. 2012 (triangles, seconds); with
 *    OUTDIR their meshes are written there as PLY for the pictures.
 * Targets on 2 cores: tree <= 1 s, polygonization <= 60 s.
 * Usage: bench_mesh [VOXEL [THREADS [synthetic|preset|scenes|all|junction|canyon|chamber
 *        [plain|walls|both [OUTDIR]]]]]
 * (default 0.5 2 all both). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "karst.h"

/* CPU seconds of this process (user + system, every thread): on a shared
 * machine the wall clock measures the load, this the work. */
static double cpu_s(void) {
  struct rusage u;
  if (getrusage(RUSAGE_SELF, &u)) return NAN;
  return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec + (double)u.ru_stime.tv_sec +
         1e-6 * (double)u.ru_stime.tv_usec;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void clampv(double *p, const double lo[3], const double hi[3]) {
  for (int a = 0; a < 3; a++)
    p[a] = fmin(hi[a], fmax(lo[a], p[a]));
}

/* Path a -> b as a polyline: midpoint displacement by up to `amp` times the
 * segment length (tortuosity) until the segments are at most `seg` long. */
static int path(karst_network_t *net, karst_rng_t *r, karst_int_t ia, karst_int_t ib, double amp,
                double seg, const double lo[3], const double hi[3], int depth, double rad,
                int type) {
  const double *a = net->xyz + 3 * ia, *b = net->xyz + 3 * ib;
  double len = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                    (a[2] - b[2]) * (a[2] - b[2]));
  if (len <= seg || depth > 20) {
    karst_int_t e;
    if (karst_network_add_edge(net, ia, ib, &e)) return -1;
    karst_attr_t *ra = karst_network_attr_find(net, KARST_ATTR_EDGE, "radius");
    karst_attr_t *ta = karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
    ra->data[e] = rad;
    ta->data[e] = type;
    return 0;
  }
  double m[3], d[3];
  karst_rng_unit_vector(r, d);
  double s = amp * len * karst_rng_uniform(r);
  for (int c = 0; c < 3; c++)
    m[c] = 0.5 * (a[c] + b[c]) + s * d[c];
  m[2] = 0.5 * (a[2] + b[2]) + 0.3 * s * d[2]; /* flatter vertically */
  clampv(m, lo, hi);
  karst_int_t im;
  if (karst_network_add_node(net, m[0], m[1], m[2], &im)) return -1;
  if (path(net, r, ia, im, amp, seg, lo, hi, depth + 1, rad, type)) return -1;
  return path(net, r, im, ib, amp, seg, lo, hi, depth + 1, rad, type);
}

/* The plain tree (hard unions, no details nor speleothems) or the walls. */
static void params(karst_implicit_params_t *par, karst_geometry_t *g, int walls, double voxel) {
  karst_implicit_params_init(par);
  karst_geometry_init(g);
  par->geometry = g;
  par->voxel = voxel;
  if (!walls) {
    g->blend = 0;
    par->details = par->speleothems = 0;
  }
}

/* Build the tree of @p net and polygonize @p box at @p voxel; print the
 * figures; write the mesh to @p out when not NULL. */
static int run_case(karst_ctx_t *ctx, const char *name, const karst_network_t *net,
                    const double box[6], double voxel, const karst_implicit_params_t *par,
                    const char *out) {
  karst_sdf_t *sdf;
  if (karst_sdf_create(ctx, &sdf)) return -1;
  karst_implicit_stats_t bst;
  double t0 = now_s(), c0 = cpu_s();
  karst_error_t err = karst_implicit_build(ctx, net, par, NULL, sdf, &bst);
  double t1 = now_s(), c1 = cpu_s();
  if (err) {
    fprintf(stderr, "bench_mesh: %s\n", ctx->errmsg);
    karst_sdf_free(sdf);
    return -1;
  }
  karst_sdf_stats_t ss;
  karst_sdf_stats(sdf, &ss);
  printf("bench_mesh: %s: tree: %lld nodes (%lld sweeps, %lld of them morphing, with %lld mitred "
         "ends, %lld revolved sections at %lld sharp bends, %lld junction balls, %lld blended "
         "junctions, %lld ellipsoids, %lld stalactites and %lld stalagmites, %s), %lld hierarchy "
         "nodes, %.2f MB, built in %.3f s (%.3f s of CPU; target <= 1 s; paper 67 k nodes, 7.4 MB, "
         "7.5 s)\n",
         name, (long long)ss.n_nodes, (long long)ss.by_kind[KARST_SDF_SWEEP],
         (long long)bst.n_morphs, (long long)bst.n_mitred_ends,
         (long long)ss.by_kind[KARST_SDF_REVOLVE], (long long)bst.n_bends,
         (long long)bst.n_joint_balls, (long long)bst.n_blends,
         (long long)ss.by_kind[KARST_SDF_ELLIPSOID], (long long)bst.n_stalactites,
         (long long)bst.n_stalagmites, bst.details_lipschitz > 0 ? "wall details" : "smooth walls",
         (long long)ss.n_bvh_nodes, ss.memory_bytes / 1e6, t1 - t0, c1 - c0);
  fflush(stdout);
  karst_mesh_t m;
  karst_mesh_init(&m);
  karst_polygonize_stats_t ps;
  double t2 = now_s(), c2 = cpu_s();
  err = karst_mesh_polygonize(ctx, sdf, box, voxel, &m, &ps);
  double t3 = now_s(), c3 = cpu_s();
  if (err) {
    fprintf(stderr, "bench_mesh: %s\n", ctx->errmsg);
    karst_sdf_free(sdf);
    return -1;
  }
  double grid = (double)(ps.cells[0] + 1) * (ps.cells[1] + 1) * (ps.cells[2] + 1);
  printf("bench_mesh: %s: polygonized at %g m over the whole extent (%lld x %lld x %lld cells) "
         "in %.2f s on %d threads (target <= 60 s; %.2f s of CPU): %lld triangles, %lld vertices, "
         "%.3g field "
         "evaluations (%.2f %% of the %.3g grid points), %lld of %lld blocks skipped, volume "
         "%.0f m3\n",
         name, voxel, (long long)ps.cells[0], (long long)ps.cells[1], (long long)ps.cells[2],
         t3 - t2, ctx->nthreads, c3 - c2, (long long)m.n_triangles, (long long)m.n_vertices,
         (double)ps.n_evals, 100.0 * ps.n_evals / grid, grid, (long long)ps.n_skipped,
         (long long)ps.n_blocks, karst_mesh_volume(&m));
  fflush(stdout);
  if (out && karst_mesh_write(ctx, out, &m)) fprintf(stderr, "bench_mesh: %s\n", ctx->errmsg);
  karst_mesh_destroy(&m);
  karst_sdf_free(sdf);
  return 0;
}

/* The looping-cave preset as the generator makes it (seed of the scenario). */
static int run_preset(karst_ctx_t *ctx, double voxel, int config) {
  const char *path = KARST_SOURCE_DIR "/datasets/scenarios/looping_cave.yaml";
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_network_t net;
  karst_network_init(&net);
  karst_generate_stats_t gs;
  int rc = -1;
  if (karst_scenario_load(ctx, path, &sc) ||
      karst_generate(ctx, &sc, sc.seed, 0, &net, NULL, &gs)) {
    fprintf(stderr, "bench_mesh: %s\n", ctx->errmsg);
    goto done;
  }
  printf("bench_mesh: looping-cave preset (%s, seed %llu): %lld nodes, %lld edges, %.1f km of "
         "conduits in %.1f x %.1f x %.1f km\n",
         path, (unsigned long long)sc.seed, (long long)net.n_nodes, (long long)net.n_edges,
         gs.total_length / 1000, (sc.domain_max[0] - sc.domain_min[0]) / 1000,
         (sc.domain_max[1] - sc.domain_min[1]) / 1000,
         (sc.domain_max[2] - sc.domain_min[2]) / 1000);
  double box[6] = {sc.domain_min[0], sc.domain_min[1], sc.domain_min[2],
                   sc.domain_max[0], sc.domain_max[1], sc.domain_max[2]};
  rc = 0;
  for (int walls = 0; walls < 2; walls++) {
    if (!(config & (1 << walls))) continue;
    karst_implicit_params_t par;
    karst_geometry_t g;
    params(&par, &g, walls, voxel);
    par.seed = sc.seed;
    par.fractures = sc.fractures;
    par.n_fractures = sc.n_fractures;
    rc |= run_case(ctx, walls ? "preset, walls" : "preset, plain", &net, box, voxel, &par, NULL);
  }
done:
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
  return rc;
}

/* A network of nodes P and edges E (pairs), radii r and types ty. */
static void scene_network(karst_network_t *net, const double (*P)[3], int n, const int (*E)[2],
                          int m, const double *r, const int *ty) {
  karst_network_init(net);
  for (int i = 0; i < n; i++)
    karst_network_add_node(net, P[i][0], P[i][1], P[i][2], NULL);
  double *rad, *typ;
  for (int e = 0; e < m; e++)
    karst_network_add_edge(net, E[e][0], E[e][1], NULL);
  karst_network_attr_add(net, KARST_ATTR_EDGE, "radius", 1, 0, &rad);
  karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &typ);
  for (int e = 0; e < m; e++)
    rad[e] = r[e], typ[e] = ty[e];
}

/* The close-ups of docs/geometry.md: a junction of passages (blended and
 * hard, smooth walls to show the flare), a canyon with flutes, a chamber
 * with speleothems. */
static int run_scenes(karst_ctx_t *ctx, const char *only, const char *outdir) {
  char path[1024];
  int rc = 0;
  if (!only || strcmp(only, "junction") == 0) {
    /* (coordinates off the grid's planes, where flat walls would lie on grid points) */
    const double P[4][3] = {
        {-12, 0.013, 0.017}, {0.011, 0.013, 0.017}, {12, -0.5, 0.6}, {7, 9, 1.5}};
    const int E[3][2] = {{0, 1}, {1, 2}, {1, 3}};
    const double r[3] = {2.0, 2.0, 1.4};
    const int ty[3] = {KARST_TUNNEL_PASSAGE, KARST_TUNNEL_PASSAGE, KARST_TUNNEL_TUBE};
    karst_network_t net;
    scene_network(&net, P, 4, E, 3, r, ty);
    const double box[6] = {-11, -4, -3, 11, 10.5, 4};
    for (int blend = 1; blend >= 0; blend--) {
      karst_implicit_params_t par;
      karst_geometry_t g;
      params(&par, &g, 1, 0.05);
      par.details = par.speleothems = 0;
      if (!blend) g.blend = 0;
      snprintf(path, sizeof path, "%s/junction_%s.ply", outdir ? outdir : ".",
               blend ? "blend" : "hard");
      rc |= run_case(ctx, blend ? "scene junction, blended" : "scene junction, hard union", &net,
                     box, 0.05, &par, outdir ? path : NULL);
    }
    karst_network_destroy(&net);
  }
  if (!only || strcmp(only, "canyon") == 0) {
    /* a straight canyon, slightly descending (the details of joints: docs/geometry.md) */
    const double P[2][3] = {{-13, 0.013, 0.417}, {13, 1.5, -0.6}};
    const int E[1][2] = {{0, 1}};
    const double r[1] = {2.0};
    const int ty[1] = {KARST_TUNNEL_CANYON};
    karst_network_t net;
    scene_network(&net, P, 2, E, 1, r, ty);
    const double box[6] = {-12, -3, -6, 12, 4.5, 6};
    karst_implicit_params_t par;
    karst_geometry_t g;
    params(&par, &g, 1, 0.04);
    snprintf(path, sizeof path, "%s/canyon.ply", outdir ? outdir : ".");
    rc |= run_case(ctx, "scene canyon with flutes", &net, box, 0.04, &par, outdir ? path : NULL);
    karst_network_destroy(&net);
  }
  if (!only || strcmp(only, "chamber") == 0) {
    const double P[4][3] = {{-22, 0.013, -1}, {-7, 0.013, 0.017}, {7, 1, 0.017}, {22, 3, -1}};
    const int E[3][2] = {{0, 1}, {1, 2}, {2, 3}};
    const double r[3] = {2.2, 6.0, 2.2};
    const int ty[3] = {KARST_TUNNEL_PASSAGE, KARST_TUNNEL_CHAMBER, KARST_TUNNEL_PASSAGE};
    karst_network_t net;
    scene_network(&net, P, 4, E, 3, r, ty);
    const double box[6] = {-20, -7, -5, 20, 8, 5};
    karst_implicit_params_t par;
    karst_geometry_t g;
    params(&par, &g, 1, 0.06);
    g.speleothems[KARST_TUNNEL_CHAMBER].density = 0.12;
    snprintf(path, sizeof path, "%s/chamber.ply", outdir ? outdir : ".");
    rc |= run_case(ctx, "scene chamber with speleothems", &net, box, 0.06, &par,
                   outdir ? path : NULL);
    karst_network_destroy(&net);
  }
  return rc;
}

int main(int argc, char **argv) {
  double voxel = argc > 1 ? atof(argv[1]) : 0.5;
  int threads = argc > 2 ? atoi(argv[2]) : 2;
  const char *which = argc > 3 ? argv[3] : "all";
  const char *cfg = argc > 4 ? argv[4] : "both";
  const char *outdir = argc > 5 ? argv[5] : NULL;
  int config = strcmp(cfg, "plain") == 0 ? 1 : strcmp(cfg, "walls") == 0 ? 2 : 3;
  const double lo[3] = {0, 0, 0}, hi[3] = {500, 700, 200};
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = threads > 0 ? threads : 1;
  karst_network_t net;
  karst_network_init(&net);
  double *dummy;
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &dummy);
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &dummy);
  karst_rng_t r;
  karst_rng_init(&r, 2021, 0);
  enum { K = 47 };
  for (int i = 0; i < K; i++) {
    double p[3];
    for (int a = 0; a < 3; a++)
      p[a] = karst_rng_uniform_range(&r, lo[a] + 20, hi[a] - 20);
    karst_network_add_node(&net, p[0], p[1], p[2], NULL);
  }
  /* join each key point to its nearest neighbours until 20 km of straight
   * connections (the displaced paths are a little longer) */
  static const int types[] = {KARST_TUNNEL_TUBE,     KARST_TUNNEL_KEYHOLE, KARST_TUNNEL_CANYON,
                              KARST_TUNNEL_BED,      KARST_TUNNEL_PASSAGE, KARST_TUNNEL_TUBE,
                              KARST_TUNNEL_EPIKARST, KARST_TUNNEL_CHAMBER};
  char joined[K][K];
  memset(joined, 0, sizeof joined);
  double straight = 0;
  int paths = 0;
  for (int k = 1; k < K && straight < 20000; k++) {
    for (int i = 0; i < K && straight < 20000; i++) {
      /* k-th nearest neighbour of i */
      double d[K];
      int idx[K];
      for (int j = 0; j < K; j++) {
        const double *a = net.xyz + 3 * i, *b = net.xyz + 3 * j;
        d[j] = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                    (a[2] - b[2]) * (a[2] - b[2]));
        idx[j] = j;
      }
      for (int x = 0; x < K; x++)
        for (int y = x + 1; y < K; y++)
          if (d[idx[y]] < d[idx[x]]) {
            int t = idx[x];
            idx[x] = idx[y];
            idx[y] = t;
          }
      int j = idx[k];
      if (joined[i][j]) continue;
      joined[i][j] = joined[j][i] = 1;
      int type = types[karst_rng_below(&r, 8)];
      if (type == KARST_TUNNEL_CHAMBER && d[j] > 60)
        type = KARST_TUNNEL_TUBE; /* chambers are short */
      double rad = type == KARST_TUNNEL_EPIKARST ? 0.5 : karst_rng_uniform_range(&r, 0.5, 4.0);
      if (type == KARST_TUNNEL_CHAMBER) {
        karst_int_t e;
        karst_network_add_edge(&net, i, j, &e);
        karst_network_attr_find(&net, KARST_ATTR_EDGE, "radius")->data[e] = 3 * rad;
        karst_network_attr_find(&net, KARST_ATTR_EDGE, "tunnel_type")->data[e] = type;
      } else if (path(&net, &r, i, j, 0.2, 8.0, lo, hi, 0, rad, type)) {
        fprintf(stderr, "bench_mesh: out of memory\n");
        return 1;
      }
      straight += d[j];
      paths++;
    }
  }
  double total = 0;
  for (karst_int_t e = 0; e < net.n_edges; e++)
    total += karst_network_edge_length(&net, e);
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  printf("bench_mesh: synthetic: looping-cave-sized network: %d key points, %d paths, %lld nodes, "
         "%lld edges, %.1f km of conduits in %.1f x %.1f x %.1f km (machine: %ld cores, %d "
         "threads used)\n",
         K, paths, (long long)net.n_nodes, (long long)net.n_edges, total / 1000, hi[0] / 1000,
         hi[1] / 1000, hi[2] / 1000, cores, ctx.nthreads);

  double box[6] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  int rc = 0;
  int all = strcmp(which, "all") == 0;
  if (all || strcmp(which, "synthetic") == 0)
    for (int walls = 0; walls < 2; walls++) {
      if (!(config & (1 << walls))) continue;
      karst_implicit_params_t par;
      karst_geometry_t g;
      params(&par, &g, walls, voxel);
      rc |= run_case(&ctx, walls ? "synthetic, walls" : "synthetic, plain", &net, box, voxel, &par,
                     NULL);
    }
  if (all || strcmp(which, "preset") == 0) rc |= run_preset(&ctx, voxel, config);
  if (all || strcmp(which, "scenes") == 0) rc |= run_scenes(&ctx, NULL, outdir);
  if (!strcmp(which, "junction") || !strcmp(which, "canyon") || !strcmp(which, "chamber"))
    rc |= run_scenes(&ctx, which, outdir);
  karst_network_destroy(&net);
  return rc ? 1 : 0;
}
