/* The karst Python extension (karst._karst): shared pieces of the C files of src/python/. The
 * extension is a thin layer over the library: it converts between Python objects and karst types,
 * releases the GIL around every library call, and turns karst errors into Python exceptions
 * carrying the message the command-line program prints. The Python API itself is src/python/karst/.
 */
#ifndef KARST_PYTHON_INTERNAL_H
#define KARST_PYTHON_INTERNAL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL karst_python_ARRAY_API
#ifndef KARST_PYTHON_IMPORT_ARRAY
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include <pthread.h>
#include <signal.h>

#include "karst.h"

/** Seconds between two calls of a Python progress callback (the last call is always made). */
#define KARST_PY_PROGRESS_INTERVAL 0.2

/** The exception classes of the module (module state). */
typedef struct {
  PyObject *error;                      /**< karst.KarstError */
  PyObject *by_code[KARST_ERROR_COUNT]; /**< the class raised for each error code */
  PyObject *warning;                    /**< karst.KarstWarning */
} karst_py_state_t;

/** One library call made from Python: its context and what crosses the GIL boundary. */
typedef struct {
  karst_ctx_t ctx;
  karst_py_state_t *state;
  PyObject *module;     /**< the extension module (borrowed) */
  volatile int stop;    /**< ctx.interrupt: set by Ctrl-C or a failing progress callback */
  volatile int sigint;  /**< Ctrl-C was pressed during the call */
  int sigint_installed; /**< SIGINT sets the interrupt flag during this call */
  struct sigaction old_sigint;
  PyObject *progress;   /**< Python callable (stage, done, total), or NULL (borrowed) */
  double last_progress; /**< monotonic time of its last call */
  PyObject *cb_type, *cb_value, *cb_tb; /**< an exception raised by the callback */
  pthread_mutex_t lock; /**< guards the warnings (the library logs from worker threads) */
  char *warnings;       /**< warnings logged during the call, one per line */
  size_t warnings_len;
} karst_py_call_t;

/** Start a call: context with @p nthreads threads (<= 0: all processors), warnings collected,
 * progress to @p progress (or none), Ctrl-C stopping the library when in the main thread.
 * Call with the GIL held, before Py_BEGIN_ALLOW_THREADS. */
void karst_py_call_begin(karst_py_call_t *c, PyObject *module, int nthreads, PyObject *progress);
/**
 * End a call made with the GIL released, once it is held again: restore SIGINT, issue the
 * warnings as karst.KarstWarning, then set the exception of the outcome: the progress
 * callback's own exception, KeyboardInterrupt after Ctrl-C, or the class of @p err with
 * ctx.errmsg (the CLI's message). Returns 0 on success, -1 with an exception set.
 */
int karst_py_call_finish(karst_py_call_t *c, karst_error_t err);

/** Raise the class of @p code with @p msg (the library's message). Returns NULL. */
PyObject *karst_py_raise(PyObject *module, karst_error_t code, const char *msg);

/** @p net as a Python dict: xyz (n, 3) float64, edges (m, 2) int64, node_data and edge_data
 * ({name: array}; integer attributes int64, others float64; several components as (n, k)),
 * labels (list or None), crs, title. New reference, NULL with an exception set. */
PyObject *karst_py_network_to_dict(const karst_network_t *net);
/** The network of a Python object with the attributes of karst.Network (xyz, edges, node_data,
 * edge_data, labels, crs, title) into @p net (initialised by the caller); checks shapes, sizes
 * and that edges name existing nodes. 0, or -1 with an exception set. */
int karst_py_network_from_object(PyObject *module, PyObject *obj, karst_network_t *net);

/** A path argument (str, bytes or os.PathLike) as a new bytes object, NULL on error. */
PyObject *karst_py_path(PyObject *obj);

/* The module's functions (src/python/calls.c). */
PyObject *karst_py_generate(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_read_network(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_metrics(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_write_vtp(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_ensemble(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_ensemble_table(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_compare(PyObject *module, PyObject *args, PyObject *kw);
PyObject *karst_py_export_gpkg(PyObject *module, PyObject *args, PyObject *kw);

#endif
