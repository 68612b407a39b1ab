/* kergs solver type "snesvi": the per-step problem written as a mixed complementarity problem (MCP) with bounds and
   handed to PETSc's variational-inequality Newton solvers: SNESVINEWTONRSLS (reduced-space active set, the default,
   with the l2 line search) or SNESVINEWTONSSLS (semismooth Newton on the Fischer-Burmeister function, with PETSc's
   backtracking), by -solver_snes_type. It is kergs's measure of PETSc's own engine against `newton` (docs/solver.md,
   "PETSc's SNESVI").

   MCP (one per active contact, 2D): unknowns z = (z_n, theta) with z_n >= 0 and -1 <= theta <= 1, the impulse
   r(z) = s (z_n, mu z_n theta), and the function F(z) = (rho / s) u with u = W r(z) + v^d and rho = 1 / W_aa,nn; s (the
   impulse scale), the largest |rho v^d_n| of the step, makes z and F of order one, which SNESVI's absolute tolerances
   on the bounds need. Its solutions are those of the Signorini-Coulomb law: z_n = 0 or u_n = 0, with u_n >= 0;
   theta = -1 (r_t = -mu r_n) where u_t >= 0, theta = 1 where u_t <= 0, u_t = 0 in between (stick). Without friction
   (mu = 0, or one component) theta is fixed at 0 and the MCP is the linear complementarity problem of the normal
   impulses. F is smooth (bilinear in z), with Jacobian diag(rho / s) W T, T = dr/dz = s [[1, 0], [mu theta, mu z_n]]
   per contact, computed as a sparse matrix product; T is singular where z_n = 0 (theta undetermined for an open
   contact) and W is singular in a confined packing, so J is too: J + shift I (-solver_snesvi_shift), and on one rank
   zero pivots shifted too. Inactive contacts are left out (r = 0). Convergence is the natural residual
   of the original problem, the same as every type's (KergsSweepResiduals), tested after every SNES iteration;
   -solver_max_it caps the SNES iterations, and the best iterate is kept when SNES stops on a failure (a failed line
   search may leave a trial point). Everything else is PETSc's: -solver_snes_*, -solver_snes_linesearch_*,
   -solver_ksp_*, -solver_pc_* (default: a direct LU with AMD, PETSc's on one rank, MUMPS on several). */
#include <kergs/private/solverimpl.h>
#include <petscsnes.h>

typedef struct {
  SNES       snes;          /* this step's solver; prefix solver_ */
  char       snestype[64];  /* its type, as the options chose it (SolverSetFromOptions_SnesVI) */
  Mat        Wa;            /* W over the active contacts' components, AIJ */
  Mat        T, J;          /* dr/dz (block diagonal) and the Jacobian diag(row_scale) Wa T */
  IS         is;            /* the active components, global indices of r */
  Vec        z, zbest;      /* the unknowns, and the best iterate of the solve */
  Vec        lower, upper;  /* their bounds */
  Vec        r_active;      /* r(z) */
  Vec        F, vd_active;  /* F(z), and v^d over the active components */
  Vec        row_scale;     /* rho / s per component */
  PetscReal  impulse_scale; /* s: r = s (z_n, mu z_n theta) */
  PetscReal *mu, *rho;      /* per active contact; rho = 1 / W_aa,nn */
  PetscInt   nactive, nc;   /* local active contacts, components per contact */
  Vec        r, v, vd;      /* the operators' contact vectors, during a solve */
  PetscReal  res, best;     /* the natural residual at the last iterate, and the smallest of the solve (at zbest) */
  PetscReal  shift;         /* -solver_snesvi_shift: J + shift I (J's entries are of order 1) */
  /* figures of the last solve */
  PetscInt            its, linear_its, function_evals;
  SNESConvergedReason reason;
} SnesVI;

static PetscErrorCode DestroyStepObjects(SnesVI *vi)
{
  PetscFunctionBeginUser;
  PetscCall(SNESDestroy(&vi->snes));
  PetscCall(MatDestroy(&vi->Wa));
  PetscCall(MatDestroy(&vi->T));
  PetscCall(MatDestroy(&vi->J));
  PetscCall(ISDestroy(&vi->is));
  PetscCall(VecDestroy(&vi->z));
  PetscCall(VecDestroy(&vi->zbest));
  PetscCall(VecDestroy(&vi->lower));
  PetscCall(VecDestroy(&vi->upper));
  PetscCall(VecDestroy(&vi->r_active));
  PetscCall(VecDestroy(&vi->F));
  PetscCall(VecDestroy(&vi->vd_active));
  PetscCall(VecDestroy(&vi->row_scale));
  PetscCall(PetscFree2(vi->mu, vi->rho));
  vi->nactive = 0;
  PetscFunctionReturn(0);
}

/* r_active = r(z) = s (z_n, mu z_n theta) per active contact. */
static PetscErrorCode ImpulsesFromUnknowns(SnesVI *vi, Vec z, Vec r_active)
{
  const PetscScalar *zl;
  PetscScalar       *rl;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(z, &zl));
  PetscCall(VecGetArray(r_active, &rl));
  for (PetscInt k = 0; k < vi->nactive; k++) {
    rl[k * vi->nc] = vi->impulse_scale * zl[k * vi->nc];
    if (vi->nc > 1) rl[k * vi->nc + 1] = vi->mu[k] * vi->impulse_scale * zl[k * vi->nc] * zl[k * vi->nc + 1];
  }
  PetscCall(VecRestoreArray(r_active, &rl));
  PetscCall(VecRestoreArrayRead(z, &zl));
  PetscFunctionReturn(0);
}

/* F(z) = (rho / s) (W r(z) + v^d) over the active components. */
static PetscErrorCode FormFunction(SNES snes, Vec z, Vec F, void *ctx)
{
  SnesVI *vi = (SnesVI *)ctx;

  PetscFunctionBeginUser;
  (void)snes;
  PetscCall(ImpulsesFromUnknowns(vi, z, vi->r_active));
  PetscCall(MatMultAdd(vi->Wa, vi->r_active, vi->vd_active, F));
  PetscCall(VecPointwiseMult(F, F, vi->row_scale));
  PetscFunctionReturn(0);
}

/* T = dr/dz at z: per contact s [[1, 0], [mu theta, mu z_n]] (s alone without friction). The zero at (n, t) is set
   too, so that T's pattern, hence J's (MatMatMult reused), is the same at every z. */
static PetscErrorCode FormTransform(SnesVI *vi, Vec z)
{
  const PetscScalar *zl;
  const PetscReal    s = vi->impulse_scale;
  PetscInt           rstart;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(z, &rstart, NULL));
  PetscCall(VecGetArrayRead(z, &zl));
  for (PetscInt k = 0; k < vi->nactive; k++) {
    const PetscInt row = rstart + k * vi->nc;
    PetscCall(MatSetValue(vi->T, row, row, s, INSERT_VALUES));
    if (vi->nc > 1) {
      const PetscInt    cols[2] = {row, row + 1};
      const PetscScalar vals[2] = {s * vi->mu[k] * zl[k * vi->nc + 1], s * vi->mu[k] * zl[k * vi->nc]};
      PetscCall(MatSetValue(vi->T, row, row + 1, 0.0, INSERT_VALUES));
      PetscCall(MatSetValues(vi->T, 1, &cols[1], 2, cols, vals, INSERT_VALUES));
    }
  }
  PetscCall(VecRestoreArrayRead(z, &zl));
  PetscCall(MatAssemblyBegin(vi->T, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(vi->T, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* J = diag(rho / s) Wa T(z) + shift I. */
static PetscErrorCode FormJacobian(SNES snes, Vec z, Mat J, Mat P, void *ctx)
{
  SnesVI *vi = (SnesVI *)ctx;

  PetscFunctionBeginUser;
  (void)snes;
  (void)P;
  PetscCall(FormTransform(vi, z));
  PetscCall(MatMatMult(vi->Wa, vi->T, MAT_REUSE_MATRIX, PETSC_DEFAULT, &J));
  PetscCall(MatDiagonalScale(J, vi->row_scale, NULL));
  if (vi->shift > 0) PetscCall(MatShift(J, vi->shift));
  PetscFunctionReturn(0);
}

/* vi->res = the natural residual of the original problem at z; leaves r(z) in the operators' r (0 on the inactive
   contacts) and W r + v^d in their v. */
static PetscErrorCode NaturalResidual(KergsSolver s, SnesVI *vi, Vec z)
{
  KergsResiduals res;

  PetscFunctionBeginUser;
  PetscCall(ImpulsesFromUnknowns(vi, z, vi->r_active));
  PetscCall(VecSet(vi->r, 0.0));
  PetscCall(VecISCopy(vi->r, vi->is, SCATTER_FORWARD, vi->r_active));
  PetscCall(KergsSweepResiduals(s->sweep, vi->r, vi->vd, vi->v, &res));
  vi->res = res.natural;
  PetscFunctionReturn(0);
}

/* SNES's convergence test, replaced: converged when the original problem's natural residual is at most -solver_tol
   (SNESVI's own norms are ignored), diverged at -solver_max_it. Besides, it prints the monitors' line of the
   iteration and keeps the best iterate in zbest. At iteration 0 z is the start, whose residual is known. */
static PetscErrorCode TrackNaturalResidual(SNES snes, PetscInt it, PetscReal xnorm, PetscReal gnorm, PetscReal fnorm,
                                           SNESConvergedReason *reason, void *ctx)
{
  KergsSolver s  = (KergsSolver)ctx;
  SnesVI     *vi = (SnesVI *)s->data;
  Vec         z;

  PetscFunctionBeginUser;
  (void)xnorm;
  (void)gnorm;
  *reason = SNES_CONVERGED_ITERATING;
  if (PetscIsInfOrNanReal(fnorm)) {
    *reason = SNES_DIVERGED_FNORM_NAN;
    PetscFunctionReturn(0);
  }
  if (it > 0) {
    PetscCall(SNESGetSolution(snes, &z));
    PetscCall(NaturalResidual(s, vi, z));
    PetscCall(KergsSolverMonitor(s, it, vi->res, vi->res));
    if (vi->res < vi->best) {
      vi->best = vi->res;
      PetscCall(VecCopy(z, vi->zbest));
    }
  }
  if (vi->res <= s->tol)
    *reason = SNES_CONVERGED_FNORM_ABS;
  else if (it >= s->max_it)
    *reason = SNES_DIVERGED_MAX_IT;
  PetscFunctionReturn(0);
}

/* The linear solver: a direct LU with AMD, PETSc's on one rank (zero pivots shifted), MUMPS on several. RSLS factors a
   new submatrix of J at every iteration, so nothing is set on a factor here (MUMPS's null-pivot detection, which
   `newton` switches on, would be lost); J's shift keeps the factored matrices nonsingular. */
static PetscErrorCode ConfigureLinearSolver(KergsSolver s, SNES snes)
{
  KSP         ksp;
  PC          pc;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCLU));
  PetscCall(PCFactorSetMatOrderingType(pc, MATORDERINGAMD));
  PetscCall(PCFactorSetMatSolverType(pc, size > 1 ? MATSOLVERMUMPS : MATSOLVERPETSC));
  if (size == 1) PetscCall(PCFactorSetShiftType(pc, MAT_SHIFT_NONZERO));
  PetscFunctionReturn(0);
}

/* The SNES of a step (sizes change with the active set): RSLS, a direct LU, then the options under solver_; the l2
   line search for RSLS unless one was chosen (with PETSc's backtracking RSLS stops on failed line searches on 4 of
   confine500's 10 frictional steps, with l2 on 2; SSLS does better with the backtracking). Only the VI types: any
   other would ignore the bounds. */
static PetscErrorCode CreateSNES(KergsSolver s, SnesVI *vi)
{
  PetscBool vitype, rsls, chosen;
  char      prefix[256];

  PetscFunctionBeginUser;
  PetscCall(KergsSolverInnerPrefix(s, "solver_", prefix, sizeof(prefix)));
  PetscCall(SNESCreate(s->comm, &vi->snes));
  PetscCall(SNESSetOptionsPrefix(vi->snes, prefix));
  PetscCall(SNESSetType(vi->snes, SNESVINEWTONRSLS));
  PetscCall(ConfigureLinearSolver(s, vi->snes));
  PetscCall(SNESSetMaxLinearSolveFailures(vi->snes, PETSC_MAX_INT));
  PetscCall(SNESSetTolerances(vi->snes, 0.0, 0.0, 0.0, s->max_it, -1)); /* TrackNaturalResidual decides; -1: any number of F */
  PetscCall(SNESSetFromOptions(vi->snes));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)vi->snes, &vitype, SNESVINEWTONRSLS, SNESVINEWTONSSLS, ""));
  PetscCheck(vitype, s->comm, PETSC_ERR_ARG_WRONG, "-solver_snes_type must be vinewtonrsls or vinewtonssls for -solver_type snesvi");
  PetscCall(PetscObjectTypeCompare((PetscObject)vi->snes, SNESVINEWTONRSLS, &rsls));
  PetscCall(PetscOptionsHasName(NULL, prefix, "-snes_linesearch_type", &chosen));
  if (rsls && !chosen) {
    SNESLineSearch ls;
    PetscCall(SNESGetLineSearch(vi->snes, &ls));
    PetscCall(SNESLineSearchSetType(ls, SNESLINESEARCHL2));
  }
  PetscFunctionReturn(0);
}

/* The active components (IS), mu and rho per active contact, and W over the active components (AIJ). */
static PetscErrorCode BuildActiveSystem(KergsSolver s, SnesVI *vi, KergsOperators ops, PetscInt n)
{
  PetscReal *blocks;
  Mat        Wfull;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(n + 1, &vi->mu, n + 1, &vi->rho));
  PetscCall(PetscMalloc1(n * vi->nc * vi->nc + 1, &blocks));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, blocks));
  vi->nactive = 0;
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) {
      const PetscReal wnn    = blocks[a * vi->nc * vi->nc];
      vi->mu[vi->nactive]    = vi->nc > 1 ? s->mu[a] : 0.0;
      vi->rho[vi->nactive++] = wnn > 0 ? 1.0 / wnn : 1.0;
    }
  PetscCall(PetscFree(blocks));
  PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
  PetscCall(KergsSolverActiveSubmatrix(s, Wfull, n, vi->nc, &vi->is, &vi->Wa));
  PetscCall(MatDestroy(&Wfull));
  PetscFunctionReturn(0);
}

/* The vectors over the active components, T's pattern (nc nonzeros per row at most) and J = Wa T's. */
static PetscErrorCode BuildJacobianPattern(KergsSolver s, SnesVI *vi)
{
  PetscInt m;

  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(vi->Wa, &vi->z, &vi->r_active));
  PetscCall(VecDuplicate(vi->z, &vi->zbest));
  PetscCall(VecDuplicate(vi->z, &vi->lower));
  PetscCall(VecDuplicate(vi->z, &vi->upper));
  PetscCall(VecDuplicate(vi->z, &vi->F));
  PetscCall(VecDuplicate(vi->z, &vi->vd_active));
  PetscCall(VecDuplicate(vi->z, &vi->row_scale));
  PetscCall(VecGetLocalSize(vi->z, &m));
  PetscCall(MatCreateAIJ(s->comm, m, m, PETSC_DETERMINE, PETSC_DETERMINE, vi->nc, NULL, 0, NULL, &vi->T));
  PetscCall(MatSetOption(vi->T, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  vi->impulse_scale = 1.0;
  PetscCall(FormTransform(vi, vi->z)); /* z = 0: the pattern */
  PetscCall(MatMatMult(vi->Wa, vi->T, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &vi->J));
  PetscFunctionReturn(0);
}

/* Active set (KergsSolverSetUpSweep), then, unless no contact is active, the MCP's matrices and vectors and the SNES. */
static PetscErrorCode SolverSetUp_SnesVI(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  SnesVI        *vi = (SnesVI *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nactive = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(DestroyStepObjects(vi));
  vi->nc = layout.ncomp;
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) nactive++;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nactive, 1, MPIU_INT, MPI_SUM, s->comm));
  if (nactive == 0) PetscFunctionReturn(0);
  PetscCall(BuildActiveSystem(s, vi, ops, n));
  PetscCall(BuildJacobianPattern(s, vi));
  PetscCall(CreateSNES(s, vi));
  PetscCall(SNESSetFunction(vi->snes, vi->F, FormFunction, vi));
  PetscCall(SNESSetJacobian(vi->snes, vi->J, vi->J, FormJacobian, vi));
  PetscCall(SNESVISetVariableBounds(vi->snes, vi->lower, vi->upper));
  PetscCall(SNESSetConvergenceTest(vi->snes, TrackNaturalResidual, s, NULL));
  PetscFunctionReturn(0);
}

/* s = the largest |rho v^d_n| (1 if none), z from the warm start r (z_n = r_n / s projected on z_n >= 0; theta =
   r_t / (mu r_n) within [-1, 1], 0 where r_n = 0), the bounds, v^d over the active components and the rows' scaling
   rho / s. */
static PetscErrorCode StartFromImpulses(KergsSolver s, SnesVI *vi)
{
  PetscScalar       *zl, *lo, *hi, *sl;
  const PetscScalar *rl, *vdl;
  PetscReal          largest = 0.0;
  Vec                sub;

  PetscFunctionBeginUser;
  PetscCall(VecGetSubVector(vi->vd, vi->is, &sub));
  PetscCall(VecCopy(sub, vi->vd_active));
  PetscCall(VecRestoreSubVector(vi->vd, vi->is, &sub));
  PetscCall(VecGetArrayRead(vi->vd_active, &vdl));
  for (PetscInt k = 0; k < vi->nactive; k++) largest = PetscMax(largest, PetscAbsReal(vi->rho[k] * PetscRealPart(vdl[k * vi->nc])));
  PetscCall(VecRestoreArrayRead(vi->vd_active, &vdl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &largest, 1, MPIU_REAL, MPIU_MAX, s->comm));
  vi->impulse_scale = largest > 0 ? largest : 1.0;
  PetscCall(VecGetSubVector(vi->r, vi->is, &sub));
  PetscCall(VecGetArrayRead(sub, &rl));
  PetscCall(VecGetArray(vi->z, &zl));
  PetscCall(VecGetArray(vi->lower, &lo));
  PetscCall(VecGetArray(vi->upper, &hi));
  PetscCall(VecGetArray(vi->row_scale, &sl));
  for (PetscInt k = 0; k < vi->nactive; k++) {
    const PetscInt  i  = k * vi->nc;
    const PetscReal rn = PetscMax(PetscRealPart(rl[i]), 0.0);
    zl[i]              = rn / vi->impulse_scale;
    lo[i]              = 0.0;
    hi[i]              = PETSC_INFINITY;
    sl[i]              = vi->rho[k] / vi->impulse_scale;
    if (vi->nc > 1) {
      const PetscReal bound = vi->mu[k] > 0 ? 1.0 : 0.0; /* mu = 0: theta fixed at 0 */
      zl[i + 1]             = vi->mu[k] > 0 && rn > 0 ? PetscClipInterval(PetscRealPart(rl[i + 1]) / (vi->mu[k] * rn), -1.0, 1.0) : 0.0;
      lo[i + 1]             = -bound;
      hi[i + 1]             = bound;
      sl[i + 1]             = vi->rho[k] / vi->impulse_scale;
    }
  }
  PetscCall(VecRestoreArray(vi->row_scale, &sl));
  PetscCall(VecRestoreArray(vi->upper, &hi));
  PetscCall(VecRestoreArray(vi->lower, &lo));
  PetscCall(VecRestoreArray(vi->z, &zl));
  PetscCall(VecRestoreArrayRead(sub, &rl));
  PetscCall(VecRestoreSubVector(vi->r, vi->is, &sub));
  PetscFunctionReturn(0);
}

/* From the warm start, SNESSolve unless it already solves the step; the best iterate's impulses end in the operators'
   r. The step's matrices, vectors and SNES are freed at the end (the memory of a step is the solve's only). */
static PetscErrorCode SolverSolve_SnesVI(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                         KergsSolveStats *stats)
{
  SnesVI        *vi = (SnesVI *)s->data;
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  (void)scene;
  (void)contacts;
  PetscCall(PetscTime(&t0));
  PetscCall(KergsOperatorsGetContactVectors(ops, &vi->r, &vi->v, &vi->vd));
  vi->its = vi->linear_its = vi->function_evals = 0;
  vi->reason                                    = SNES_CONVERGED_ITERATING;
  if (!vi->snes) { /* no active contact: r = 0 already (KergsSolverSetUpSweep) */
    KergsResiduals res;
    PetscCall(KergsSweepResiduals(s->sweep, vi->r, vi->vd, vi->v, &res));
    vi->res = res.natural;
  } else {
    PetscCall(StartFromImpulses(s, vi));
    PetscCall(NaturalResidual(s, vi, vi->z));
    vi->best = vi->res;
    PetscCall(VecCopy(vi->z, vi->zbest));
    if (vi->res > s->tol) {
      PetscCall(SNESSolve(vi->snes, NULL, vi->z));
      PetscCall(SNESGetIterationNumber(vi->snes, &vi->its));
      PetscCall(SNESGetLinearSolveIterations(vi->snes, &vi->linear_its));
      PetscCall(SNESGetNumberFunctionEvals(vi->snes, &vi->function_evals));
      PetscCall(SNESGetConvergedReason(vi->snes, &vi->reason));
      PetscCall(NaturalResidual(s, vi, vi->zbest));
      PetscCall(PetscInfo(NULL, "snesvi: %" PetscInt_FMT " iterations, %s, natural residual %g\n", vi->its,
                          SNESConvergedReasons[vi->reason], (double)vi->res));
    }
  }
  stats->iterations = vi->its;
  stats->criterion  = vi->res;
  stats->reason     = KERGS_SOLVER_DIVERGED_MAX_IT;
  if (vi->res <= s->tol) PetscCall(KergsSolverCriterionMet(s, stats));
  PetscCall(DestroyStepObjects(vi));
  vi->r = vi->v = vi->vd = NULL;
  PetscCall(PetscTime(&t1));
  stats->sweep_seconds = t1 - t0;
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverStats_SnesVI(KergsSolver s, KergsSolveStats *st)
{
  SnesVI *vi = (SnesVI *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsSolveStatsAdd(st, "linear_iterations", (PetscReal)vi->linear_its));
  PetscCall(KergsSolveStatsAdd(st, "function_evaluations", (PetscReal)vi->function_evals));
  PetscCall(KergsSolveStatsAdd(st, "snes_reason", (PetscReal)vi->reason));
  PetscFunctionReturn(0);
}

/* The SNES options are read for -help and the unused-option check (and the type checked); each step's SNES reads them
   again. */
static PetscErrorCode SolverSetFromOptions_SnesVI(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  SnesVI *vi = (SnesVI *)s->data;

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "PETSc SNESVI on the complementarity problem (snesvi)");
  PetscCall(PetscOptionsReal("-solver_snesvi_shift", "Shift of the Jacobian, J + shift I (J singular where W is and where r_n = 0)", "",
                             vi->shift, &vi->shift, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(vi->shift >= 0 && !PetscIsInfOrNanReal(vi->shift), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_snesvi_shift %g must be non-negative", (double)vi->shift);
  PetscCall(SNESDestroy(&vi->snes));
  PetscCall(CreateSNES(s, vi));
  {
    SNESType type;
    PetscCall(SNESGetType(vi->snes, &type));
    PetscCall(PetscStrncpy(vi->snestype, type, sizeof(vi->snestype)));
  }
  PetscCall(SNESDestroy(&vi->snes));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_SnesVI(KergsSolver s, PetscViewer viewer)
{
  SnesVI *vi = (SnesVI *)s->data;

  PetscFunctionBeginUser;
  PetscCall(
      PetscViewerASCIIPrintf(viewer,
                             "PETSc SNES %s on the complementarity problem in z = (r_n / s, theta), r_t = mu r_n theta, F = rho u / s, "
                             "Jacobian shift %g\n",
                             vi->snestype, (double)vi->shift));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverDestroy_SnesVI(KergsSolver s)
{
  SnesVI *vi = (SnesVI *)s->data;

  PetscFunctionBeginUser;
  PetscCall(DestroyStepObjects(vi));
  PetscCall(PetscFree(vi));
  s->data = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_SnesVI(KergsSolver s)
{
  SnesVI *vi;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&vi));
  s->needs_both_triangles = PETSC_TRUE; /* KergsOperatorsGetFullW */
  vi->shift               = 1e-8;
  s->data                 = vi;
  s->max_it               = 1000;
  s->tol                  = 1e-10;
  s->criterion            = KERGS_CRITERION_NATURAL;
  s->fixed_criterion      = PETSC_TRUE;
  s->iteration_name       = "SNES iterations";
  s->ops.setfromoptions   = SolverSetFromOptions_SnesVI;
  s->ops.setup            = SolverSetUp_SnesVI;
  s->ops.solve            = SolverSolve_SnesVI;
  s->ops.stats            = SolverStats_SnesVI;
  s->ops.view             = SolverView_SnesVI;
  s->ops.destroy          = SolverDestroy_SnesVI;
  PetscFunctionReturn(0);
}
