/* flexmbs: a small C shim over KLU's 64-bit API (klu_l_* real, klu_zl_* complex).
 *
 * The handle keeps klu_l_common, the symbolic analysis and a copy of the CSC
 * pattern in C, so Fortran sees an opaque pointer and never mirrors KLU's
 * structs. One symbolic analysis serves a real and a complex numeric
 * factorisation, which live side by side (RADAU5 needs both at once).
 *
 * Indices are int64_t, 0-based CSC; complex values are interleaved (re, im),
 * the layout of C's double _Complex and Fortran's complex(c_double_complex).
 * Every function returns one of the FLEXMBS_KLU_* codes below, which the
 * Fortran module flexmbs_linalg_klu repeats as named constants.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <complex.h>
#include <math.h>
#include <suitesparse/klu.h> /* Debian: klu.h lives in suitesparse/ */
#include <suitesparse/cholmod.h>

_Static_assert(sizeof(SuiteSparse_long) == sizeof(int64_t),
               "KLU's SuiteSparse_long must be 64-bit for the klu_l_* API");

enum {
    FLEXMBS_KLU_OK = 0,
    FLEXMBS_KLU_SINGULAR = 1,       /* a zero pivot: the matrix is singular */
    FLEXMBS_KLU_OUT_OF_MEMORY = -2, /* same values as KLU's own codes */
    FLEXMBS_KLU_INVALID = -3,
    FLEXMBS_KLU_TOO_LARGE = -4,
    FLEXMBS_KLU_NOT_ANALYSED = -10, /* no symbolic analysis in the handle */
    FLEXMBS_KLU_NOT_FACTORED = -11, /* no numeric factorisation to solve with */
    FLEXMBS_KLU_NOT_FINITE = -12    /* a value is Inf or NaN */
};

enum { PART_REAL = 0, PART_COMPLEX = 1 };

/* Fill-reducing orderings (flexmbs_klu_analyse's `ordering`); the Fortran
 * module repeats them as klu_ordering_*. */
enum { ORDERING_AMD = 0, ORDERING_ND = 1, ORDERING_AUTO = 2 };

/* 'auto' keeps AMD unless the matrix is large and AMD predicts much fill:
 * then nested dissection (METIS) does better. Measured on the Brusselator:
 * 2-D grids (fill ratio (nnz(L)+nnz(U))/nnz(A) of 18 at n = 10^4, 29 at
 * 10^5) factor 20-40 % faster with ND; 1-D (ratio 1.5) 20-40 % slower, and
 * 2-D at n = 10^3 (ratio 9) no faster. */
static const int64_t nd_min_order = 5000;
static const double nd_min_fill_ratio = 10.0;

/* klu_l_refactor keeps the pivot order of the last fresh factorisation. It is
 * accepted while KLU's pivot-ratio estimate rcond = min |u_ii| / max |u_ii|
 * stays above this fraction of its value at that fresh factorisation;
 * otherwise the matrix is factored afresh with new pivoting. A stale order
 * shows as tiny or as grown diagonal pivots, both of which lower rcond; 1e-2
 * lets a reused order cost at most about two digits beyond fresh pivoting,
 * which the simplified Newton iterations of the DAE solvers absorb. KLU's
 * reciprocal pivot growth rgrowth, O(nnz) a call (10 % of the five-body run
 * when taken at every refactorisation), is measured at fresh factorisations
 * only, for the statistics. */
static const double refactor_degrade_ratio = 1.0e-2;

typedef struct {
    klu_l_numeric *numeric;
    double rcond_fresh;                /* at the last fresh factorisation */
    double rcond;                      /* at the last (re)factorisation */
    double rgrowth;                    /* at the last fresh factorisation */
    int64_t nfactor, nrefactor;        /* fresh and reused-pivot counts */
} numeric_part;

typedef struct {
    klu_l_common common;
    klu_l_symbolic *symbolic;
    int64_t n, nnz;
    SuiteSparse_long *colptr, *rowind; /* copy of the analysed pattern */
    int ordering_used;                 /* ORDERING_AMD or ORDERING_ND */
    numeric_part part[2];              /* PART_REAL, PART_COMPLEX */
} flexmbs_klu;

static int code_of(const klu_l_common *common)
{
    switch (common->status) {
    case KLU_OK:
        return FLEXMBS_KLU_OK;
    case KLU_SINGULAR:
        return FLEXMBS_KLU_SINGULAR;
    case KLU_OUT_OF_MEMORY:
        return FLEXMBS_KLU_OUT_OF_MEMORY;
    case KLU_TOO_LARGE:
        return FLEXMBS_KLU_TOO_LARGE;
    default:
        return FLEXMBS_KLU_INVALID;
    }
}

static void free_numeric(flexmbs_klu *h, int which)
{
    numeric_part *p = &h->part[which];
    if (p->numeric != NULL) {
        if (which == PART_REAL)
            klu_l_free_numeric(&p->numeric, &h->common);
        else
            klu_zl_free_numeric(&p->numeric, &h->common);
    }
    p->numeric = NULL;
}

/* Free numerics, symbolic and pattern; keep the handle and its common. */
static void clear(flexmbs_klu *h)
{
    free_numeric(h, PART_REAL);
    free_numeric(h, PART_COMPLEX);
    if (h->symbolic != NULL) klu_l_free_symbolic(&h->symbolic, &h->common);
    h->symbolic = NULL;
    free(h->colptr);
    free(h->rowind);
    h->colptr = NULL;
    h->rowind = NULL;
    h->n = 0;
    h->nnz = 0;
    memset(h->part, 0, sizeof h->part);
}

/* A new empty handle, or NULL when out of memory. */
void *flexmbs_klu_create(void)
{
    flexmbs_klu *h = calloc(1, sizeof *h);
    if (h == NULL) return NULL;
    klu_l_defaults(&h->common);
    return h;
}

/* Free the handle and everything it holds; *handle becomes NULL. */
void flexmbs_klu_free(void **handle)
{
    if (handle == NULL || *handle == NULL) return;
    flexmbs_klu *h = *handle;
    clear(h);
    free(h);
    *handle = NULL;
}

/* Symbolic analysis of an n x n pattern (colptr[n+1], rowind[colptr[n]],
 * 0-based, no duplicates). Replaces any earlier pattern and factorisation. */
/* Nested dissection for KLU's ordering = 3: METIS (through CHOLMOD) on the
 * pattern of A + Aᵀ of each diagonal block KLU hands over. Returns 1 on
 * success, 0 on failure. */
static SuiteSparse_long nested_dissection(SuiteSparse_long n, SuiteSparse_long *Ap,
                                          SuiteSparse_long *Ai, SuiteSparse_long *Perm,
                                          klu_l_common *Common)
{
    (void)Common;
    cholmod_common cc;
    cholmod_sparse A;
    SuiteSparse_long ok = 0;
    cholmod_l_start(&cc);
    memset(&A, 0, sizeof A);
    A.nrow = (size_t)n;
    A.ncol = (size_t)n;
    A.nzmax = (size_t)Ap[n];
    A.p = Ap;
    A.i = Ai;
    A.stype = 0;
    A.itype = CHOLMOD_LONG;
    A.xtype = CHOLMOD_PATTERN;
    A.dtype = CHOLMOD_DOUBLE;
    A.packed = 1;
    cholmod_sparse *At = cholmod_l_transpose(&A, 0, &cc);
    cholmod_sparse *S = At != NULL ? cholmod_l_add(&A, At, NULL, NULL, 0, 0, &cc) : NULL;
    if (S != NULL) {
        S->stype = 1; /* symmetric: METIS orders S itself, not S Sᵀ */
        ok = cholmod_l_metis(S, NULL, 0, 1, Perm, &cc) ? 1 : 0;
    }
    cholmod_l_free_sparse(&S, &cc);
    cholmod_l_free_sparse(&At, &cc);
    cholmod_l_finish(&cc);
    return ok;
}

/* Symbolic analysis with AMD, or with nested dissection (falling back to
 * AMD should METIS fail). */
static klu_l_symbolic *analyse_with(flexmbs_klu *h, int64_t n, int nd)
{
    klu_l_symbolic *symbolic = NULL;
    if (nd) {
        h->common.ordering = 3;
        h->common.user_order = nested_dissection;
        symbolic = klu_l_analyze(n, h->colptr, h->rowind, &h->common);
        if (symbolic != NULL) {
            h->ordering_used = ORDERING_ND;
            return symbolic;
        }
    }
    h->common.ordering = 0;
    h->common.user_order = NULL;
    symbolic = klu_l_analyze(n, h->colptr, h->rowind, &h->common);
    h->ordering_used = ORDERING_AMD;
    return symbolic;
}

int flexmbs_klu_ordering_used(const void *handle)
{
    const flexmbs_klu *h = handle;
    return h == NULL ? -1 : h->ordering_used;
}

int flexmbs_klu_analyse(void *handle, int64_t n, const int64_t *colptr,
                        const int64_t *rowind, int ordering)
{
    flexmbs_klu *h = handle;
    if (h == NULL || n <= 0 || colptr == NULL || rowind == NULL) return FLEXMBS_KLU_INVALID;
    clear(h);
    int64_t nnz = colptr[n];
    if (colptr[0] != 0 || nnz < 0) return FLEXMBS_KLU_INVALID;
    h->colptr = malloc((size_t)(n + 1) * sizeof *h->colptr);
    h->rowind = malloc((size_t)(nnz > 0 ? nnz : 1) * sizeof *h->rowind);
    if (h->colptr == NULL || h->rowind == NULL) {
        clear(h);
        return FLEXMBS_KLU_OUT_OF_MEMORY;
    }
    memcpy(h->colptr, colptr, (size_t)(n + 1) * sizeof *h->colptr);
    memcpy(h->rowind, rowind, (size_t)nnz * sizeof *h->rowind);
    h->symbolic = analyse_with(h, n, ordering == ORDERING_ND);
    if (ordering == ORDERING_AUTO && h->symbolic != NULL && n >= nd_min_order
        && h->symbolic->lnz + h->symbolic->unz > nd_min_fill_ratio * (double)(nnz > 0 ? nnz : 1)) {
        klu_l_free_symbolic(&h->symbolic, &h->common);
        h->symbolic = analyse_with(h, n, 1);
    }
    if (h->symbolic == NULL) {
        int code = code_of(&h->common);
        clear(h);
        return code == FLEXMBS_KLU_OK ? FLEXMBS_KLU_INVALID : code;
    }
    h->n = n;
    h->nnz = nnz;
    return FLEXMBS_KLU_OK;
}

/* KLU's estimates of the nonzeros of L and U from the symbolic analysis
 * (Symbolic->lnz, ->unz, exact for the diagonal blocks when no pivoting
 * beyond the diagonal occurs); -1 each before an analysis. */
int flexmbs_klu_predicted_fill(const void *handle, double *lnz, double *unz)
{
    const flexmbs_klu *h = handle;
    *lnz = -1.0;
    *unz = -1.0;
    if (h == NULL || h->symbolic == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    *lnz = h->symbolic->lnz;
    *unz = h->symbolic->unz;
    return FLEXMBS_KLU_OK;
}

/* Nonzeros of L + U of a part's numeric factorisation (Numeric->lnz + unz,
 * the off-diagonal blocks of the BTF form excluded); -1 when none is alive. */
int64_t flexmbs_klu_factor_nonzeros(const void *handle, int part)
{
    const flexmbs_klu *h = handle;
    if (h == NULL || (part != PART_REAL && part != PART_COMPLEX)) return -1;
    const klu_l_numeric *numeric = h->part[part].numeric;
    return numeric == NULL ? -1 : (int64_t)(numeric->lnz + numeric->unz);
}

/* Record rcond, and with `growth` rgrowth, of the current numeric
 * factorisation. */
static int measure(flexmbs_klu *h, int which, double *values, int growth)
{
    numeric_part *p = &h->part[which];
    SuiteSparse_long ok;
    if (which == PART_REAL) {
        ok = klu_l_rcond(h->symbolic, p->numeric, &h->common)
             && (!growth || klu_l_rgrowth(h->colptr, h->rowind, values, h->symbolic,
                                          p->numeric, &h->common));
    } else {
        ok = klu_zl_rcond(h->symbolic, p->numeric, &h->common)
             && (!growth || klu_zl_rgrowth(h->colptr, h->rowind, values, h->symbolic,
                                           p->numeric, &h->common));
    }
    if (!ok) return code_of(&h->common);
    p->rcond = h->common.rcond;
    if (growth) p->rgrowth = h->common.rgrowth;
    return FLEXMBS_KLU_OK;
}

/* KLU pivots straight through Inf and NaN; catch them before factoring. */
static int all_finite(const flexmbs_klu *h, int which, const double *values)
{
    int64_t nvalues = (which == PART_REAL ? 1 : 2) * h->nnz;
    for (int64_t k = 0; k < nvalues; k++)
        if (!isfinite(values[k])) return 0;
    return 1;
}

/* Factor afresh, choosing a new pivot order. */
static int fresh_factor(flexmbs_klu *h, int which, double *values)
{
    numeric_part *p = &h->part[which];
    if (h->symbolic == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    free_numeric(h, which);
    if (!all_finite(h, which, values)) return FLEXMBS_KLU_NOT_FINITE;
    if (which == PART_REAL)
        p->numeric = klu_l_factor(h->colptr, h->rowind, values, h->symbolic, &h->common);
    else
        p->numeric = klu_zl_factor(h->colptr, h->rowind, values, h->symbolic, &h->common);
    /* With halt_if_singular (KLU's default) a singular matrix yields NULL. */
    if (p->numeric == NULL || h->common.status != KLU_OK) {
        int code = code_of(&h->common);
        free_numeric(h, which);
        return code == FLEXMBS_KLU_OK ? FLEXMBS_KLU_INVALID : code;
    }
    int code = measure(h, which, values, 1);
    if (code != FLEXMBS_KLU_OK) {
        free_numeric(h, which);
        return code;
    }
    p->rcond_fresh = p->rcond;
    p->nfactor++;
    return FLEXMBS_KLU_OK;
}

/* Refactor with the old pivot order when there is one and it stays good
 * (see refactor_degrade_ratio); factor afresh otherwise. */
static int refactor(flexmbs_klu *h, int which, double *values)
{
    numeric_part *p = &h->part[which];
    if (h->symbolic == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    if (p->numeric == NULL) return fresh_factor(h, which, values);
    if (!all_finite(h, which, values)) {
        free_numeric(h, which);
        return FLEXMBS_KLU_NOT_FINITE;
    }
    SuiteSparse_long ok;
    if (which == PART_REAL)
        ok = klu_l_refactor(h->colptr, h->rowind, values, h->symbolic, p->numeric,
                            &h->common);
    else
        ok = klu_zl_refactor(h->colptr, h->rowind, values, h->symbolic, p->numeric,
                             &h->common);
    if (!ok || h->common.status != KLU_OK) {
        /* A zero pivot in the old order need not mean a singular matrix. */
        if (h->common.status == KLU_SINGULAR) return fresh_factor(h, which, values);
        int code = code_of(&h->common);
        free_numeric(h, which);
        return code == FLEXMBS_KLU_OK ? FLEXMBS_KLU_INVALID : code;
    }
    if (measure(h, which, values, 0) != FLEXMBS_KLU_OK
        || !(p->rcond >= refactor_degrade_ratio * p->rcond_fresh))
        return fresh_factor(h, which, values);
    p->nrefactor++;
    return FLEXMBS_KLU_OK;
}

int flexmbs_klu_factor(void *handle, const double *values)
{
    if (handle == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    return fresh_factor(handle, PART_REAL, (double *)values);
}

int flexmbs_klu_refactor(void *handle, const double *values)
{
    if (handle == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    return refactor(handle, PART_REAL, (double *)values);
}

int flexmbs_klu_zfactor(void *handle, const double _Complex *values)
{
    if (handle == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    return fresh_factor(handle, PART_COMPLEX, (double *)values);
}

int flexmbs_klu_zrefactor(void *handle, const double _Complex *values)
{
    if (handle == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    return refactor(handle, PART_COMPLEX, (double *)values);
}

/* Overwrite b (n x nrhs, column-major) with A^-1 b. */
int flexmbs_klu_solve(void *handle, int64_t nrhs, double *b)
{
    flexmbs_klu *h = handle;
    if (h == NULL || h->symbolic == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    if (h->part[PART_REAL].numeric == NULL) return FLEXMBS_KLU_NOT_FACTORED;
    if (nrhs < 1 || b == NULL) return FLEXMBS_KLU_INVALID;
    if (!klu_l_solve(h->symbolic, h->part[PART_REAL].numeric, h->n, nrhs, b, &h->common))
        return code_of(&h->common);
    return FLEXMBS_KLU_OK;
}

int flexmbs_klu_zsolve(void *handle, int64_t nrhs, double _Complex *b)
{
    flexmbs_klu *h = handle;
    if (h == NULL || h->symbolic == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    if (h->part[PART_COMPLEX].numeric == NULL) return FLEXMBS_KLU_NOT_FACTORED;
    if (nrhs < 1 || b == NULL) return FLEXMBS_KLU_INVALID;
    if (!klu_zl_solve(h->symbolic, h->part[PART_COMPLEX].numeric, h->n, nrhs, (double *)b,
                      &h->common))
        return code_of(&h->common);
    return FLEXMBS_KLU_OK;
}

/* Statistics of one part (0 real, 1 complex): counts of fresh and reused
 * factorisations, rcond of the latest and rgrowth of the latest fresh one,
 * whether one is alive. */
int flexmbs_klu_stats(const void *handle, int part, int64_t *nfactor, int64_t *nrefactor,
                      double *rcond, double *rgrowth, int *factored)
{
    const flexmbs_klu *h = handle;
    *nfactor = 0;
    *nrefactor = 0;
    *rcond = 0.0;
    *rgrowth = 0.0;
    *factored = 0;
    if (h == NULL) return FLEXMBS_KLU_NOT_ANALYSED;
    if (part != PART_REAL && part != PART_COMPLEX) return FLEXMBS_KLU_INVALID;
    const numeric_part *p = &h->part[part];
    *nfactor = p->nfactor;
    *nrefactor = p->nrefactor;
    *rcond = p->rcond;
    *rgrowth = p->rgrowth;
    *factored = p->numeric != NULL;
    return FLEXMBS_KLU_OK;
}

/* The threshold of the refactor check, for documentation and tests. */
double flexmbs_klu_refactor_degrade_ratio(void)
{
    return refactor_degrade_ratio;
}
