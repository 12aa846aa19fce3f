/* flexmbs: why IDA's nonlinear solves fail, counted by cause.
 *
 * IDA counts the step attempts whose nonlinear solve failed
 * (IDAGetNumStepSolveFails) but not why. This shim gives IDA SUNDIALS' own
 * Newton solver (SUNNonlinSol_Newton, as IDA would create it) wrapped in an
 * observer: every call passes straight through, unchanged, and the observer
 * watches the results of IDA's residual, linear-solver setup and solve and
 * convergence test. When a solve fails, the last thing that failed in its
 * last pass decides the cause:
 *
 *   the residual (or, through flexmbs_ida_observer_refused, a Jacobian
 *   callback) refused                          -> FLEXMBS_IDA_REFUSED
 *   the linear solver's setup or solve failed  -> FLEXMBS_IDA_SINGULAR
 *   the convergence test saw divergence        -> FLEXMBS_IDA_DIVERGED
 *   the iteration limit was reached            -> FLEXMBS_IDA_SLOW
 *
 * Each failing solve is one failed step (IDA's ncfn), so the four counts
 * add up to IDAGetNumStepSolveFails. The Fortran module flexmbs_dae_ida
 * repeats the cause numbers as named constants.
 */
#include <stdlib.h>
#include <ida/ida.h>
#include <sundials/sundials_nonlinearsolver.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

enum {
    FLEXMBS_IDA_NONE = 0,
    FLEXMBS_IDA_REFUSED = 1,
    FLEXMBS_IDA_SINGULAR = 2,
    FLEXMBS_IDA_DIVERGED = 3,
    FLEXMBS_IDA_SLOW = 4,
    FLEXMBS_IDA_CAUSES = 4
};

typedef struct {
    SUNNonlinearSolver inner;      /* SUNDIALS' Newton solver doing the work */
    SUNNonlinSolSysFn sys;         /* IDA's functions, called through */
    SUNNonlinSolLSetupFn lsetup;
    SUNNonlinSolLSolveFn lsolve;
    SUNNonlinSolConvTestFn ctest;
    void *ctest_data;
    void *mem;                     /* IDA's memory during a solve */
    int last;                      /* what failed last in this solve's pass */
    long counts[FLEXMBS_IDA_CAUSES + 1];
} observer_t;

static observer_t *observer_of(SUNNonlinearSolver nls) { return (observer_t *)nls->content; }

static int observed_sys(N_Vector y, N_Vector f, void *data)
{
    observer_t *o = (observer_t *)data;
    int flag = o->sys(y, f, o->mem);
    if (flag != 0) o->last = FLEXMBS_IDA_REFUSED;
    return flag;
}

static int observed_lsetup(booleantype jbad, booleantype *jcur, void *data)
{
    observer_t *o = (observer_t *)data;
    int flag;
    /* a new pass: what failed before is superseded */
    o->last = FLEXMBS_IDA_NONE;
    flag = o->lsetup(jbad, jcur, o->mem);
    if (flag != 0 && o->last != FLEXMBS_IDA_REFUSED) o->last = FLEXMBS_IDA_SINGULAR;
    return flag;
}

static int observed_lsolve(N_Vector b, void *data)
{
    observer_t *o = (observer_t *)data;
    int flag = o->lsolve(b, o->mem);
    if (flag != 0 && o->last != FLEXMBS_IDA_REFUSED) o->last = FLEXMBS_IDA_SINGULAR;
    return flag;
}

static int observed_ctest(SUNNonlinearSolver nls, N_Vector y, N_Vector del, realtype tol,
                          N_Vector ewt, void *data)
{
    observer_t *o = (observer_t *)data;
    int flag = o->ctest(nls, y, del, tol, ewt, o->ctest_data);
    if (flag == SUN_NLS_CONV_RECVR) o->last = FLEXMBS_IDA_DIVERGED;
    return flag;
}

static SUNNonlinearSolver_Type observer_type(SUNNonlinearSolver nls)
{
    return SUNNonlinSolGetType(observer_of(nls)->inner);
}

static int observer_initialize(SUNNonlinearSolver nls)
{
    return SUNNonlinSolInitialize(observer_of(nls)->inner);
}

static int observer_solve(SUNNonlinearSolver nls, N_Vector y0, N_Vector ycor, N_Vector w,
                          realtype tol, booleantype call_lsetup, void *mem)
{
    observer_t *o = observer_of(nls);
    int flag;
    o->mem = mem;
    o->last = FLEXMBS_IDA_NONE;
    flag = SUNNonlinSolSolve(o->inner, y0, ycor, w, tol, call_lsetup, o);
    if (flag != SUN_NLS_SUCCESS) {
        /* nothing observed failed: Newton stopped at its iteration limit */
        o->counts[o->last == FLEXMBS_IDA_NONE ? FLEXMBS_IDA_SLOW : o->last]++;
    }
    return flag;
}

static int observer_free(SUNNonlinearSolver nls)
{
    if (nls == NULL) return SUN_NLS_SUCCESS;
    if (nls->content != NULL) {
        SUNNonlinSolFree(observer_of(nls)->inner);
        free(nls->content);
        nls->content = NULL;
    }
    SUNNonlinSolFreeEmpty(nls);
    return SUN_NLS_SUCCESS;
}

static int observer_set_sys(SUNNonlinearSolver nls, SUNNonlinSolSysFn fn)
{
    observer_t *o = observer_of(nls);
    o->sys = fn;
    return SUNNonlinSolSetSysFn(o->inner, fn ? observed_sys : NULL);
}

static int observer_set_lsetup(SUNNonlinearSolver nls, SUNNonlinSolLSetupFn fn)
{
    observer_t *o = observer_of(nls);
    o->lsetup = fn;
    return SUNNonlinSolSetLSetupFn(o->inner, fn ? observed_lsetup : NULL);
}

static int observer_set_lsolve(SUNNonlinearSolver nls, SUNNonlinSolLSolveFn fn)
{
    observer_t *o = observer_of(nls);
    o->lsolve = fn;
    return SUNNonlinSolSetLSolveFn(o->inner, fn ? observed_lsolve : NULL);
}

static int observer_set_ctest(SUNNonlinearSolver nls, SUNNonlinSolConvTestFn fn, void *data)
{
    observer_t *o = observer_of(nls);
    o->ctest = fn;
    o->ctest_data = data;
    return SUNNonlinSolSetConvTestFn(o->inner, fn ? observed_ctest : NULL, o);
}

static int observer_set_max_iters(SUNNonlinearSolver nls, int maxiters)
{
    return SUNNonlinSolSetMaxIters(observer_of(nls)->inner, maxiters);
}

static int observer_num_iters(SUNNonlinearSolver nls, long int *niters)
{
    return SUNNonlinSolGetNumIters(observer_of(nls)->inner, niters);
}

static int observer_cur_iter(SUNNonlinearSolver nls, int *iter)
{
    return SUNNonlinSolGetCurIter(observer_of(nls)->inner, iter);
}

static int observer_num_conv_fails(SUNNonlinearSolver nls, long int *nconvfails)
{
    return SUNNonlinSolGetNumConvFails(observer_of(nls)->inner, nconvfails);
}

/* Give IDA (after IDAInit) the observed Newton solver; NULL on failure.
 * `y` is IDA's solution vector (the template). Free with
 * flexmbs_ida_observer_free after IDAFree. */
SUNNonlinearSolver flexmbs_ida_observer_attach(void *ida_mem, N_Vector y, SUNContext ctx)
{
    SUNNonlinearSolver nls = SUNNonlinSolNewEmpty(ctx);
    observer_t *o;
    if (nls == NULL) return NULL;
    o = (observer_t *)calloc(1, sizeof(observer_t));
    if (o == NULL) {
        SUNNonlinSolFreeEmpty(nls);
        return NULL;
    }
    nls->content = o;
    o->inner = SUNNonlinSol_Newton(y, ctx);
    if (o->inner == NULL) {
        observer_free(nls);
        return NULL;
    }
    nls->ops->gettype = observer_type;
    nls->ops->initialize = observer_initialize;
    nls->ops->solve = observer_solve;
    nls->ops->free = observer_free;
    nls->ops->setsysfn = observer_set_sys;
    nls->ops->setlsetupfn = observer_set_lsetup;
    nls->ops->setlsolvefn = observer_set_lsolve;
    nls->ops->setctestfn = observer_set_ctest;
    nls->ops->setmaxiters = observer_set_max_iters;
    nls->ops->getnumiters = observer_num_iters;
    nls->ops->getcuriter = observer_cur_iter;
    nls->ops->getnumconvfails = observer_num_conv_fails;
    if (IDASetNonlinearSolver(ida_mem, nls) != IDA_SUCCESS) {
        observer_free(nls);
        return NULL;
    }
    return nls;
}

/* A callback of the model refused (a Jacobian that failed inside the
 * linear solver's setup, a residual of IDA's difference quotients). */
void flexmbs_ida_observer_refused(SUNNonlinearSolver nls)
{
    if (nls != NULL) observer_of(nls)->last = FLEXMBS_IDA_REFUSED;
}

/* counts[0..3]: failed solves refused, singular, diverged, slow. */
void flexmbs_ida_observer_counts(SUNNonlinearSolver nls, long counts[FLEXMBS_IDA_CAUSES])
{
    int c;
    for (c = 0; c < FLEXMBS_IDA_CAUSES; c++)
        counts[c] = nls != NULL ? observer_of(nls)->counts[c + 1] : 0;
}

void flexmbs_ida_observer_free(SUNNonlinearSolver nls) { observer_free(nls); }
