/**
 * @file ensemble.h
 * @brief Stochastic ensembles: N realisations of one scenario, each drawn only
 *        from random streams derived from (base seed, realisation index), run
 *        on a pthread work queue and, when started under Open MPI, across
 *        ranks. Every member is written to a temporary directory and renamed
 *        into place when complete, so an interrupted run loses nothing and a
 *        re-run computes only the missing members (docs/ensembles.md).
 *
 * Layout of an ensemble directory DIR:
 *   DIR/realisations/NNNN/network.vtp (+ whatever the write hook adds)
 *   DIR/realisations/NNNN/metrics.csv   one header line and one row
 *   DIR/realisations/ensemble.key       scenario hash and base seed (guards re-runs)
 *   DIR/ensemble.pvd, DIR/metrics.csv, DIR/ensemble.json (rebuilt at the end)
 *   DIR/.ensemble.lock                   only while a run works in DIR
 */
#ifndef KARST_ENSEMBLE_H
#define KARST_ENSEMBLE_H

#include <stdio.h>

#include "karst/common.h"
#include "karst/network.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * What the runner does for one member. Every hook receives a private context
 * (a copy of the caller's, one thread, no progress callback) and must draw
 * random numbers only from @p member_seed. Hooks may be called concurrently
 * from several threads with different members.
 */
typedef struct karst_ensemble_hooks {
  /** Build member @p index (seed karst_ensemble_member_seed(base, index)) into @p net. */
  karst_error_t (*realise)(karst_ctx_t *ctx, void *user, uint64_t member_seed, karst_int_t index,
                           karst_network_t *net);
  /** Write the member's files into the directory @p dir ("network.vtp" for the pipeline and
   *  its collection file; a runner that keeps only metrics, as karst calibrate does, writes
   *  none). */
  karst_error_t (*write)(karst_ctx_t *ctx, void *user, const char *dir, const karst_network_t *net);
  /** Fill values[0 .. n_metrics-1] (NAN when undefined). */
  karst_error_t (*measure)(karst_ctx_t *ctx, void *user, const karst_network_t *net,
                           double *values);
  /** Write the collection file @p path listing @p n member files (relative paths). */
  karst_error_t (*write_collection)(karst_ctx_t *ctx, void *user, const char *path, int n,
                                    const char *const *files);
  int n_metrics;
  const char *const *metric_names; /**< CSV column names of the measured values */
  void *user;
} karst_ensemble_hooks_t;

/** Most members an ensemble may have: -n beyond this is refused before anything is created
 *  (member directories are at least 4 digits; 1e8 members is far beyond any real study). */
#define KARST_ENSEMBLE_MAX_MEMBERS 100000000
/** Most worker threads per process: -j beyond this is refused (a guard against typos such as
 *  -j 20000, which would try to start that many threads). */
#define KARST_ENSEMBLE_MAX_THREADS 1024

/** The lock file of a running ensemble, DIR/.ensemble.lock: held with an exclusive flock(2)
 *  while karst_ensemble_run works in DIR (a second run into DIR fails with KARST_EBUSY) and
 *  removed when the run ends. */
#define KARST_ENSEMBLE_LOCK_NAME ".ensemble.lock"
/** The run log of an ensemble, DIR/ensemble_log.json: wall time, members computed and reused,
 *  threads and ranks of the last run. Everything else (ensemble.json, metrics.csv, the members)
 *  is reproducible: byte-identical whether the run was resumed or not. */
#define KARST_ENSEMBLE_LOG_NAME "ensemble_log.json"
/** The lock file `karst generate` holds in its output directory while it writes it (the same
 *  kind of lock as KARST_ENSEMBLE_LOCK_NAME: a second generate into DIR fails with KARST_EBUSY). */
#define KARST_GENERATE_LOCK_NAME ".generate.lock"

/** A held directory lock (karst_dir_lock); fd -1 when none. */
typedef struct karst_dir_lock {
  int fd;
  char *path;
} karst_dir_lock_t;
/**
 * Take the exclusive, non-blocking flock(2) of DIR/@p name (created, holding this process's
 * id), the lock of karst_ensemble_run; KARST_EBUSY, with a message naming DIR, the other
 * "karst @p what" and its pid, when another process holds it. Released (and unlinked) by
 * karst_dir_unlock, or when the process dies. O(1).
 */
karst_error_t karst_dir_lock(karst_ctx_t *ctx, const char *dir, const char *name, const char *what,
                             karst_dir_lock_t *lock);
/** Release a lock taken by karst_dir_lock (unlinks its file); a lock with fd -1 is left. */
void karst_dir_unlock(karst_dir_lock_t *lock);

/** How to run an ensemble. */
typedef struct karst_ensemble_options {
  karst_int_t n;               /**< members, 1 to KARST_ENSEMBLE_MAX_MEMBERS */
  uint64_t seed;               /**< base seed */
  int nthreads;                /**< threads, 1 to KARST_ENSEMBLE_MAX_THREADS (default 1) */
  int use_mpi;                 /**< 1: split across MPI ranks when MPI is initialised (default 1) */
  const char *scenario_path;   /**< recorded in ensemble.json (may be NULL) */
  const char *scenario_hash;   /**< 16 hex digits (karst_file_hash), guards re-runs (may be NULL) */
  const char *parameters_json; /**< body of the "parameters" object, one `"key": value` per line
                                    (karst_ensemble_parameters_json), or NULL */
} karst_ensemble_options_t;

/** What a run did. */
typedef struct karst_ensemble_summary {
  karst_int_t n;        /**< members in the ensemble */
  karst_int_t computed; /**< members computed by this process in this run */
  karst_int_t reused;   /**< members found complete from an earlier run */
  karst_int_t complete; /**< members complete at the end (all ranks) */
  double wall_seconds;  /**< wall time of this run */
  int ranks, rank;      /**< MPI world (1, 0 without MPI) */
} karst_ensemble_summary_t;

/** Defaults: n = 1, seed = 1, one thread, MPI when available, no scenario. */
void karst_ensemble_options_init(karst_ensemble_options_t *opt);

/** The seed of member @p index: the first output of karst_rng stream (@p seed, @p index). */
uint64_t karst_ensemble_member_seed(uint64_t seed, karst_int_t index);

/** Run (or complete) the ensemble in @p dir; see the file comment and docs/ensembles.md. */
karst_error_t karst_ensemble_run(karst_ctx_t *ctx, const char *dir,
                                 const karst_ensemble_options_t *opt,
                                 const karst_ensemble_hooks_t *hooks,
                                 karst_ensemble_summary_t *summary);

/** Most metric columns the pipeline hooks carry. */
#define KARST_ENSEMBLE_MAX_METRICS 64

/** Storage behind karst_ensemble_hooks_pipeline (caller-owned; must outlive the run). */
typedef struct karst_ensemble_pipeline {
  const karst_scenario_t *sc;
  const char *names[KARST_ENSEMBLE_MAX_METRICS];
} karst_ensemble_pipeline_t;

/**
 * The real pipeline as hooks: karst_generate on @p sc (member seed,
 * realisation 0), karst_vtk_write_network + karst_write_karstnet
 * (network.vtp, network_nodes.dat, network_links.dat), karst_metrics_compute
 * with the columns of karst_metric_fields, karst_vtk_write_pvd.
 */
karst_error_t karst_ensemble_hooks_pipeline(karst_ctx_t *ctx, karst_ensemble_hooks_t *hooks,
                                            karst_ensemble_pipeline_t *storage,
                                            const karst_scenario_t *sc);

/**
 * The effective parameters of @p sc as the body of a flat JSON object, one
 * `"key": value` per line (dotted keys, e.g. "sampling.k"). Caller frees.
 */
char *karst_ensemble_parameters_json(const karst_scenario_t *sc);

/**
 * The number of processes a launcher says it started: OMPI_COMM_WORLD_SIZE
 * (Open MPI's mpirun) or else PMI_SIZE (MPICH's Hydra, Slurm's PMI); 1 when
 * neither is set to a whole number >= 1. Reads only the environment.
 */
int karst_ensemble_launcher_size(void);

/**
 * MPI: when this process was started by mpirun (env OMPI_COMM_WORLD_SIZE or
 * PMI_SIZE) and the library was built with MPI, initialise MPI if needed and
 * return the world size in @p ranks and this rank in @p rank; otherwise 1 and 0.
 * @p initialised receives 1 when this call initialised MPI.
 * A library built without MPI returns KARST_EUNSUPPORTED when a launcher
 * started more than one process (karst_ensemble_launcher_size() > 1): each
 * would compute every member and they would race on the files.
 */
karst_error_t karst_ensemble_mpi_start(karst_ctx_t *ctx, int *ranks, int *rank, int *initialised);
/** Finalise MPI when @p initialised (from karst_ensemble_mpi_start) is non-zero. */
void karst_ensemble_mpi_finish(int initialised);

/** A metrics table read from an ensemble's metrics.csv: index, seed, then named columns. */
typedef struct karst_ensemble_table {
  karst_int_t n_rows;
  int n_cols;         /**< metric columns (index and seed excluded) */
  char **names;       /**< n_cols column names */
  karst_int_t *index; /**< n_rows member indices */
  uint64_t *seed;     /**< n_rows member seeds */
  double *values;     /**< n_rows * n_cols, row-major; NAN where the cell is empty */
} karst_ensemble_table_t;

void karst_ensemble_table_init(karst_ensemble_table_t *t);
void karst_ensemble_table_destroy(karst_ensemble_table_t *t);
/** Read DIR/metrics.csv (or any file in that format); errors name FILE:LINE. */
karst_error_t karst_ensemble_table_read(karst_ctx_t *ctx, const char *path,
                                        karst_ensemble_table_t *t);
/** Column of @p name, or -1. */
int karst_ensemble_table_column(const karst_ensemble_table_t *t, const char *name);

#ifdef __cplusplus
}
#endif
#endif
