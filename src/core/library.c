/* Shared libraries opened on first use (library_internal.h). */
#include "core/library_internal.h"

#include <dlfcn.h>
#include <stdio.h>

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
