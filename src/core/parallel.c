/* The static-partition thread pool of parallel_internal.h. */
#include <pthread.h>

#include "core/parallel_internal.h"

typedef struct task {
  karst_i_task_fn fn;
  void *arg;
  int tid, nthreads;
} task_t;

static void *task_main(void *p) {
  task_t *t = p;
  t->fn(t->arg, t->tid, t->nthreads);
  return NULL;
}

/**
 * Run @p fn on @p nthreads threads (see parallel_internal.h).
 * @param nthreads requested threads, clamped to [1, KARST_I_MAX_THREADS].
 * @param fn the work of one thread: fn(arg, tid, nthreads).
 * @param arg passed through.
 * Time complexity: O(nthreads) besides the work itself.
 */
void karst_i_parallel_run(int nthreads, karst_i_task_fn fn, void *arg) {
  if (nthreads < 1) nthreads = 1;
  if (nthreads > KARST_I_MAX_THREADS) nthreads = KARST_I_MAX_THREADS;
  if (nthreads == 1) {
    fn(arg, 0, 1);
    return;
  }
  pthread_t th[KARST_I_MAX_THREADS];
  task_t tasks[KARST_I_MAX_THREADS];
  int started[KARST_I_MAX_THREADS] = {0};
  for (int t = 0; t < nthreads; t++)
    tasks[t] = (task_t){fn, arg, t, nthreads};
  for (int t = 1; t < nthreads; t++)
    started[t] = pthread_create(&th[t], NULL, task_main, &tasks[t]) == 0;
  fn(arg, 0, nthreads);
  for (int t = 1; t < nthreads; t++) {
    if (started[t])
      pthread_join(th[t], NULL);
    else
      fn(arg, t, nthreads);
  }
}
