/* The BLAS thread count, set through OpenBLAS's own entry point when the
 * BLAS in the process is OpenBLAS. Looked up at run time (dlsym), so that
 * flexmbs links and runs with any BLAS: with another one nothing is set. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdlib.h>

typedef void (*set_threads_fn)(int);
typedef int (*get_threads_fn)(void);

/* Set n threads; 1 when OpenBLAS was found, 0 otherwise. */
int flexmbs_blas_set_threads(int n)
{
    set_threads_fn set = (set_threads_fn)dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
    if (set == NULL) return 0;
    set(n);
    return 1;
}

/* OpenBLAS's current thread count, or 0 when the BLAS is not OpenBLAS. */
int flexmbs_blas_get_threads(void)
{
    get_threads_fn get = (get_threads_fn)dlsym(RTLD_DEFAULT, "openblas_get_num_threads");
    return get == NULL ? 0 : get();
}

/* 1 when the variable is set (to anything), 0 otherwise. */
int flexmbs_env_is_set(const char *name)
{
    return getenv(name) != NULL;
}
