/* karst._karst: module definition, exceptions, and the bridge between a library call made with
 * the GIL released and Python (warnings, progress callbacks, Ctrl-C). */
#define KARST_PYTHON_IMPORT_ARRAY
#include "python/python_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "karst/arrays.h"
#include "karst/palette.h"

/* ------------------------------------------------------------------------ */
/* Exceptions                                                                */
/* ------------------------------------------------------------------------ */

/* The Python class of each error code: KarstError and a subclass that is also the built-in
 * exception a Python programmer expects (ValueError for bad values, OSError for files ...). */
static const struct {
  karst_error_t code;
  const char *name; /* NULL: KarstError itself */
  const char *doc;
} classes[] = {
    {KARST_ENOMEM, NULL, NULL}, /* MemoryError, below */
    {KARST_EINVAL, "InvalidValueError", "A value karst cannot use (KARST_EINVAL)."},
    {KARST_EIO, "KarstIOError", "A file that cannot be read or written (KARST_EIO)."},
    {KARST_EPARSE, "ParseError", "Malformed input: the message names FILE:LINE (KARST_EPARSE)."},
    {KARST_ERANGE, "RangeError", "A value outside its allowed range (KARST_ERANGE)."},
    {KARST_ENOTFOUND, "NotFoundError", "A file, program or name that does not exist."},
    {KARST_EUNSUPPORTED, "UnsupportedError", "Not supported (KARST_EUNSUPPORTED)."},
    {KARST_EUNREACHABLE, "UnreachableError",
     "A key point cannot be connected to the network (KARST_EUNREACHABLE)."},
    {KARST_EEXTERNAL, "ExternalError", "An external program or library failed."},
    {KARST_EBUSY, "BusyError", "In use by another process, e.g. an ensemble being run."},
    {KARST_ENOTIMPL, "NotImplementedKarstError", "Not available yet (KARST_ENOTIMPL)."},
};

static PyObject *builtin_base(karst_error_t code) {
  switch (code) {
  case KARST_EINVAL:
  case KARST_EPARSE:
  case KARST_ERANGE:
    return PyExc_ValueError;
  case KARST_EIO:
  case KARST_EBUSY:
    return PyExc_OSError;
  case KARST_ENOTFOUND:
    return PyExc_FileNotFoundError;
  case KARST_EUNSUPPORTED:
  case KARST_ENOTIMPL:
    return PyExc_NotImplementedError;
  default:
    return NULL;
  }
}

static karst_py_state_t *state_of(PyObject *module) {
  return (karst_py_state_t *)PyModule_GetState(module);
}

/* Raise @p cls(msg) with the attribute code = "KARST_E..." on the instance. */
static PyObject *raise_with_code(PyObject *cls, karst_error_t code, const char *msg) {
  PyObject *exc = PyObject_CallFunction(cls, "s", msg);
  if (!exc) return NULL;
  PyObject *name = PyUnicode_FromString(karst_error_name(code));
  if (!name || PyObject_SetAttrString(exc, "code", name) < 0) {
    Py_XDECREF(name);
    Py_DECREF(exc);
    return NULL;
  }
  Py_DECREF(name);
  PyErr_SetObject(cls, exc);
  Py_DECREF(exc);
  return NULL;
}

PyObject *karst_py_raise(PyObject *module, karst_error_t code, const char *msg) {
  karst_py_state_t *st = state_of(module);
  if (!msg || !*msg) msg = karst_strerror(code);
  if (code == KARST_ENOMEM) return PyErr_Format(PyExc_MemoryError, "%s", msg);
  if (code == KARST_EINTERRUPTED) {
    PyErr_SetString(PyExc_KeyboardInterrupt, msg);
    return NULL;
  }
  PyObject *cls = (int)code >= 0 && code < KARST_ERROR_COUNT && st->by_code[code]
                      ? st->by_code[code]
                      : st->error;
  return raise_with_code(cls, code, msg);
}

/* ------------------------------------------------------------------------ */
/* A call with the GIL released                                              */
/* ------------------------------------------------------------------------ */

/* The call of the main thread that Ctrl-C stops (signal handlers can only reach statics). */
static karst_py_call_t *volatile sigint_target;
static unsigned long main_thread_ident;

static void on_sigint(int sig) {
  (void)sig;
  karst_py_call_t *c = sigint_target;
  if (c) {
    c->sigint = 1;
    c->stop = 1;
  }
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void py_log(void *user, karst_log_level_t level, const char *msg) {
  karst_py_call_t *c = user;
  if (level > KARST_LOG_WARNING) return;
  size_t n = strlen(msg);
  pthread_mutex_lock(&c->lock);
  char *w = realloc(c->warnings, c->warnings_len + n + 2);
  if (w) {
    memcpy(w + c->warnings_len, msg, n);
    w[c->warnings_len + n] = '\n';
    w[c->warnings_len + n + 1] = '\0';
    c->warnings = w;
    c->warnings_len += n + 1;
  }
  pthread_mutex_unlock(&c->lock);
}

/* The library's progress, to the Python callable; may run on any thread, so it takes the GIL.
 * A callback that raises stops the call, and its exception is raised by the call. */
static void py_progress(void *user, const char *stage, double done, double total) {
  karst_py_call_t *c = user;
  double t = now_s();
  pthread_mutex_lock(&c->lock);
  int due = (total > 0 && done >= total) || done == 0 ||
            t - c->last_progress >= KARST_PY_PROGRESS_INTERVAL;
  if (due) c->last_progress = t;
  pthread_mutex_unlock(&c->lock);
  if (!due) return;
  PyGILState_STATE g = PyGILState_Ensure();
  if (!c->cb_type) {
    PyObject *r = PyObject_CallFunction(c->progress, "sdd", stage, done, total);
    if (r) {
      Py_DECREF(r);
    } else {
      PyErr_Fetch(&c->cb_type, &c->cb_value, &c->cb_tb);
      c->stop = 1;
    }
  }
  PyGILState_Release(g);
}

void karst_py_call_begin(karst_py_call_t *c, PyObject *module, int nthreads, PyObject *progress) {
  memset(c, 0, sizeof *c);
  karst_ctx_init(&c->ctx);
  c->state = state_of(module);
  c->module = module;
  pthread_mutex_init(&c->lock, NULL);
  c->ctx.log = py_log;
  c->ctx.log_user = c;
  c->ctx.verbosity = KARST_LOG_WARNING;
  if (nthreads <= 0) {
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    nthreads = n > 0 ? (int)n : 1;
  }
  c->ctx.nthreads = nthreads;
  c->ctx.interrupt = &c->stop;
  if (progress && progress != Py_None) {
    c->progress = progress;
    c->ctx.progress = py_progress;
    c->ctx.progress_user = c;
  }
  /* Ctrl-C: Python's own handler only sets a flag that the interpreter reads once it runs
   * again, i.e. after the library returns; during the call, ours stops the library. */
  if (PyThread_get_thread_ident() == main_thread_ident && !sigint_target) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigint_target = c;
    if (sigaction(SIGINT, &sa, &c->old_sigint) == 0)
      c->sigint_installed = 1;
    else
      sigint_target = NULL;
  }
}

int karst_py_call_finish(karst_py_call_t *c, karst_error_t err) {
  int status = 0;
  if (c->sigint_installed) {
    sigaction(SIGINT, &c->old_sigint, NULL);
    sigint_target = NULL;
  }
  if (PyErr_Occurred()) { /* the caller failed before the library ran */
    Py_XDECREF(c->cb_type), Py_XDECREF(c->cb_value), Py_XDECREF(c->cb_tb);
    free(c->warnings);
    pthread_mutex_destroy(&c->lock);
    return -1;
  }
  /* Warnings first: a failure may follow them. */
  for (char *line = c->warnings; line && *line && status == 0;) {
    char *nl = strchr(line, '\n');
    if (nl) *nl = '\0';
    if (PyErr_WarnEx(c->state->warning, line, 1) < 0) status = -1;
    line = nl ? nl + 1 : line + strlen(line);
  }
  free(c->warnings);
  c->warnings = NULL;
  pthread_mutex_destroy(&c->lock);
  if (status < 0) {
    Py_XDECREF(c->cb_type), Py_XDECREF(c->cb_value), Py_XDECREF(c->cb_tb);
    return -1;
  }
  if (c->cb_type) {
    PyErr_Restore(c->cb_type, c->cb_value, c->cb_tb);
    return -1;
  }
  if (c->sigint) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    return -1;
  }
  if (err) {
    const char *msg = c->ctx.errmsg[0] ? c->ctx.errmsg : karst_strerror(err);
    karst_py_raise(c->module, err, msg);
    return -1;
  }
  return 0;
}

/* ------------------------------------------------------------------------ */
/* Small functions                                                           */
/* ------------------------------------------------------------------------ */

PyObject *karst_py_path(PyObject *obj) {
  PyObject *out = NULL;
  if (!PyUnicode_FSConverter(obj, &out)) return NULL;
  return out;
}

static PyObject *py_versions(PyObject *module, PyObject *unused) {
  (void)module, (void)unused;
  karst_component_t c[KARST_COMPONENTS_MAX];
  int n = karst_versions(c);
  PyObject *list = PyList_New(n);
  for (int i = 0; list && i < n; i++) {
    PyObject *t = Py_BuildValue("(ss)", c[i].name, c[i].version);
    if (!t) {
      Py_CLEAR(list);
      break;
    }
    PyList_SET_ITEM(list, i, t);
  }
  return list;
}

static PyObject *py_metric_fields(PyObject *module, PyObject *unused) {
  (void)module, (void)unused;
  int n = 0;
  const karst_metric_field_t *f = karst_metric_fields(&n);
  PyObject *list = PyList_New(n);
  for (int i = 0; list && i < n; i++) {
    PyObject *t = Py_BuildValue("(sO)", f[i].key, f[i].is_int ? Py_True : Py_False);
    if (!t) {
      Py_CLEAR(list);
      break;
    }
    PyList_SET_ITEM(list, i, t);
  }
  return list;
}

/* palette(array): [(code, name, "#RRGGBB"), ...] of a categorical array, or None. */
static PyObject *py_palette(PyObject *module, PyObject *arg) {
  (void)module;
  const char *name = PyUnicode_AsUTF8(arg);
  if (!name) return NULL;
  const karst_palette_t *p = karst_palette_find(name);
  if (!p || p->kind != KARST_PALETTE_CATEGORICAL) Py_RETURN_NONE;
  PyObject *list = PyList_New(p->n);
  for (int i = 0; list && i < p->n; i++) {
    PyObject *t =
        Py_BuildValue("(iss)", p->categories[i].code, p->categories[i].name, p->categories[i].hex);
    if (!t) {
      Py_CLEAR(list);
      break;
    }
    PyList_SET_ITEM(list, i, t);
  }
  return list;
}

/* role_colour(name): the palette's colour of "ensemble", "survey", "published", "none",
 * "structure". */
static PyObject *py_role_colour(PyObject *module, PyObject *arg) {
  (void)module;
  static const char *const roles[KARST_PALETTE_ROLE_COUNT] = {"ensemble", "survey", "published",
                                                              "none", "structure"};
  const char *name = PyUnicode_AsUTF8(arg);
  if (!name) return NULL;
  for (int i = 0; i < KARST_PALETTE_ROLE_COUNT; i++)
    if (strcmp(name, roles[i]) == 0)
      return PyUnicode_FromString(karst_palette_role((karst_palette_role_t)i));
  return PyErr_Format(PyExc_ValueError,
                      "unknown role '%s' (ensemble, survey, published, none or structure)", name);
}

/* array_info(name): (unit, title, meaning, where) of an array karst writes, or None
 * (include/karst/arrays.h). */
static PyObject *py_array_info(PyObject *module, PyObject *arg) {
  (void)module;
  const char *name = PyUnicode_AsUTF8(arg);
  if (!name) return NULL;
  const karst_array_info_t *a = karst_arrays_find(name);
  if (!a) Py_RETURN_NONE;
  return Py_BuildValue("{s:s,s:s,s:s,s:s}", "unit", a->unit, "title", a->title, "meaning",
                       a->meaning, "where", a->where);
}

static PyObject *names_list(const char *(*fn)(int), int n) {
  PyObject *list = PyList_New(n);
  for (int i = 0; list && i < n; i++) {
    PyObject *s = PyUnicode_FromString(fn(i));
    if (!s) {
      Py_CLEAR(list);
      break;
    }
    PyList_SET_ITEM(list, i, s);
  }
  return list;
}

static const char *tunnel_name(int i) {
  return karst_tunnel_type_name((karst_tunnel_type_t)i);
}
static const char *kind_name(int i) {
  return karst_node_kind_name((karst_node_kind_t)i);
}

static PyObject *py_tunnel_type_names(PyObject *m, PyObject *u) {
  (void)m, (void)u;
  return names_list(tunnel_name, KARST_TUNNEL_TYPE_COUNT);
}

static PyObject *py_node_kind_names(PyObject *m, PyObject *u) {
  (void)m, (void)u;
  return names_list(kind_name, KARST_NODE_KIND_COUNT);
}

/* published(path or None): {metric: (n, min, max)} of the table of Collon et al. 2017. */
static PyObject *py_published(PyObject *module, PyObject *args) {
  PyObject *path_obj = Py_None, *path = NULL;
  if (!PyArg_ParseTuple(args, "|O", &path_obj)) return NULL;
  if (path_obj != Py_None && !(path = karst_py_path(path_obj))) return NULL;
  karst_py_call_t c;
  karst_py_call_begin(&c, module, 1, NULL);
  karst_published_t pub;
  karst_published_init(&pub);
  char found[4096] = "";
  karst_error_t err = KARST_SUCCESS;
  Py_BEGIN_ALLOW_THREADS;
  if (path)
    snprintf(found, sizeof found, "%s", PyBytes_AS_STRING(path));
  else
    err = karst_published_locate(&c.ctx, found, sizeof found);
  if (path || !err) err = karst_published_read(&c.ctx, found, &pub);
  Py_END_ALLOW_THREADS;
  Py_XDECREF(path);
  PyObject *out = NULL;
  if (karst_py_call_finish(&c, err) == 0) {
    PyObject *ranges = PyDict_New();
    for (int i = 0; ranges && i < pub.n_ranges; i++) {
      PyObject *t = Py_BuildValue("(idd)", pub.ranges[i].n, pub.ranges[i].min, pub.ranges[i].max);
      if (!t || PyDict_SetItemString(ranges, pub.ranges[i].key, t) < 0) Py_CLEAR(ranges);
      Py_XDECREF(t);
    }
    if (ranges)
      out = Py_BuildValue("{s:s,s:i,s:N}", "path", found, "n_caves", pub.n_caves, "ranges", ranges);
  }
  karst_published_destroy(&pub);
  return out;
}

#define KW(f) (PyCFunction)(void (*)(void))(f), METH_VARARGS | METH_KEYWORDS

static PyMethodDef methods[] = {
    {"generate", KW(karst_py_generate),
     "generate(scenario, seed, realisation, threads, samples, "
     "progress) -> (network dict, stats dict, samples)"},
    {"read_network", KW(karst_py_read_network), "read_network(path) -> network dict"},
    {"metrics", KW(karst_py_metrics), "metrics(network or path, true_north, threads) -> dict"},
    {"write_vtp", KW(karst_py_write_vtp), "write_vtp(network, path)"},
    {"ensemble", KW(karst_py_ensemble),
     "ensemble(scenario, output, n, seed, threads, progress) -> summary dict"},
    {"ensemble_table", KW(karst_py_ensemble_table),
     "ensemble_table(path) -> (names, index, seed, values)"},
    {"compare", KW(karst_py_compare),
     "compare(metrics_csv, label, names, values, published) -> [row dict]"},
    {"export_gpkg", KW(karst_py_export_gpkg), "export_gpkg(source, path, crs, qml) -> summary"},
    {"versions", py_versions, METH_NOARGS, "[(component, version)] of karst --version"},
    {"metric_fields", py_metric_fields, METH_NOARGS, "[(metric, is_integer)] in output order"},
    {"palette", py_palette, METH_O, "palette(array) -> [(code, name, colour)] or None"},
    {"role_colour", py_role_colour, METH_O, "role_colour(role) -> '#RRGGBB'"},
    {"array_info", py_array_info, METH_O, "array_info(name) -> {unit, title, meaning, where}"},
    {"tunnel_type_names", py_tunnel_type_names, METH_NOARGS, "names of tunnel_type codes"},
    {"node_kind_names", py_node_kind_names, METH_NOARGS, "names of node kind codes"},
    {"published", py_published, METH_VARARGS, "published(path=None) -> the 34-cave table"},
    {NULL, NULL, 0, NULL}};

static int traverse(PyObject *m, visitproc visit, void *arg) {
  karst_py_state_t *st = state_of(m);
  Py_VISIT(st->error);
  Py_VISIT(st->warning);
  for (int i = 0; i < KARST_ERROR_COUNT; i++)
    Py_VISIT(st->by_code[i]);
  return 0;
}

static int clear(PyObject *m) {
  karst_py_state_t *st = state_of(m);
  Py_CLEAR(st->error);
  Py_CLEAR(st->warning);
  for (int i = 0; i < KARST_ERROR_COUNT; i++)
    Py_CLEAR(st->by_code[i]);
  return 0;
}

static void free_module(void *m) {
  clear((PyObject *)m);
}

static struct PyModuleDef module_def = {PyModuleDef_HEAD_INIT,
                                        "karst._karst",
                                        "The C extension behind the karst package.",
                                        sizeof(karst_py_state_t),
                                        methods,
                                        NULL,
                                        traverse,
                                        clear,
                                        free_module};

/* The identity of the main thread, where Python delivers signals. */
static int find_main_thread(void) {
  PyObject *threading = PyImport_ImportModule("threading");
  if (!threading) return -1;
  PyObject *main = PyObject_CallMethod(threading, "main_thread", NULL);
  Py_DECREF(threading);
  if (!main) return -1;
  PyObject *ident = PyObject_GetAttrString(main, "ident");
  Py_DECREF(main);
  if (!ident) return -1;
  main_thread_ident = PyLong_AsUnsignedLong(ident);
  Py_DECREF(ident);
  return PyErr_Occurred() ? -1 : 0;
}

PyMODINIT_FUNC PyInit__karst(void) {
  import_array();
  PyObject *m = PyModule_Create(&module_def);
  if (!m) return NULL;
  karst_py_state_t *st = state_of(m);
  if (find_main_thread() < 0) goto fail;
  st->error = PyErr_NewExceptionWithDoc(
      "karst.KarstError",
      "An error of the karst library; str(e) is the message the karst command prints and "
      "e.code the name of the error code (e.g. 'KARST_EPARSE').",
      NULL, NULL);
  st->warning = PyErr_NewExceptionWithDoc("karst.KarstWarning", "A warning of the karst library.",
                                          PyExc_UserWarning, NULL);
  if (!st->error || !st->warning) goto fail;
  Py_INCREF(st->error);
  if (PyModule_AddObject(m, "KarstError", st->error) < 0) goto fail;
  Py_INCREF(st->warning);
  if (PyModule_AddObject(m, "KarstWarning", st->warning) < 0) goto fail;
  for (size_t i = 0; i < sizeof classes / sizeof classes[0]; i++) {
    if (!classes[i].name) continue;
    PyObject *base = builtin_base(classes[i].code);
    PyObject *bases = base ? PyTuple_Pack(2, st->error, base) : PyTuple_Pack(1, st->error);
    if (!bases) goto fail;
    char qual[96];
    snprintf(qual, sizeof qual, "karst.%s", classes[i].name);
    PyObject *cls = PyErr_NewExceptionWithDoc(qual, classes[i].doc, bases, NULL);
    Py_DECREF(bases);
    if (!cls) goto fail;
    st->by_code[classes[i].code] = cls;
    Py_INCREF(cls);
    if (PyModule_AddObject(m, classes[i].name, cls) < 0) {
      Py_DECREF(cls);
      goto fail;
    }
  }
  if (PyModule_AddStringConstant(m, "__version__", karst_version()) < 0) goto fail;
  return m;
fail:
  Py_DECREF(m);
  return NULL;
}
