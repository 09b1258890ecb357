/* A minimal static-partition thread pool shared by the stages that split
 * their work over ctx->nthreads (graph, sampling). Work is assigned by
 * thread number only, never by who finishes first, so a computation whose
 * pieces write disjoint memory gives the same result for any thread count. */
#ifndef KARST_PARALLEL_INTERNAL_H
#define KARST_PARALLEL_INTERNAL_H

/** Upper bound on the threads karst_i_parallel_run starts. */
#define KARST_I_MAX_THREADS 256

typedef void (*karst_i_task_fn)(void *arg, int tid, int nthreads);

/**
 * Run fn(arg, tid, nthreads) for tid = 0 .. nthreads - 1 (clamped to
 * [1, KARST_I_MAX_THREADS]) and wait for all of them. Thread 0 runs in the
 * caller; a thread that cannot be created runs its part in the caller after
 * the others, so the work done is the same either way.
 */
void karst_i_parallel_run(int nthreads, karst_i_task_fn fn, void *arg);

#endif
