/* kergs solver: the per-step problem W r - v = -v^d with the contact law (eq. 1, 2), solved by a type
   chosen by name (-solver_type), the way PETSc chooses a KSP. This file holds what the types share:
   the registry, the options, which contacts are active, and the loop of sweeps with its stopping test. */
#include <kergs/private/solverimpl.h>
#include <math.h>

const char *const KergsCriteria[] = {"quad", "maxm", "natural", "KergsCriterion", "KERGS_CRITERION_", NULL};

/* indexed from KERGS_SOLVER_REASON_MIN, as PETSc's KSPConvergedReasons */
static const char *const ReasonNamesShifted[] = {"DIVERGED_NANORINF", "DIVERGED_KERNEL",   "DIVERGED_LINEAR_SOLVE", "DIVERGED_INFEASIBLE",
                                                 "DIVERGED_RESIDUAL", "DIVERGED_MAX_IT",   "CONVERGED_ITERATING",   "CONVERGED_QUAD",
                                                 "CONVERGED_MAXM",    "CONVERGED_NATURAL", "CONVERGED_NO_CONTACTS"};
const char *const       *KergsSolverConvergedReasons = ReasonNamesShifted - KERGS_SOLVER_REASON_MIN;

const char *KergsSolverConvergedReasonDescription(KergsSolverConvergedReason reason)
{
  switch (reason) {
  case KERGS_SOLVER_DIVERGED_NANORINF:
    return "the impulses or their residual are not finite";
  case KERGS_SOLVER_DIVERGED_KERNEL:
    return "the kernel projector misses ker H_f (-kernel_check_tol; the step's kernel_check_error in /stats); try another "
           "-kernel_null_pivot_tol";
  case KERGS_SOLVER_DIVERGED_LINEAR_SOLVE:
    return "a linear solve failed";
  case KERGS_SOLVER_DIVERGED_INFEASIBLE:
    return "the step's problem has no solution";
  case KERGS_SOLVER_DIVERGED_RESIDUAL:
    return "the criterion was met but the original problem is not solved (-solver_residual_tol, -solver_velocity_tol)";
  case KERGS_SOLVER_DIVERGED_MAX_IT:
    return "-solver_max_it reached";
  case KERGS_SOLVER_CONVERGED_ITERATING:
    return "still iterating";
  case KERGS_SOLVER_CONVERGED_QUAD:
  case KERGS_SOLVER_CONVERGED_MAXM:
  case KERGS_SOLVER_CONVERGED_NATURAL:
    return "-solver_tol met";
  case KERGS_SOLVER_CONVERGED_NO_CONTACTS:
    return "no contact";
  }
  return "unknown reason";
}

static PetscFunctionList SolverList = NULL;
#define KERGS_SOLVER_MAXTYPES 16
static char     SolverNames[KERGS_SOLVER_MAXTYPES][64]; /* the registered names, in order, for -help */
static PetscInt SolverNumTypes = 0;

PetscErrorCode KergsSolverRegister(const char name[], PetscErrorCode (*create)(KergsSolver))
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListAdd(&SolverList, name, create));
  if (SolverNumTypes < KERGS_SOLVER_MAXTYPES) PetscCall(PetscStrncpy(SolverNames[SolverNumTypes++], name, sizeof(SolverNames[0])));
  PetscFunctionReturn(0);
}

/* Forget the registry at PetscFinalize (PETSc may be initialized again). */
static PetscErrorCode SolverFinalizePackage(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListDestroy(&SolverList));
  SolverNumTypes = 0;
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverRegisterAll(void)
{
  PetscFunctionBeginUser;
  if (SolverList) PetscFunctionReturn(0);
  PetscCall(PetscRegisterFinalize(SolverFinalizePackage));
  PetscCall(KergsSolverRegister(KERGS_SOLVER_NLGS, KergsSolverCreate_NLGS));
  PetscCall(KergsSolverRegister(KERGS_SOLVER_NLKERGS, KergsSolverCreate_NLKerGS));
  PetscCall(KergsSolverRegister(KERGS_SOLVER_NLGSJAC, KergsSolverCreate_NLGSJac));
  PetscCall(KergsSolverRegister(KERGS_SOLVER_NEWTON, KergsSolverCreate_Newton));
  PetscCall(KergsSolverRegister(KERGS_SOLVER_TRESCA, KergsSolverCreate_Tresca));
  PetscCall(KergsSolverRegister(KERGS_SOLVER_SNESVI, KergsSolverCreate_SnesVI));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate(MPI_Comm comm, KergsSolver *solver)
{
  KergsSolver s;

  PetscFunctionBeginUser;
  PetscCall(SolverRegisterAll());
  PetscCall(PetscNew(&s));
  s->comm = comm;
  /* defaults that give the right answer (docs/solver.md, "Defaults"): a type that sets none of its own (nlgs, the
     regularised types) iterates until the natural residual is 1e-6, without the paper's cap of 150 sweeps, which left
     18 of 20 confine500 steps unconverged with wall forces 91 % off (docs/tradeoff.md); a step counts as solved at a
     natural residual of 1e-6 (the paper's scenes set the paper's settings themselves, cases/confine5.opts) */
  s->max_it           = 10000;
  s->tol              = 1e-6;
  s->residual_tol     = 1e-6;
  s->infeasible_ratio = 1e4;
  s->velocity_tol     = 1e-2;
  s->shifted_id       = -1; /* no v^d holds gap offsets yet */
  s->criterion        = KERGS_CRITERION_NATURAL;
  PetscCall(KergsSweepCreate(comm, &s->sweep));
  *solver = s;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverSetType(KergsSolver s, KergsSolverType type)
{
  PetscErrorCode (*create)(KergsSolver);

  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListFind(SolverList, type, &create));
  PetscCheck(create, s->comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "Unknown -solver_type %s (see -help for the registered types)", type);
  if (s->ops.destroy) PetscCall((*s->ops.destroy)(s));
  PetscCall(PetscMemzero(&s->ops, sizeof(s->ops)));
  s->data                 = NULL;
  s->needs_H              = PETSC_FALSE;
  s->needs_full_W         = PETSC_FALSE;
  s->needs_both_triangles = PETSC_FALSE;
  s->fixed_criterion      = PETSC_FALSE;
  s->iteration_name       = "sweeps";
  PetscCall(PetscStrncpy(s->type, type, sizeof(s->type)));
  PetscCall((*create)(s));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverSetFromOptions(KergsSolver s)
{
  char      type[64] = KERGS_SOLVER_NEWTON; /* the cheapest type converging on every step (docs/tradeoff.md) */
  PetscBool set;

  PetscFunctionBeginUser;
  if (s->type[0]) PetscCall(PetscStrncpy(type, s->type, sizeof(type)));
  PetscOptionsBegin(s->comm, s->prefix, "Contact solver options", NULL);
  PetscCall(PetscOptionsFList("-solver_type", "Solver of the per-step contact problem", "KergsSolverSetType", SolverList, type, type,
                              sizeof(type), &set));
  /* the type first: it may set its own defaults of the common options, which the options then override */
  if (!s->ops.solve || set) PetscCall(KergsSolverSetType(s, type));
  PetscCall(
      KergsOptionsInt(PetscOptionsObject, "-solver_max_it",
                      "Maximum number of iterations per step: sweeps (NLGS, NLGS-Jac: 10000; the paper caps at 150), Newton steps (1000)",
                      "", s->max_it, &s->max_it, NULL));
  PetscCall(PetscOptionsReal("-solver_tol", "Tolerance of the convergence criterion", "", s->tol, &s->tol, NULL));
  PetscCall(PetscOptionsReal(
      "-solver_residual_tol",
      "A step converges only if the natural residual of the original problem is at most this (whatever the type's own criterion)", "",
      s->residual_tol, &s->residual_tol, NULL));
  PetscCall(PetscOptionsReal("-solver_velocity_tol",
                             "... and the law's worst violation in velocity, relative to the problem's largest velocity, at most this", "",
                             s->velocity_tol, &s->velocity_tol, NULL));
  PetscCall(PetscOptionsEnum("-solver_criterion",
                             "Convergence criterion: quad (W-weighted relative change of r, LMGC90 Quad), maxm (largest change over mean, "
                             "LMGC90 Maxm), natural (natural-map residual, Siconos)",
                             "", KergsCriteria, (PetscEnum)s->criterion, (PetscEnum *)&s->criterion, NULL));
  PetscCall(PetscOptionsReal("-solver_infeasible_ratio",
                             "A failed step is infeasible when any solution would need impulses this many times the problem's scale "
                             "(sqrt(active contacts) times its largest free velocity over its mean W_nn), proved by a compressive "
                             "self-equilibrated network that the free velocities close (inf: never)",
                             "KergsSolverSolve", s->infeasible_ratio, &s->infeasible_ratio, NULL));
  PetscCall(KergsSolverMonitorSetFromOptions(PetscOptionsObject, s));
  PetscCall(PetscViewerDestroy(&s->reason_viewer));
  PetscCall(PetscOptionsViewer("-solver_converged_reason", "Print why each solve stopped (KergsSolverConvergedReason)", "KergsSolverSolve",
                               &s->reason_viewer, &s->reason_format, NULL));
  PetscCall(PetscOptionsName("-solver_view",
                             "Print the solver's settings at the start of the run (PETSc viewer syntax: ::ascii_info_detail, ascii:FILE)",
                             "KergsSolverView", NULL));
  if (s->ops.setfromoptions) PetscCall((*s->ops.setfromoptions)(PetscOptionsObject, s));
  PetscOptionsEnd();
  if (s->fixed_criterion) s->criterion = KERGS_CRITERION_NATURAL; /* -solver_criterion does not apply (docs/solver.md) */
  PetscCheck(s->max_it >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_max_it %" PetscInt_FMT " must be at least 1", s->max_it);
  PetscCheck(s->tol > 0 && PetscIsNormalReal(s->tol), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_tol %g must be a positive number",
             (double)s->tol);
  PetscCheck(s->residual_tol > 0 && PetscIsNormalReal(s->residual_tol), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_residual_tol %g must be a positive number", (double)s->residual_tol);
  PetscCheck(s->infeasible_ratio > 0 && !PetscIsNanReal(s->infeasible_ratio), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_infeasible_ratio %g must be positive (inf: never infeasible)", (double)s->infeasible_ratio);
  PetscCheck(s->velocity_tol > 0 && PetscIsNormalReal(s->velocity_tol), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_velocity_tol %g must be a positive number", (double)s->velocity_tol);
  PetscFunctionReturn(0);
}

/* Active contacts (eq. 2, KergsContactIsActive: the same decision as the assembly of W over active pairs). An
   inactive contact's impulse is 0 at the solution: its warm start is set to 0 too, so that the first sweep does not
   feel an impulse the law is about to cancel (and W over active pairs gives the same iterates as the whole W).
   The predictive gap rule writes Signorini on the end-of-step gap, v_n >= -g~/(theta dt) for g~ > 0: its offset is added
   here, once per step, to v^d's normal component, so that every type, its law, its natural residual and the FCLib
   export solve the same problem, u = W r + v^d + offset with 0 <= u_n _|_ r_n >= 0. */
PetscErrorCode KergsSolverSetUpSweep(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  PetscScalar   *r, *q;
  KergsContact  *c;
  KergsActivity  act;
  KergsDofLayout layout;
  PetscInt       n, nc;
  Vec            rv, vd;
  Mat            W;
  PetscInt64     id;
  PetscBool      shifted;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(contacts, &n, &c));
  PetscCall(KergsContactsGetActivity(contacts, scene, &act));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &rv, NULL, &vd));
  PetscCall(KergsOperatorsGetW(ops, &W, NULL));
  nc = layout.ncomp;
  if (n > s->nalloc) {
    PetscCall(PetscFree3(s->mu, s->active, s->gapvel));
    s->nalloc = PetscMax(n, 2 * s->nalloc);
    PetscCall(PetscMalloc3(s->nalloc, &s->mu, s->nalloc, &s->active, s->nalloc, &s->gapvel));
  }
  PetscCall(PetscObjectGetId((PetscObject)vd, &id));
  shifted = (PetscBool)(id == s->shifted_id); /* each assembly creates a new v^d (KergsOperatorsAssembleH) */
  PetscCall(VecGetArray(rv, &r));
  PetscCall(VecGetArray(vd, &q));
  for (PetscInt k = 0; k < n; k++) {
    s->active[k] = KergsContactIsActive(&act, &c[k]);
    s->mu[k]     = c[k].mu;
    s->gapvel[k] = s->active[k] ? KergsContactGapVelocity(&act, &c[k]) : 0.0;
    if (!shifted) q[k * nc] += s->gapvel[k];
    if (!s->active[k])
      for (PetscInt j = 0; j < nc; j++) r[k * nc + j] = 0.0;
  }
  PetscCall(VecRestoreArray(vd, &q));
  PetscCall(VecRestoreArray(rv, &r));
  s->shifted_id = id;
  PetscCall(KergsSweepSetUp(s->sweep, W, nc, s->mu, s->active));
  PetscCall(KergsSweepSetGapVelocities(s->sweep, act.rule == KERGS_GAP_PREDICTIVE ? s->gapvel : NULL));
  PetscFunctionReturn(0);
}

/* For the types that work on the active contacts only (tresca, snesvi, newton's De Saxce start): their components as an
   IS of global indices into the contact vectors (W's rows), and W over them as AIJ (TAO's and SNESVI's active-set
   methods extract submatrices on arbitrary component subsets). */
PetscErrorCode KergsSolverActiveSubmatrix(KergsSolver s, Mat W, PetscInt n, PetscInt nc, IS *is, Mat *Wa)
{
  PetscInt rstart, m = 0, *idx;
  Mat      Wsub;

  PetscFunctionBeginUser;
  PetscCall(MatGetOwnershipRange(W, &rstart, NULL));
  PetscCall(PetscMalloc1(n * nc + 1, &idx));
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a])
      for (PetscInt j = 0; j < nc; j++) idx[m++] = rstart + a * nc + j;
  PetscCall(ISCreateGeneral(s->comm, m, idx, PETSC_OWN_POINTER, is));
  PetscCall(MatCreateSubMatrix(W, *is, *is, MAT_INITIAL_MATRIX, &Wsub));
  PetscCall(MatConvert(Wsub, MATAIJ, MAT_INITIAL_MATRIX, Wa));
  PetscCall(MatDestroy(&Wsub));
  PetscFunctionReturn(0);
}

/* Sweeps until the chosen criterion is below tol or max_it sweeps were done (Algorithm 2's loop).
   At exit the natural-map residual is recomputed from r, whatever the criterion. */
PetscErrorCode KergsSolverIterate(KergsSolver s, KergsOperators ops, PetscReal *extra, const PetscReal *Wdiag, KergsSolveStats *stats)
{
  KergsSweepMeasures m;
  PetscReal          value = 0.0;
  PetscLogDouble     t0, t1;
  PetscInt           nglobal;
  Vec                r, v, vd;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t0));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, &v, &vd));
  PetscCall(VecGetSize(r, &nglobal));
  stats->iterations = 0;
  stats->reason     = KERGS_SOLVER_CONVERGED_NO_CONTACTS;
  if (nglobal > 0) {
    stats->reason = KERGS_SOLVER_DIVERGED_MAX_IT;
    for (PetscInt k = 1; k <= s->max_it; k++) {
      if (s->ops.presweep) PetscCall((*s->ops.presweep)(s, ops, extra));
      PetscCall(KergsSweepRun(s->iterate_sweep ? s->iterate_sweep : s->sweep, r, vd, extra, Wdiag, &m));
      stats->iterations = k;
      switch (s->criterion) {
      case KERGS_CRITERION_QUAD:
        value = m.quad;
        break;
      case KERGS_CRITERION_MAXM:
        value = m.maxm;
        break;
      case KERGS_CRITERION_NATURAL:
        PetscCall(KergsSweepNaturalResidual(s->sweep, r, vd, v, &value));
        break;
      }
      /* the natural residual of the original problem is known here only when it is the criterion (s->sweep is on W) */
      PetscCall(KergsSolverMonitor(s, k, value, s->criterion == KERGS_CRITERION_NATURAL ? value : (PetscReal)NAN));
      if (value < s->tol) {
        PetscCall(KergsSolverCriterionMet(s, stats));
        break;
      }
    }
  }
  PetscCall(PetscTime(&t1));
  stats->sweep_seconds = t1 - t0;
  {
    PetscLogDouble compute;
    PetscCall(KergsSweepGetComputeSeconds(s->iterate_sweep ? s->iterate_sweep : s->sweep, &compute));
    stats->compute_seconds = compute;
  }
  stats->criterion = value;
  PetscFunctionReturn(0);
}

/* For the types: the criterion fell below -solver_tol (the reason names the criterion; a step without contacts keeps
   its own). */
PetscErrorCode KergsSolverCriterionMet(KergsSolver s, KergsSolveStats *stats)
{
  static const KergsSolverConvergedReason by_criterion[] = {KERGS_SOLVER_CONVERGED_QUAD, KERGS_SOLVER_CONVERGED_MAXM,
                                                            KERGS_SOLVER_CONVERGED_NATURAL};

  PetscFunctionBeginUser;
  if (stats->reason != KERGS_SOLVER_CONVERGED_NO_CONTACTS) stats->reason = by_criterion[s->criterion];
  PetscFunctionReturn(0);
}

/* Whatever the type and its own criterion, a step converges only if r solves the original problem (W, not a
   regularised one): natural residual and velocity error recomputed from r (the sweep on W holds the active set). */
static PetscErrorCode DecideConvergence(KergsSolver s, KergsOperators ops, KergsSolveStats *stats)
{
  KergsResiduals res;
  Vec            r, v, vd;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, &v, &vd));
  PetscCall(KergsSweepResiduals(s->sweep, r, vd, v, &res));
  stats->residual       = res.natural;
  stats->velocity_error = res.velocity;
  if (PetscIsInfOrNanReal(res.natural) || PetscIsInfOrNanReal(res.velocity))
    stats->reason = KERGS_SOLVER_DIVERGED_NANORINF;
  else if (stats->reason > 0 && !(res.natural <= s->residual_tol && res.velocity <= s->velocity_tol))
    stats->reason = KERGS_SOLVER_DIVERGED_RESIDUAL;
  PetscFunctionReturn(0);
}

/* A Farkas certificate of infeasibility from the impulses of a failed solve. On a problem without a solution every
   type's impulses run away along a compressive self-equilibrated network: w >= 0 on the normal components of the
   active contacts with W w ~ 0 that the free velocities close, q = w . v^d_n < 0. For any solution r (u = W r + v^d,
   u_n >= 0) 0 <= w . u = (W w) . r + q, so that |r|_2 >= -q / |W w|_2: no solution has impulses below that bound,
   whatever the friction. The step is infeasible when the bound exceeds -solver_infeasible_ratio times the problem's
   impulse scale: sqrt(active contacts) times the impulse that stops its fastest contact (largest free velocity over
   the mean W_nn), the size of |r|_2 when every contact carries that impulse. Measured on confine5_straight: 3.3e4
   to 1.7e6 times for newton, tresca and snesvi on step 1; capped NLGS leaves too little evidence on its first steps (7
   to 1,700 times: DIVERGED_MAX_IT); feasible steps that capped NLGS fails on, confine500's: at most 0.3. The weights of w, largest 1,
   are kept per local contact in s->infeasible (KergsSolverGetInfeasibleNetwork). */
static PetscErrorCode DetectInfeasible(KergsSolver s, KergsOperators ops, KergsSolveStats *stats, PetscReal *ratio)
{
  const PetscScalar *r, *vd, *g, *w;
  PetscScalar       *wl;
  PetscReal         *diag, wmax = 0.0, bound, scale;
  PetscReal          sums[4] = {0, 0, 0, 0}, vmax = 0.0; /* active contacts, q = w . v^d_n, |W w|^2, sum of their W_nn */
  KergsDofLayout     layout;
  PetscInt           n, nc;
  Vec                rv, vdv, wv, gv;
  Mat                W;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &rv, NULL, &vdv));
  PetscCall(KergsOperatorsGetW(ops, &W, NULL));
  PetscCall(VecGetLocalSize(rv, &n));
  nc = layout.ncomp;
  n /= nc;
  /* w: the normal impulses of the active contacts, compressive part, scaled to a largest weight of 1 */
  PetscCall(VecDuplicate(rv, &wv));
  PetscCall(VecGetArrayRead(rv, &r));
  PetscCall(VecGetArray(wv, &wl));
  for (PetscInt k = 0; k < n * nc; k++) wl[k] = 0.0;
  for (PetscInt a = 0; a < n; a++) {
    if (s->active[a]) wl[a * nc] = PetscMax(PetscRealPart(r[a * nc]), 0.0);
    wmax = PetscMax(wmax, PetscRealPart(wl[a * nc]));
  }
  PetscCall(VecRestoreArrayRead(rv, &r));
  PetscCall(VecRestoreArray(wv, &wl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &wmax, 1, MPIU_REAL, MPIU_MAX, s->comm));
  if (!(wmax > 0 && PetscIsNormalReal(wmax))) {
    PetscCall(VecDestroy(&wv));
    PetscFunctionReturn(0);
  }
  PetscCall(VecScale(wv, 1.0 / wmax));
  PetscCall(VecDuplicate(rv, &gv));
  PetscCall(MatMult(W, wv, gv));
  PetscCall(PetscMalloc1(n * nc * nc, &diag));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, diag));
  PetscCall(VecGetArrayRead(wv, &w));
  PetscCall(VecGetArrayRead(gv, &g));
  PetscCall(VecGetArrayRead(vdv, &vd));
  for (PetscInt a = 0; a < n; a++) {
    if (!s->active[a]) continue;
    sums[0] += 1.0;
    sums[1] += PetscRealPart(w[a * nc]) * PetscRealPart(vd[a * nc]);
    for (PetscInt c = 0; c < nc; c++) sums[2] += PetscSqr(PetscRealPart(g[a * nc + c]));
    sums[3] += diag[a * nc * nc]; /* W_nn */
    vmax = PetscMax(vmax, PetscAbsReal(PetscRealPart(vd[a * nc])));
  }
  PetscCall(VecRestoreArrayRead(vdv, &vd));
  PetscCall(VecRestoreArrayRead(gv, &g));
  PetscCall(PetscFree(diag));
  PetscCall(VecDestroy(&gv));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 4, MPIU_REAL, MPIU_SUM, s->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &vmax, 1, MPIU_REAL, MPIU_MAX, s->comm));
  scale = sums[3] > 0 ? vmax / (sums[3] / sums[0]) * PetscSqrtReal(sums[0]) : 0.0;
  bound = sums[1] < 0 ? (sums[2] > 0 ? -sums[1] / PetscSqrtReal(sums[2]) : PETSC_INFINITY) : 0.0;
  PetscCall(PetscInfo(NULL, "infeasibility test: w . v^d_n %g, |W w| %g, impulse bound %g, impulse scale %g\n", (double)sums[1],
                      (double)PetscSqrtReal(sums[2]), (double)bound, (double)scale));
  *ratio = scale > 0 ? PetscMin(bound / scale, PETSC_MAX_REAL) : 0.0; /* finite, as every statistic */
  if (scale > 0 && bound > s->infeasible_ratio * scale) {
    stats->reason = KERGS_SOLVER_DIVERGED_INFEASIBLE;
    PetscCall(PetscMalloc1(n, &s->infeasible));
    for (PetscInt a = 0; a < n; a++) s->infeasible[a] = PetscRealPart(w[a * nc]);
  }
  PetscCall(VecRestoreArrayRead(wv, &w));
  PetscCall(VecDestroy(&wv));
  PetscFunctionReturn(0);
}

/* -solver_converged_reason: one line per solve, as -ksp_converged_reason */
static PetscErrorCode ConvergedReasonView(KergsSolver s, const KergsSolveStats *stats)
{
  PetscViewer viewer = s->reason_viewer;

  PetscFunctionBeginUser;
  if (!viewer) PetscFunctionReturn(0);
  PetscCall(PetscViewerPushFormat(viewer, s->reason_format));
  PetscCall(PetscViewerASCIIPrintf(viewer, "Contact %s%ssolve %s due to %s in step %" PetscInt_FMT " after %" PetscInt_FMT " %s: %s\n",
                                   s->prefix ? s->prefix : "", s->prefix ? " " : "", stats->reason > 0 ? "converged" : "did not converge",
                                   KergsSolverConvergedReasons[stats->reason], s->step, stats->iterations, s->iteration_name,
                                   KergsSolverConvergedReasonDescription(stats->reason)));
  PetscCall(PetscViewerPopFormat(viewer));
  PetscFunctionReturn(0);
}

/* The energy the answer's errors put into the step. Over a step the kinetic energy changes by 1/2 (V+ + V-)^T (H r + R^d);
   the contacts' share at the end-of-step velocities u = W r + v^d is 1/2 sum_a r_a . u_a, which the exact law makes
   -1/2 sum_a mu r_n |u_t| (r_n u_n = 0, sliding against friction): anything else is energy created or destroyed by
   the solver's error. Recorded: law_work_error = 1/2 sum_a (|r_n u_n| + |r_t u_t + mu r_n |u_t||) (J), and, as its
   scale, contact_energy = 1/2 r^T W r (J), the kinetic energy the impulses alone would impart. v holds W r + v^d. */
static PetscErrorCode RecordLawWork(KergsSolver s, KergsOperators ops, KergsSolveStats *stats)
{
  const PetscScalar *r, *v, *vd;
  KergsDofLayout     layout;
  PetscReal          sums[2] = {0.0, 0.0};
  PetscInt           n, nc;
  Vec                rv, vv, vdv;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &rv, &vv, &vdv));
  PetscCall(VecGetLocalSize(rv, &n));
  nc = layout.ncomp;
  PetscCall(VecGetArrayRead(rv, &r));
  PetscCall(VecGetArrayRead(vv, &v));
  PetscCall(VecGetArrayRead(vdv, &vd));
  for (PetscInt a = 0; a < n / nc; a++) {
    const PetscReal rn = PetscRealPart(r[a * nc]), un = PetscRealPart(v[a * nc]);
    sums[0] += PetscAbsReal(rn * un);
    if (nc > 1) {
      const PetscReal rt = PetscRealPart(r[a * nc + 1]), ut = PetscRealPart(v[a * nc + 1]);
      sums[0] += PetscAbsReal(rt * ut + s->mu[a] * rn * PetscAbsReal(ut));
    }
    for (PetscInt c = 0; c < nc; c++) sums[1] += PetscRealPart(r[a * nc + c]) * PetscRealPart(v[a * nc + c] - vd[a * nc + c]);
  }
  PetscCall(VecRestoreArrayRead(rv, &r));
  PetscCall(VecRestoreArrayRead(vv, &v));
  PetscCall(VecRestoreArrayRead(vdv, &vd));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 2, MPIU_REAL, MPIU_SUM, s->comm));
  PetscCall(KergsSolveStatsAdd(stats, "law_work_error", 0.5 * sums[0]));
  PetscCall(KergsSolveStatsAdd(stats, "contact_energy", 0.5 * sums[1]));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverSolve(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops, KergsSolveStats *stats)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCheck(s->ops.solve, s->comm, PETSC_ERR_ORDER, "Call KergsSolverSetFromOptions() or KergsSolverSetType() first");
  PetscCall(PetscMemzero(stats, sizeof(*stats)));
  PetscCall(PetscLogEventBegin(KERGS_Solve, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  s->solve_start = t0;
  s->held        = PETSC_FALSE;
  if (s->ops.setup) PetscCall((*s->ops.setup)(s, scene, contacts, ops));
  PetscCall((*s->ops.solve)(s, scene, contacts, ops, stats));
  PetscCall(DecideConvergence(s, ops, stats));
  PetscCall(PetscFree(s->infeasible));
  {
    PetscReal ratio = 0.0; /* 0: no failed solve to test */
    if (stats->reason < 0 && stats->reason != KERGS_SOLVER_DIVERGED_NANORINF) PetscCall(DetectInfeasible(s, ops, stats, &ratio));
    PetscCall(KergsSolveStatsAdd(stats, "infeasible_impulse_ratio", ratio));
  }
  PetscCall(KergsSolverMonitorFlush(s, stats->residual));
  PetscCall(RecordLawWork(s, ops, stats));
  if (s->ops.stats) PetscCall((*s->ops.stats)(s, stats));
  PetscCall(ConvergedReasonView(s, stats));
  /* the sweep lives for one solve: drop its reference to this step's W, so that W is freed at the start of the
     next assembly instead of coexisting with the next step's W (the peak memory) */
  PetscCall(KergsSweepReset(s->sweep));
  PetscCall(PetscTime(&t1));
  stats->seconds = t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_Solve, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverView(KergsSolver s, PetscViewer viewer)
{
  PetscViewerFormat format;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerGetFormat(viewer, &format));
  PetscCall(PetscViewerASCIIPrintf(viewer, "Contact solver%s%s: %s, at most %" PetscInt_FMT " %s, criterion %s < %g\n",
                                   s->prefix ? " " : "", s->prefix ? s->prefix : "", s->type, s->max_it, s->iteration_name,
                                   KergsCriteria[s->criterion], (double)s->tol));
  if (format == PETSC_VIEWER_ASCII_INFO_DETAIL)
    PetscCall(PetscViewerASCIIPrintf(viewer, "  converged: natural residual <= %g and relative velocity error <= %g\n",
                                     (double)s->residual_tol, (double)s->velocity_tol));
  if (s->ops.view) {
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall((*s->ops.view)(s, viewer));
    PetscCall(PetscViewerASCIIPopTab(viewer));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverViewAdapter(void *s, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSolverView((KergsSolver)s, viewer));
  PetscFunctionReturn(0);
}

/* name (with the solver's prefix) given, as -solver_view [viewer]: view the solver there. Collective. */
PetscErrorCode KergsSolverViewFromOptions(KergsSolver s, const char name[])
{
  PetscFunctionBeginUser;
  PetscCall(KergsViewFromOptions(s->comm, s->prefix, name, SolverViewAdapter, s));
  PetscFunctionReturn(0);
}

/* As KSPSetOptionsPrefix: every option of the solver, its type, kernel, predictor and inner PETSc solvers is then read
   as -<prefix>solver_..., so that two solvers of one program take different options. Before KergsSolverSetFromOptions. */
PetscErrorCode KergsSolverSetOptionsPrefix(KergsSolver s, const char prefix[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(s->prefix));
  if (prefix && prefix[0]) {
    PetscCheck(prefix[0] != '-', s->comm, PETSC_ERR_ARG_WRONG, "Options prefix %s must not start with a hyphen", prefix);
    PetscCall(PetscStrallocpy(prefix, &s->prefix));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverGetOptionsPrefix(KergsSolver s, const char *prefix[])
{
  PetscFunctionBeginUser;
  *prefix = s->prefix;
  PetscFunctionReturn(0);
}

/* The prefix of an inner object's options: the solver's prefix, then `inner` ("solver_", "solver_tresca_"). */
PetscErrorCode KergsSolverInnerPrefix(KergsSolver s, const char inner[], char prefix[], size_t len)
{
  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(prefix, len, "%s%s", s->prefix ? s->prefix : "", inner));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverDestroy(KergsSolver *s)
{
  PetscFunctionBeginUser;
  if (!*s) PetscFunctionReturn(0);
  if ((*s)->ops.destroy) PetscCall((*(*s)->ops.destroy)(*s));
  PetscCall(KergsSolverMonitorCancel(*s));
  PetscCall(PetscViewerDestroy(&(*s)->reason_viewer));
  PetscCall(PetscFree((*s)->infeasible));
  PetscCall(PetscFree((*s)->prefix));
  PetscCall(KergsSweepDestroy(&(*s)->sweep));
  PetscCall(PetscFree3((*s)->mu, (*s)->active, (*s)->gapvel));
  PetscCall(PetscFree(*s));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverPrintHelpAllTypes(MPI_Comm comm)
{
  PetscFunctionBeginUser;
  PetscCall(SolverRegisterAll());
  for (PetscInt t = 0; t < SolverNumTypes; t++) {
    KergsSolver s;
    PetscCall(KergsSolverCreate(comm, &s));
    PetscCall(KergsSolverSetType(s, SolverNames[t]));
    if (s->ops.setfromoptions) {
      char title[64];
      /* one title per type: PETSc prints the help of a (prefix, title) pair once only */
      PetscCall(PetscSNPrintf(title, sizeof(title), "Contact solver type %s options", SolverNames[t]));
      PetscOptionsBegin(comm, NULL, title, NULL);
      PetscOptionsHeadBegin(PetscOptionsObject, SolverNames[t]);
      PetscCall((*s->ops.setfromoptions)(PetscOptionsObject, s));
      PetscOptionsEnd();
    }
    PetscCall(KergsSolverDestroy(&s));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolveStatsAdd(KergsSolveStats *st, const char name[], PetscReal value)
{
  PetscFunctionBeginUser;
  PetscCheck(st->nextra < KERGS_SOLVE_MAXEXTRA, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KergsSolveStatsAdd: more than %d figures (%s)",
             KERGS_SOLVE_MAXEXTRA, name);
  PetscCall(PetscStrncpy(st->extra[st->nextra].name, name, sizeof(st->extra[0].name)));
  st->extra[st->nextra++].value = value;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolveStatsAddText(KergsSolveStats *st, const char name[], const char value[])
{
  PetscFunctionBeginUser;
  PetscCheck(st->ntext < KERGS_SOLVE_MAXTEXT, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KergsSolveStatsAddText: more than %d texts (%s)",
             KERGS_SOLVE_MAXTEXT, name);
  PetscCall(PetscStrncpy(st->text[st->ntext].name, name, sizeof(st->text[0].name)));
  PetscCall(PetscStrncpy(st->text[st->ntext++].value, value, sizeof(st->text[0].value)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverGetType(KergsSolver s, KergsSolverType *type)
{
  PetscFunctionBeginUser;
  *type = s->type;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverGetInfeasibleNetwork(KergsSolver s, const PetscReal **weights)
{
  PetscFunctionBeginUser;
  *weights = s->infeasible;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverGetActive(KergsSolver s, const PetscBool **active)
{
  PetscFunctionBeginUser;
  *active = s->active;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverNeedsH(KergsSolver s, PetscBool *needs)
{
  PetscFunctionBeginUser;
  *needs = s->needs_H;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverNeedsBothTriangles(KergsSolver s, PetscBool *needs)
{
  PetscFunctionBeginUser;
  *needs = s->needs_both_triangles;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverNeedsFullW(KergsSolver s, PetscBool *needs)
{
  PetscFunctionBeginUser;
  *needs = s->needs_full_W;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverGetTolerances(KergsSolver s, PetscReal *tol, PetscInt *max_it)
{
  PetscFunctionBeginUser;
  if (tol) *tol = s->tol;
  if (max_it) *max_it = s->max_it;
  PetscFunctionReturn(0);
}

/* What -solver_max_it counts, for messages: "sweeps" or "Newton steps". */
PetscErrorCode KergsSolverGetIterationName(KergsSolver s, const char **name)
{
  PetscFunctionBeginUser;
  *name = s->iteration_name;
  PetscFunctionReturn(0);
}
