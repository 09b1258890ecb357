/*
 * The ensemble runner (include/karst/ensemble.h, docs/ensembles.md).
 *
 * Why it is built this way:
 *  - Member i depends only on (base seed, i): its seed is the first output of
 *    the stream (seed, i) and every draw of the pipeline comes from that seed,
 *    so the files are the same whatever the thread or rank count.
 *  - A member is written into a hidden temporary directory and renamed onto
 *    DIR/realisations/NNNN when complete; rename(2) of a directory is atomic,
 *    so "the final directory exists" is the one definition of "done". An
 *    interrupted or killed run leaves only hidden temporaries, removed by the
 *    next run, which then computes the missing members only.
 *  - The collection files (metrics.csv, ensemble.pvd, ensemble.json) are
 *    rebuilt from the member files at the end, never appended to, so a resumed
 *    run ends with exactly the bytes of an uninterrupted one.
 */
#include "karst/ensemble.h"

#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ensemble/ensemble_internal.h"
#include "io/input_internal.h"
#include "karst/io.h"
#include "karst/version.h"

#include "ensemble/mpi_api_internal.h"

void karst_ensemble_options_init(karst_ensemble_options_t *opt) {
  memset(opt, 0, sizeof *opt);
  opt->n = 1;
  opt->seed = 1;
  opt->nthreads = 1;
  opt->use_mpi = 1;
}

/**
 * Seed of member @p index of an ensemble with base seed @p seed.
 * @return the first 64-bit output of the karst_rng stream (seed, index); the
 *         member is then generated from this seed alone (realisation 0), so
 *         `karst generate --seed <member seed>` reproduces it.
 * Time complexity: O(1).
 */
uint64_t karst_ensemble_member_seed(uint64_t seed, karst_int_t index) {
  karst_rng_t r;
  karst_rng_init(&r, seed, (uint64_t)index);
  return karst_rng_u64(&r);
}

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

char *karst_i_path_join(const char *a, const char *b) {
  size_t n = strlen(a) + strlen(b) + 2;
  char *p = malloc(n);
  if (p) snprintf(p, n, "%s/%s", a, b);
  return p;
}

void karst_i_member_name(char out[32], karst_int_t index) {
  snprintf(out, 32, "%04" PRId64, index);
}

static int is_dir(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* Remove a file or a directory tree (members hold files only; depth is small). */
static int remove_tree(const char *path) {
  struct stat st;
  if (lstat(path, &st) != 0) return errno == ENOENT ? 0 : -1;
  if (!S_ISDIR(st.st_mode)) return remove(path);
  DIR *d = opendir(path);
  if (!d) return -1;
  int rc = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
    char *sub = karst_i_path_join(path, e->d_name);
    if (!sub || remove_tree(sub) != 0) rc = -1;
    free(sub);
  }
  closedir(d);
  if (rmdir(path) != 0) rc = -1;
  return rc;
}

/* Leftovers of an interrupted or killed run: hidden names containing ".tmp." (the
 * pattern of karst_temp_name and of member temporaries). */
static karst_error_t remove_stale_temporaries(karst_ctx_t *ctx, const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return KARST_SUCCESS;
  karst_error_t err = KARST_SUCCESS;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (e->d_name[0] != '.' || !strstr(e->d_name, ".tmp.")) continue;
    char *p = karst_i_path_join(dir, e->d_name);
    if (!p) {
      err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", dir);
      break;
    }
    if (remove_tree(p) != 0) {
      err = karst_set_error(ctx, KARST_EIO, "%s: cannot remove the leftover of an earlier run: %s",
                            p, strerror(errno));
      free(p);
      break;
    }
    karst_log(ctx, KARST_LOG_INFO, "removed %s, left by an interrupted run", p);
    free(p);
  }
  closedir(d);
  return err;
}

/* ------------------------------------------------------------------------ */
/* The lock: one run at a time in DIR.                                      */
/* ------------------------------------------------------------------------ */
/* Take the exclusive, non-blocking flock(2) of DIR/.ensemble.lock and write this process's id
 * into it. The lock file is unlinked when the run ends (release_lock), so a finished ensemble
 * holds exactly the files of an uninterrupted run. Because of that unlink, a process may win
 * the lock on a file that another process has just unlinked; it then checks that the name
 * still refers to the inode it locked and tries again otherwise (the usual pattern for
 * removable lock files). A lock dies with its process, so kill -9 never leaves DIR locked. */
static karst_error_t take_lock_named(karst_ctx_t *ctx, const char *dir, const char *name,
                                     const char *what, int *fd_out, char **path_out) {
  char *path = karst_i_path_join(dir, name);
  *fd_out = -1;
  *path_out = NULL;
  if (!path) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  for (int attempt = 0; attempt < 100; attempt++) {
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) {
      karst_error_t err = karst_set_error(ctx, KARST_EIO, "%s: cannot create the lock file: %s",
                                          path, strerror(errno));
      free(path);
      return err;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      int e = errno;
      char pid[32] = "";
      ssize_t got = e == EWOULDBLOCK ? pread(fd, pid, sizeof pid - 1, 0) : -1;
      close(fd);
      karst_error_t err;
      if (e == EWOULDBLOCK) {
        pid[got > 0 ? got : 0] = '\0';
        pid[strspn(pid, "0123456789")] = '\0';
        err = karst_set_error(ctx, KARST_EBUSY,
                              "%s is in use by another karst %s (pid %s; lock %s); wait "
                              "for it to finish or use another output directory",
                              dir, what, pid[0] ? pid : "unknown", path);
      } else {
        err = karst_set_error(ctx, KARST_EIO, "%s: cannot lock: %s", path, strerror(e));
      }
      free(path);
      return err;
    }
    struct stat held, named;
    if (fstat(fd, &held) == 0 && stat(path, &named) == 0 && held.st_dev == named.st_dev &&
        held.st_ino == named.st_ino) {
      char pid[32];
      int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
      if (ftruncate(fd, 0) != 0 || pwrite(fd, pid, (size_t)len, 0) != len) {
        /* the pid is only for the message of a refused run; the lock itself holds */
      }
      *fd_out = fd;
      *path_out = path;
      return KARST_SUCCESS;
    }
    close(fd); /* locked a file that was unlinked meanwhile: try the new one */
  }
  free(path);
  return karst_set_error(ctx, KARST_EBUSY, "%s: cannot take the lock %s (it keeps changing)", dir,
                         name);
}

static karst_error_t take_lock(karst_ctx_t *ctx, const char *dir, int *fd_out, char **path_out) {
  return take_lock_named(ctx, dir, KARST_ENSEMBLE_LOCK_NAME, "ensemble", fd_out, path_out);
}

/* Unlink while still holding the lock, then close (which releases it). */
static void release_lock(int fd, char *path) {
  if (fd >= 0) {
    unlink(path);
    close(fd);
  }
  free(path);
}

karst_error_t karst_dir_lock(karst_ctx_t *ctx, const char *dir, const char *name, const char *what,
                             karst_dir_lock_t *lock) {
  return take_lock_named(ctx, dir, name, what, &lock->fd, &lock->path);
}

void karst_dir_unlock(karst_dir_lock_t *lock) {
  release_lock(lock->fd, lock->path);
  lock->fd = -1;
  lock->path = NULL;
}

/* ------------------------------------------------------------------------ */
/* The key file: a re-run into DIR must be the same scenario and seed.      */
/* ------------------------------------------------------------------------ */
/** Longest key file read back (a key is a few lines). */
#define KEY_FILE_MAX 4096

/**
 * A directory's key file (ensemble_internal.h): @p path must hold exactly @p want, or is
 * created with it (atomically). Time complexity: O(size of the key).
 */
karst_error_t karst_i_key_file(karst_ctx_t *ctx, const char *path, const char *want,
                               const char *holds, const char *advice) {
  karst_error_t err = KARST_SUCCESS;
  char *have = NULL;
  FILE *fp = NULL;
  struct stat kst; /* absent: created below; present: read through the guarded opening */
  if (stat(path, &kst) == 0 && (err = karst_i_open_regular(ctx, path, "key", KEY_FILE_MAX, &fp)))
    return err;
  if (fp) {
    have = malloc(KEY_FILE_MAX);
    if (!have) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    size_t got = fread(have, 1, KEY_FILE_MAX - 1, fp);
    have[got] = '\0';
    if (strcmp(have, want) != 0) {
      for (char *c = have; *c; c++)
        if (*c == '\n' || *c == '\r') *c = ' ';
      err = karst_set_error(ctx, KARST_EINVAL,
                            "%s: this directory holds %s (key: %.1500s); use another output "
                            "directory or %s",
                            path, holds, have, advice);
    }
    goto cleanup;
  }
  karst_atomic_file_t f;
  err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) goto cleanup;
  fputs(want, f.fp);
  err = karst_atomic_commit(ctx, &f);
cleanup:
  if (fp) fclose(fp);
  free(have);
  return err;
}

static karst_error_t check_or_write_key(karst_ctx_t *ctx, const char *real_dir,
                                        const karst_ensemble_options_t *opt) {
  char *path = karst_i_path_join(real_dir, "ensemble.key");
  char want[256];
  if (!path) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  snprintf(want, sizeof want, "karst ensemble key 1\nscenario_hash %s\nseed %" PRIu64 "\n",
           opt->scenario_hash ? opt->scenario_hash : "none", opt->seed);
  karst_error_t err = karst_i_key_file(ctx, path, want, "an ensemble of another scenario or seed",
                                       "the same scenario and seed");
  free(path);
  return err;
}

/* ------------------------------------------------------------------------ */
/* One member                                                               */
/* ------------------------------------------------------------------------ */
karst_error_t karst_i_metrics_header(karst_ctx_t *ctx, const karst_ensemble_hooks_t *h,
                                     char **out) {
  size_t n = 32;
  for (int k = 0; k < h->n_metrics; k++)
    n += strlen(h->metric_names[k]) + 1;
  char *s = malloc(n);
  if (!s) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  strcpy(s, "index,seed");
  for (int k = 0; k < h->n_metrics; k++) {
    strcat(s, ",");
    strcat(s, h->metric_names[k]);
  }
  *out = s;
  return KARST_SUCCESS;
}

/* One CSV row with a fixed float format (%.17g round-trips every double; an
 * undefined value is an empty cell). */
static void write_row(FILE *fp, karst_int_t index, uint64_t seed, int n, const double *v) {
  fprintf(fp, "%" PRId64 ",%" PRIu64, index, seed);
  for (int k = 0; k < n; k++) {
    if (isnan(v[k]))
      fputc(',', fp);
    else
      fprintf(fp, ",%.17g", v[k]);
  }
  fputc('\n', fp);
}

typedef struct run_state {
  const char *real_dir;
  const karst_ensemble_options_t *opt;
  const karst_ensemble_hooks_t *hooks;
  const char *header;
  const karst_ctx_t *parent;
  /* the work queue */
  const karst_int_t *pending;
  karst_int_t n_pending, next, done;
  int stop, active;
  karst_error_t err; /* error of the lowest failing member */
  karst_int_t err_index;
  char errmsg[KARST_ERRMSG_MAX];
  pthread_mutex_t lock;
  pthread_cond_t changed;
} run_state_t;

static karst_error_t run_member(karst_ctx_t *ctx, run_state_t *rs, karst_int_t index) {
  const karst_ensemble_hooks_t *h = rs->hooks;
  karst_error_t err = KARST_SUCCESS;
  karst_network_t net;
  char name[32], tmpname[96];
  char *final_dir = NULL, *tmp_dir = NULL, *mpath = NULL;
  double *values = NULL;
  int made_tmp = 0;
  karst_network_init(&net);
  karst_i_member_name(name, index);
  snprintf(tmpname, sizeof tmpname, ".%s.tmp.%ld", name, (long)getpid());
  final_dir = karst_i_path_join(rs->real_dir, name);
  tmp_dir = karst_i_path_join(rs->real_dir, tmpname);
  values = calloc((size_t)(h->n_metrics > 0 ? h->n_metrics : 1), sizeof *values);
  if (!final_dir || !tmp_dir || !values) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  mpath = karst_i_path_join(tmp_dir, "metrics.csv");
  if (!mpath) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  remove_tree(tmp_dir);
  if (mkdir(tmp_dir, 0777) != 0) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot create directory: %s", tmp_dir,
                          strerror(errno));
    goto cleanup;
  }
  made_tmp = 1;
  uint64_t mseed = karst_ensemble_member_seed(rs->opt->seed, index);
  err = h->realise(ctx, h->user, mseed, index, &net);
  if (err) goto cleanup;
  err = h->write(ctx, h->user, tmp_dir, &net);
  if (err) goto cleanup;
  for (int k = 0; k < h->n_metrics; k++)
    values[k] = NAN;
  if (h->measure) {
    err = h->measure(ctx, h->user, &net, values);
    if (err) goto cleanup;
  }
  {
    karst_atomic_file_t f;
    err = karst_atomic_open(ctx, &f, mpath, "wb");
    if (err) goto cleanup;
    fprintf(f.fp, "%s\n", rs->header);
    write_row(f.fp, index, mseed, h->n_metrics, values);
    err = karst_atomic_commit(ctx, &f);
    if (err) goto cleanup;
  }
  if (rename(tmp_dir, final_dir) != 0) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot rename the finished member into place: %s",
                          final_dir, strerror(errno));
    goto cleanup;
  }
  made_tmp = 0;
cleanup:
  if (made_tmp) remove_tree(tmp_dir);
  karst_network_destroy(&net);
  free(values);
  free(mpath);
  free(tmp_dir);
  free(final_dir);
  return err;
}

static void *worker(void *arg) {
  run_state_t *rs = arg;
  karst_ctx_t ctx = *rs->parent; /* each worker has its own context (error message) */
  ctx.nthreads = 1;
  ctx.progress = NULL;
  ctx.errcode = KARST_SUCCESS;
  ctx.errmsg[0] = '\0';
  for (;;) {
    pthread_mutex_lock(&rs->lock);
    if (!rs->stop && karst_interrupted(&ctx)) {
      rs->stop = 1;
      if (!rs->err) {
        rs->err = KARST_EINTERRUPTED;
        rs->err_index = -1;
        snprintf(rs->errmsg, sizeof rs->errmsg, "interrupted");
      }
    }
    if (rs->stop || rs->next >= rs->n_pending) {
      rs->active--;
      pthread_cond_broadcast(&rs->changed);
      pthread_mutex_unlock(&rs->lock);
      break;
    }
    karst_int_t index = rs->pending[rs->next++];
    pthread_mutex_unlock(&rs->lock);

    ctx.errcode = KARST_SUCCESS;
    ctx.errmsg[0] = '\0';
    karst_error_t err = run_member(&ctx, rs, index);

    pthread_mutex_lock(&rs->lock);
    if (err) {
      rs->stop = 1;
      /* Deterministic report: a real failure beats an interruption, then the lowest index. */
      int better =
          !rs->err || (rs->err == KARST_EINTERRUPTED && err != KARST_EINTERRUPTED) ||
          ((rs->err == KARST_EINTERRUPTED) == (err == KARST_EINTERRUPTED) && index < rs->err_index);
      if (better) {
        rs->err = err;
        rs->err_index = index;
        snprintf(rs->errmsg, sizeof rs->errmsg, "realisation %" PRId64 ": %.1990s", index,
                 ctx.errmsg[0] ? ctx.errmsg : karst_strerror(err));
      }
    } else {
      rs->done++;
    }
    pthread_cond_broadcast(&rs->changed);
    pthread_mutex_unlock(&rs->lock);
  }
  return NULL;
}

/* Run the pending members on a pthread work queue; the calling thread reports progress. */
static karst_error_t run_queue(karst_ctx_t *ctx, run_state_t *rs, int nthreads) {
  karst_error_t err = KARST_SUCCESS;
  pthread_t *th = NULL;
  int started = 0;
  if (rs->n_pending == 0) return KARST_SUCCESS;
  if (nthreads > rs->n_pending) nthreads = (int)rs->n_pending;
  th = calloc((size_t)nthreads, sizeof *th);
  if (!th) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  /* A first report before any work, so a display can start its clock and rate. */
  karst_progress(ctx, "ensemble", 0.0, (double)rs->n_pending);
  pthread_mutex_init(&rs->lock, NULL);
  pthread_cond_init(&rs->changed, NULL);
  rs->active = nthreads;
  for (; started < nthreads; started++) {
    if (pthread_create(&th[started], NULL, worker, rs) != 0) break;
  }
  pthread_mutex_lock(&rs->lock);
  rs->active -= nthreads - started; /* threads that could not be started */
  if (started == 0) {
    pthread_mutex_unlock(&rs->lock);
    err = karst_set_error(ctx, KARST_EINVAL, "cannot start a worker thread");
    goto cleanup;
  }
  karst_int_t reported = 0;
  for (;;) {
    karst_int_t done = rs->done;
    int active = rs->active;
    if (done != reported) {
      reported = done;
      pthread_mutex_unlock(&rs->lock);
      karst_progress(ctx, "ensemble", (double)done, (double)rs->n_pending);
      pthread_mutex_lock(&rs->lock);
      continue;
    }
    if (active == 0) break;
    /* Wake up now and then even without news so an interrupt is noticed quickly. */
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    ts.tv_nsec += 200000000L;
    if (ts.tv_nsec >= 1000000000L) {
      ts.tv_sec++;
      ts.tv_nsec -= 1000000000L;
    }
    pthread_cond_timedwait(&rs->changed, &rs->lock, &ts);
  }
  pthread_mutex_unlock(&rs->lock);
  for (int t = 0; t < started; t++)
    pthread_join(th[t], NULL);
  if (rs->err) {
    err = karst_set_error(ctx, rs->err, "%s", rs->errmsg);
  }
cleanup:
  pthread_cond_destroy(&rs->changed);
  pthread_mutex_destroy(&rs->lock);
  free(th);
  return err;
}

/* ------------------------------------------------------------------------ */
/* MPI                                                                      */
/* ------------------------------------------------------------------------ */
/* MPI's calls come from a plugin opened on first use (mpi_api_internal.h): by
 * karst_ensemble_mpi_start under a launcher, or here when the process already holds MPI (a
 * program embedding libkarst that initialised it itself). */
static int mpi_world(int use_mpi, int *rank) {
  *rank = 0;
#if KARST_HAVE_MPI
  if (!use_mpi) return 1;
  const karst_i_mpi_api_t *m = karst_i_mpi_loaded();
  if (!m) {
    void *self = dlopen(NULL, RTLD_NOW); /* the global scope: is MPI in the process already? */
    if (self && dlsym(self, "MPI_Initialized")) m = karst_i_mpi_load(NULL, 0);
    if (self) dlclose(self);
  }
  if (!m) return 1;
  int init = 0, fin = 0;
  m->initialized(&init);
  m->finalized(&fin);
  if (init && !fin) {
    int size = 1;
    m->size(&size);
    m->rank(rank);
    return size;
  }
#else
  (void)use_mpi;
#endif
  return 1;
}

/* All ranks agree on the worst error code (max); without MPI the local one. */
static karst_error_t mpi_agree(int ranks, karst_error_t local) {
#if KARST_HAVE_MPI
  const karst_i_mpi_api_t *m = karst_i_mpi_loaded(); /* ranks > 1 came from it */
  if (ranks > 1 && m) {
    int out = 0;
    m->max_int((int)local, &out);
    return (karst_error_t)out;
  }
#else
  (void)ranks;
#endif
  return local;
}

static karst_int_t mpi_sum(int ranks, karst_int_t local) {
#if KARST_HAVE_MPI
  const karst_i_mpi_api_t *m = karst_i_mpi_loaded();
  if (ranks > 1 && m) {
    long long out = 0;
    m->sum_long_long((long long)local, &out);
    return (karst_int_t)out;
  }
#else
  (void)ranks;
#endif
  return local;
}

/* ------------------------------------------------------------------------ */
/* Collection files                                                         */
/* ------------------------------------------------------------------------ */

/* Read the data row of a member's metrics.csv (after checking its header). */
static karst_error_t read_member_row(karst_ctx_t *ctx, const char *path, const char *header,
                                     char **row) {
  karst_error_t err = KARST_SUCCESS;
  char *buf = NULL;
  size_t cap = 0;
  FILE *fp;
  *row = NULL;
  if ((err = karst_i_open_regular(ctx, path, "metrics", KARST_TABLE_MAX_BYTES, &fp))) return err;
  ssize_t len = getline(&buf, &cap, fp);
  if (len <= 0 || buf[len - 1] != '\n' || (buf[len - 1] = '\0', strcmp(buf, header) != 0)) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:1: the header does not match this ensemble's metrics (\"%s\"); "
                          "remove the member to recompute it",
                          path, header);
    goto cleanup;
  }
  len = getline(&buf, &cap, fp);
  if (len <= 1 || buf[len - 1] != '\n') {
    err = karst_set_error(ctx, KARST_EPARSE, "%s:2: missing or unterminated data row", path);
    goto cleanup;
  }
  *row = buf;
  buf = NULL;
cleanup:
  free(buf);
  fclose(fp);
  return err;
}

static karst_error_t write_collection_files(karst_ctx_t *ctx, const char *dir,
                                            const karst_ensemble_options_t *opt,
                                            const karst_ensemble_hooks_t *h, const char *header,
                                            const karst_ensemble_summary_t *sum, int nthreads) {
  karst_error_t err = KARST_SUCCESS;
  karst_atomic_file_t f = {0};
  char *path = NULL, *mpath = NULL, *row = NULL, *versions = NULL;
  char **files = NULL;
  karst_int_t n = opt->n;

  /* metrics.csv: member rows copied verbatim in index order. */
  path = karst_i_path_join(dir, "metrics.csv");
  files = calloc((size_t)n, sizeof *files);
  if (!path || !files) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) goto cleanup;
  fprintf(f.fp, "%s\n", header);
  for (karst_int_t i = 0; i < n; i++) {
    char name[32], rel[96];
    karst_i_member_name(name, i);
    snprintf(rel, sizeof rel, "realisations/%s/metrics.csv", name);
    free(mpath);
    mpath = karst_i_path_join(dir, rel);
    snprintf(rel, sizeof rel, "realisations/%s/network.vtp", name);
    files[i] = strdup(rel);
    if (!mpath || !files[i]) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    free(row);
    err = read_member_row(ctx, mpath, header, &row);
    if (err) goto cleanup;
    fputs(row, f.fp);
  }
  err = karst_atomic_commit(ctx, &f);
  if (err) goto cleanup;

  /* ensemble.pvd */
  if (h->write_collection) {
    free(path);
    path = karst_i_path_join(dir, "ensemble.pvd");
    if (!path) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    err = h->write_collection(ctx, h->user, path, (int)n, (const char *const *)files);
    if (err) goto cleanup;
  }

  /* ensemble.json (karst report reads it with the JSON reader of json.h). */
  free(path);
  path = karst_i_path_join(dir, "ensemble.json");
  if (!path) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  if (!(versions = karst_versions_json())) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) goto cleanup;
  fprintf(f.fp, "{\n  \"karst_version\": ");
  karst_json_string(f.fp, karst_version());
  fprintf(f.fp, ",\n  \"versions\": %s", versions);
  fprintf(f.fp, ",\n  \"scenario\": ");
  if (opt->scenario_path)
    karst_json_string(f.fp, opt->scenario_path);
  else
    fputs("null", f.fp);
  fprintf(f.fp, ",\n  \"scenario_hash\": ");
  if (opt->scenario_hash)
    karst_json_string(f.fp, opt->scenario_hash);
  else
    fputs("null", f.fp);
  fprintf(f.fp, ",\n  \"seed\": %" PRIu64 ",\n  \"realisations\": %" PRId64 ",\n", opt->seed, n);
  fprintf(f.fp, "  \"member_seed\": \"first output of the karst_rng stream (seed, index)\",\n");
  fprintf(f.fp, "  \"metrics\": [");
  for (int k = 0; k < h->n_metrics; k++) {
    if (k) fputs(", ", f.fp);
    karst_json_string(f.fp, h->metric_names[k]);
  }
  fprintf(f.fp, "],\n  \"parameters\": {\n");
  if (opt->parameters_json) fputs(opt->parameters_json, f.fp);
  fprintf(f.fp, "  }\n}\n");
  err = karst_atomic_commit(ctx, &f);
  if (err) goto cleanup;

  /* The run log, apart from what is reproducible: a resumed ensemble's ensemble.json is
   * byte-identical to an uninterrupted one's, its ensemble_log.json is not. */
  free(path);
  path = karst_i_path_join(dir, KARST_ENSEMBLE_LOG_NAME);
  if (!path) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) goto cleanup;
  fprintf(f.fp,
          "{\n  \"wall_seconds\": %.3f,\n  \"computed\": %" PRId64 ",\n  \"reused\": %" PRId64
          ",\n  \"threads\": %d,\n  \"ranks\": %d\n}\n",
          sum->wall_seconds, sum->complete - sum->reused, sum->reused, nthreads, sum->ranks);
  err = karst_atomic_commit(ctx, &f);
  if (err) goto cleanup;

cleanup:
  if (f.fp) karst_atomic_abort(&f);
  if (files)
    for (karst_int_t i = 0; i < n; i++)
      free(files[i]);
  free(files);
  free(row);
  free(mpath);
  free(path);
  free(versions);
  return err;
}

static karst_error_t check_arguments(karst_ctx_t *ctx, const char *dir,
                                     const karst_ensemble_options_t *opt,
                                     const karst_ensemble_hooks_t *h) {
  if (!dir || !*dir) return karst_set_error(ctx, KARST_EINVAL, "no output directory given");
  if (opt->n < 1 || opt->n > KARST_ENSEMBLE_MAX_MEMBERS)
    return karst_set_error(ctx, KARST_ERANGE,
                           "the number of realisations must be within [1, %d], got %" PRId64,
                           KARST_ENSEMBLE_MAX_MEMBERS, opt->n);
  if (opt->nthreads < 1 || opt->nthreads > KARST_ENSEMBLE_MAX_THREADS)
    return karst_set_error(ctx, KARST_ERANGE,
                           "the number of threads must be within [1, %d], got %d",
                           KARST_ENSEMBLE_MAX_THREADS, opt->nthreads);
  if (!h || !h->realise || !h->write)
    return karst_set_error(ctx, KARST_EINVAL, "the ensemble needs realise and write hooks");
  if (h->n_metrics < 0 || (h->n_metrics > 0 && !h->metric_names))
    return karst_set_error(ctx, KARST_EINVAL, "invalid metric list (%d names)", h->n_metrics);
  for (int k = 0; k < h->n_metrics; k++) {
    const char *s = h->metric_names[k];
    if (!s || !*s || strpbrk(s, ",\"\n\r"))
      return karst_set_error(ctx, KARST_EINVAL,
                             "metric name %d (\"%s\") must be non-empty without commas, quotes "
                             "or line breaks",
                             k, s ? s : "");
  }
  return KARST_SUCCESS;
}

/**
 * Run, or complete, an ensemble in @p dir.
 *
 * @param ctx      context; ctx->interrupt stops the run cleanly, ctx->progress
 *                 receives ("ensemble", members done, members to compute).
 * @param dir      output directory (created).
 * @param opt      number of members, base seed, threads, what ensemble.json records.
 * @param hooks    what a member is (karst_ensemble_hooks_pipeline for the real pipeline).
 * @param summary  what happened (may be NULL).
 * @return KARST_SUCCESS when every member is complete and the collection files
 *         are written; KARST_EINTERRUPTED after an interrupt (finished members
 *         are kept, unfinished ones leave nothing behind); the error of the
 *         lowest failing member otherwise ("realisation I: ..."); KARST_EBUSY,
 *         before anything in DIR is touched, when another run holds DIR's lock
 *         (KARST_ENSEMBLE_LOCK_NAME).
 * Members whose directory DIR/realisations/NNNN exists are not recomputed.
 * Under MPI (karst_ensemble_mpi_start) rank r computes the members i with
 * i mod P = r and rank 0 writes the collection files after all ranks agree.
 * Time complexity: N member costs / (threads x ranks), plus O(N) for the files.
 */
karst_error_t karst_ensemble_run(karst_ctx_t *ctx, const char *dir,
                                 const karst_ensemble_options_t *opt,
                                 const karst_ensemble_hooks_t *hooks,
                                 karst_ensemble_summary_t *summary) {
  karst_error_t err = KARST_SUCCESS;
  char *real_dir = NULL, *header = NULL;
  karst_int_t *pending = NULL;
  karst_ensemble_summary_t sum;
  int lock_fd = -1;
  char *lock_path = NULL;
  double t0 = now_seconds();
  memset(&sum, 0, sizeof sum);
  err = check_arguments(ctx, dir, opt, hooks);
  if (err) return err;
  sum.n = opt->n;
  sum.ranks = mpi_world(opt->use_mpi, &sum.rank);

  real_dir = karst_i_path_join(dir, "realisations");
  pending = malloc((size_t)opt->n * sizeof *pending);
  if (!real_dir || !pending) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  err = karst_i_metrics_header(ctx, hooks, &header);
  if (err) goto cleanup;

  /* Rank 0 locks and prepares the directory; the others wait for its verdict. The lock comes
   * before anything else is touched: a second run must not remove the first one's temporaries. */
  if (sum.rank == 0) {
    err = karst_mkdir_p(ctx, dir);
    if (!err) err = take_lock(ctx, dir, &lock_fd, &lock_path);
    if (!err) err = karst_mkdir_p(ctx, real_dir);
    if (!err) err = remove_stale_temporaries(ctx, dir);
    if (!err) err = remove_stale_temporaries(ctx, real_dir);
    if (!err) err = check_or_write_key(ctx, real_dir, opt);
  }
  {
    karst_error_t all = mpi_agree(sum.ranks, err);
    if (all && !err)
      err = karst_set_error(ctx, all, "rank 0 could not prepare %s: %s", dir, karst_strerror(all));
    if (err) goto cleanup;
  }

  karst_int_t n_pending = 0, reused = 0;
  for (karst_int_t i = 0; i < opt->n; i++) {
    char name[32];
    karst_i_member_name(name, i);
    char *p = karst_i_path_join(real_dir, name);
    if (!p) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    int done = is_dir(p);
    free(p);
    if (done) {
      reused++;
    } else if (i % sum.ranks == sum.rank) {
      pending[n_pending++] = i;
    }
  }
  sum.reused = reused;
  if (sum.rank == 0 && reused > 0)
    karst_log(ctx, KARST_LOG_INFO,
              "%s: %" PRId64 " of %" PRId64 " realisations are already complete", dir, reused,
              opt->n);

  run_state_t rs;
  memset(&rs, 0, sizeof rs);
  rs.real_dir = real_dir;
  rs.opt = opt;
  rs.hooks = hooks;
  rs.header = header;
  rs.parent = ctx;
  rs.pending = pending;
  rs.n_pending = n_pending;
  err = run_queue(ctx, &rs, opt->nthreads);
  sum.computed = rs.done;

  {
    karst_error_t all = mpi_agree(sum.ranks, err);
    sum.complete = reused + mpi_sum(sum.ranks, rs.done);
    if (all && !err)
      err = karst_set_error(ctx, all, "another rank failed (%s); see its message",
                            karst_strerror(all));
    if (err) goto cleanup;
  }
  sum.wall_seconds = now_seconds() - t0;
  if (sum.rank == 0) {
    err = write_collection_files(ctx, dir, opt, hooks, header, &sum, opt->nthreads);
  }
  {
    karst_error_t all = mpi_agree(sum.ranks, err);
    if (all && !err) err = karst_set_error(ctx, all, "rank 0 could not write the collection files");
  }
cleanup:
  release_lock(lock_fd, lock_path);
  sum.wall_seconds = now_seconds() - t0;
  if (summary) *summary = sum;
  free(pending);
  free(header);
  free(real_dir);
  return err;
}

/* ------------------------------------------------------------------------ */
/* MPI start / finish                                                       */
/* ------------------------------------------------------------------------ */
/**
 * Processes announced by a launcher (see ensemble.h): OMPI_COMM_WORLD_SIZE, else PMI_SIZE;
 * 1 when neither is a whole number >= 1. Time complexity: O(1).
 */
int karst_ensemble_launcher_size(void) {
  const char *names[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"};
  for (int k = 0; k < 2; k++) {
    const char *v = getenv(names[k]);
    if (!v || *v < '0' || *v > '9') continue;
    char *end;
    errno = 0;
    long n = strtol(v, &end, 10);
    if (errno == 0 && *end == '\0' && n >= 1 && n <= 1000000000L) return (int)n;
  }
  return 1;
}

/**
 * Refuse a launch of several processes by a build without MPI (ensemble_internal.h).
 * Time complexity: O(1).
 */
karst_error_t karst_i_ensemble_launcher_check(karst_ctx_t *ctx, int built_with_mpi, int *size) {
  *size = karst_ensemble_launcher_size();
  if (*size > 1 && !built_with_mpi)
    return karst_set_error(
        ctx, KARST_EUNSUPPORTED,
        "started by an MPI launcher as one of %d processes (OMPI_COMM_WORLD_SIZE or PMI_SIZE), "
        "but this karst was built without MPI (CMake found no MPI, or -DKARST_WITH_MPI=OFF): "
        "each process would compute every realisation and overwrite the others' files; run "
        "one process without mpirun, or rebuild with MPI (Debian libopenmpi-dev)",
        *size);
  return KARST_SUCCESS;
}

/**
 * Join the MPI world when started by mpirun. Detection: Open MPI sets
 * OMPI_COMM_WORLD_SIZE in every rank (PMI_SIZE for other launchers); a plain
 * start never initialises MPI, so a single process does not need mpirun.
 * @p initialised is set to 1 when this call initialised MPI (pass it to
 * karst_ensemble_mpi_finish).
 * @return KARST_EEXTERNAL when MPI_Init_thread fails; KARST_EUNSUPPORTED when
 *         this build has no MPI and a launcher started several processes.
 */
karst_error_t karst_ensemble_mpi_start(karst_ctx_t *ctx, int *ranks, int *rank, int *initialised) {
  *ranks = 1;
  *rank = 0;
  *initialised = 0;
  int launched = 1;
  karst_error_t err = karst_i_ensemble_launcher_check(ctx, KARST_HAVE_MPI, &launched);
  if (err) return err;
#if KARST_HAVE_MPI
  if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMI_SIZE")) return KARST_SUCCESS;
  char why[1024];
  const karst_i_mpi_api_t *m = karst_i_mpi_load(why, sizeof why);
  if (!m)
    return karst_set_error(ctx, KARST_ENOTIMPL,
                           "started by an MPI launcher, but karst's MPI plugin (%s, next to "
                           "libkarst) could not be loaded: %s",
                           KARST_I_MPI_PLUGIN, why);
  int init = 0;
  m->initialized(&init);
  if (!init) {
    int provided = 0;
    if (m->init_thread_funneled(&provided) != 0)
      return karst_set_error(ctx, KARST_EEXTERNAL, "MPI_Init_thread failed");
    *initialised = 1;
  }
  m->size(ranks);
  m->rank(rank);
#endif
  return KARST_SUCCESS;
}

/** Finalise MPI when @p initialised (from karst_ensemble_mpi_start) says it was started there. */
void karst_ensemble_mpi_finish(int initialised) {
#if KARST_HAVE_MPI
  const karst_i_mpi_api_t *m = karst_i_mpi_loaded();
  int fin = 0;
  if (!m) return;
  m->finalized(&fin);
  if (initialised && !fin) m->finalize();
#else
  (void)initialised;
#endif
}

/* ------------------------------------------------------------------------ */
/* For other stages that run ensembles (src/calibrate/): ensemble_internal.h */
/* ------------------------------------------------------------------------ */
/** The lock of take_lock on DIR/@p name (ensemble_internal.h). Time complexity: O(1). */
karst_error_t karst_i_ensemble_lock(karst_ctx_t *ctx, const char *dir, const char *name,
                                    const char *what, int *fd, char **path) {
  return take_lock_named(ctx, dir, name, what, fd, path);
}

/** Release a lock of karst_i_ensemble_lock (ensemble_internal.h). Time complexity: O(1). */
void karst_i_ensemble_unlock(int fd, char *path) {
  release_lock(fd, path);
}

/** The MPI world as karst_ensemble_run sees it (ensemble_internal.h). Time complexity: O(1). */
int karst_i_ensemble_world(int use_mpi, int *rank) {
  return mpi_world(use_mpi, rank);
}

/** The worst error code over the ranks (ensemble_internal.h). Time complexity: one allreduce. */
karst_error_t karst_i_ensemble_agree(int ranks, karst_error_t local) {
  return mpi_agree(ranks, local);
}

/** Remove a file or directory tree (ensemble_internal.h). Time complexity: O(files). */
int karst_i_remove_tree(const char *path) {
  return remove_tree(path);
}

/** Remove leftovers ".*.tmp.*" of a killed run in @p dir (ensemble_internal.h). O(entries). */
karst_error_t karst_i_remove_stale_temporaries(karst_ctx_t *ctx, const char *dir) {
  return remove_stale_temporaries(ctx, dir);
}
