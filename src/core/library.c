/* Shared libraries opened on first use (library_internal.h). */
#define _GNU_SOURCE /* dladdr */
#include "core/library_internal.h"

#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

int karst_i_library_open(const char *file, int global, const char *const *names, void **syms,
                         size_t n, char *why, size_t why_size) {
  for (size_t i = 0; i < n; i++)
    syms[i] = NULL;
  void *lib = dlopen(file, RTLD_NOW | (global ? RTLD_GLOBAL : RTLD_LOCAL));
  if (!lib) {
    const char *e = dlerror();
    snprintf(why, why_size, "%s", e ? e : "dlopen failed");
    return -1;
  }
  for (size_t i = 0; i < n; i++) {
    syms[i] = dlsym(lib, names[i]);
    if (!syms[i]) {
      snprintf(why, why_size, "%s has no symbol %s", file, names[i]);
      for (size_t j = 0; j < n; j++)
        syms[j] = NULL;
      return -1;
    }
  }
  return 0;
}

int karst_i_library_open_plugin(const char *file, int global, const char *const *names,
                                void **syms, size_t n, char *why, size_t why_size) {
  Dl_info info;
  char path[4096];
  for (size_t i = 0; i < n; i++)
    syms[i] = NULL;
  if (!dladdr((void *)karst_i_library_open_plugin, &info) || !info.dli_fname) {
    snprintf(why, why_size, "cannot tell where libkarst is (dladdr)");
    return -1;
  }
  const char *slash = strrchr(info.dli_fname, '/');
  int dir = slash ? (int)(slash - info.dli_fname) : 0;
  if (snprintf(path, sizeof path, "%.*s%s%s", dir, info.dli_fname, slash ? "/" : "", file) >=
      (int)sizeof path) {
    snprintf(why, why_size, "the path of %s is too long", file);
    return -1;
  }
  return karst_i_library_open(slash ? path : file, global, names, syms, n, why, why_size);
}

const void *karst_i_plugin_table(const char *file, const char *entry, int global, int version,
                                 char *why, size_t why_size) {
  const char *const names[] = {entry};
  void *sym;
  if (karst_i_library_open_plugin(file, global, names, &sym, 1, why, why_size) != 0) return NULL;
  const void *(*get)(void);
  memcpy(&get, &sym, sizeof sym);
  const void *table = get();
  int got = -1;
  if (table) memcpy(&got, table, sizeof got);
  if (got != version) {
    snprintf(why, why_size, "%s is of another karst (interface %d, expected %d)", file, got,
             version);
    return NULL;
  }
  return table;
}
