/* kergs solver type "snesvi": the per-step problem written as a mixed complementarity problem (MCP) with bounds and
   handed to PETSc's variational-inequality Newton solvers: SNESVINEWTONRSLS (reduced-space active set, the default)
   or SNESVINEWTONSSLS (semismooth Newton on the Fischer-Burmeister function), by -solver_snes_type. It is kergs's
   measure of PETSc's own engine against `newton` (docs/solver.md, "PETSc's SNESVI").

   MCP (one per active contact, 2D): unknowns z = (z_n, theta) with z_n >= 0 and -1 <= theta <= 1, the impulse
   r(z) = s (z_n, mu z_n theta), and the function F(z) = (rho / s) u with u = W r(z) + v^d and rho = 1 / W_aa,nn; s, the
   largest |rho v^d_n| of the step, makes z and F of order one, which SNESVI's absolute tolerances on the bounds need.
   Its solutions are those of the Signorini-Coulomb law: z_n = 0 or u_n = 0, with u_n >= 0; theta = -1 (r_t = -mu r_n)
   where u_t >= 0, theta = 1 where u_t <= 0, u_t = 0 in between (stick). Without friction (mu = 0, or one component)
   theta is fixed at 0 and the MCP is the linear complementarity problem of the normal impulses. F is smooth (bilinear
   in z), with Jacobian diag(rho / s) W T, T = s [[1, 0], [mu theta, mu z_n]] per contact, computed as a sparse matrix
   product; T is singular where z_n = 0 (theta undetermined for an open contact) and W is singular in a confined
   packing, so J is too: J + shift I (-solver_snesvi_shift). Inactive contacts are left out (r = 0). Convergence is the
   natural residual of the original problem, the same as every type's (KergsSweepResiduals), tested after every SNES
   iteration; -solver_max_it caps the SNES iterations, and the best iterate is kept when SNES stops on a failure (a
   failed line search may leave a trial point). Everything else is PETSc's: -solver_snes_*, -solver_snes_linesearch_*,
   -solver_ksp_*, -solver_pc_* (default: a direct LU, PETSc's on one rank, MUMPS on several). */
#include <kergs/private/solverimpl.h>
#include <petscsnes.h>

typedef struct {
  SNES       snes; /* this step's solver; prefix solver_ */
  Mat        Wa;   /* W over the active contacts' components, AIJ */
  Mat        T, J; /* dr/dz, block diagonal, and the Jacobian diag(rho, c) Wa T */
  IS         is;   /* the active components, global indices of r */
  Vec        z, zbest, lb, ub, ra, ua, vda, scale;
  PetscReal  iscale;   /* s: impulses r_n = s z_n */
  PetscReal  best;     /* the smallest natural residual of this solve, at zbest */
  PetscReal *mu, *rho; /* per active contact; rho = 1 / W_aa,nn */
  PetscInt   nactive, nc;
  Vec        r, v, vd; /* the operators' full contact vectors, for the natural residual */
  PetscReal  res;      /* the natural residual at the last SNES iterate */
  PetscReal  shift;    /* -solver_snesvi_shift: J + shift I (J's entries are of order 1) */
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
  PetscCall(VecDestroy(&vi->lb));
  PetscCall(VecDestroy(&vi->ub));
  PetscCall(VecDestroy(&vi->ra));
  PetscCall(VecDestroy(&vi->ua));
  PetscCall(VecDestroy(&vi->vda));
  PetscCall(VecDestroy(&vi->scale));
  PetscCall(PetscFree2(vi->mu, vi->rho));
  PetscFunctionReturn(0);
}

/* ra = r(z): (r_n, mu r_n theta) per active contact. */
static PetscErrorCode ImpulsesFromUnknowns(SnesVI *vi, Vec z, Vec ra)
{
  const PetscScalar *zl;
  PetscScalar       *rl;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(z, &zl));
  PetscCall(VecGetArray(ra, &rl));
  for (PetscInt k = 0; k < vi->nactive; k++) {
    rl[k * vi->nc] = vi->iscale * zl[k * vi->nc];
    if (vi->nc > 1) rl[k * vi->nc + 1] = vi->mu[k] * vi->iscale * zl[k * vi->nc] * zl[k * vi->nc + 1];
  }
  PetscCall(VecRestoreArray(ra, &rl));
  PetscCall(VecRestoreArrayRead(z, &zl));
  PetscFunctionReturn(0);
}

/* F(z) = scale * (W r(z) + v^d) over the active components. */
static PetscErrorCode FormFunction(SNES snes, Vec z, Vec F, void *ctx)
{
  SnesVI *vi = (SnesVI *)ctx;

  PetscFunctionBeginUser;
  (void)snes;
  PetscCall(ImpulsesFromUnknowns(vi, z, vi->ra));
  PetscCall(MatMultAdd(vi->Wa, vi->ra, vi->vda, F));
  PetscCall(VecPointwiseMult(F, F, vi->scale));
  PetscFunctionReturn(0);
}

/* T = dr/dz at z: per contact s [[1, 0], [mu theta, mu z_n]] (s alone without friction). */
static PetscErrorCode FormTransform(SnesVI *vi, Vec z)
{
  const PetscScalar *zl;
  PetscInt           rstart;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(z, &rstart, NULL));
  PetscCall(VecGetArrayRead(z, &zl));
  for (PetscInt k = 0; k < vi->nactive; k++) {
    const PetscInt row = rstart + k * vi->nc;
    PetscCall(MatSetValue(vi->T, row, row, vi->iscale, INSERT_VALUES));
    if (vi->nc > 1) {
      const PetscInt cols[2] = {row, row + 1};
      PetscScalar    vals[2] = {vi->iscale * vi->mu[k] * zl[k * vi->nc + 1], vi->iscale * vi->mu[k] * zl[k * vi->nc]};
      PetscCall(MatSetValue(vi->T, row, row + 1, 0.0, INSERT_VALUES));
      PetscCall(MatSetValues(vi->T, 1, &cols[1], 2, cols, vals, INSERT_VALUES));
    }
  }
  PetscCall(VecRestoreArrayRead(z, &zl));
  PetscCall(MatAssemblyBegin(vi->T, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(vi->T, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* J = diag(scale) Wa T(z). */
static PetscErrorCode FormJacobian(SNES snes, Vec z, Mat J, Mat P, void *ctx)
{
  SnesVI *vi = (SnesVI *)ctx;

  PetscFunctionBeginUser;
  (void)snes;
  (void)P;
  PetscCall(FormTransform(vi, z));
  PetscCall(MatMatMult(vi->Wa, vi->T, MAT_REUSE_MATRIX, PETSC_DEFAULT, &J));
  PetscCall(MatDiagonalScale(J, vi->scale, NULL));
  if (vi->shift > 0) PetscCall(MatShift(J, vi->shift));
  PetscFunctionReturn(0);
}

/* The natural residual of the original problem at z (r(z) on the active contacts, 0 elsewhere), into vi->res. */
static PetscErrorCode NaturalResidual(KergsSolver s, SnesVI *vi, Vec z)
{
  KergsResiduals res;

  PetscFunctionBeginUser;
  PetscCall(ImpulsesFromUnknowns(vi, z, vi->ra));
  PetscCall(VecSet(vi->r, 0.0));
  PetscCall(VecISCopy(vi->r, vi->is, SCATTER_FORWARD, vi->ra));
  PetscCall(KergsSweepResiduals(s->sweep, vi->r, vi->vd, vi->v, &res));
  vi->res = res.natural;
  PetscFunctionReturn(0);
}

/* Converged when the original problem's natural residual is at most -solver_tol; the SNES's own norms are ignored. */
static PetscErrorCode ConvergenceTest(SNES snes, PetscInt it, PetscReal xnorm, PetscReal gnorm, PetscReal fnorm,
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
  PetscCall(SNESGetSolution(snes, &z));
  PetscCall(NaturalResidual(s, vi, z));
  if (it > 0) PetscCall(KergsSolverMonitor(s, it, vi->res, vi->res));
  if (vi->res < vi->best) {
    vi->best = vi->res;
    PetscCall(VecCopy(z, vi->zbest));
  }
  if (vi->res <= s->tol)
    *reason = SNES_CONVERGED_FNORM_ABS;
  else if (it >= s->max_it)
    *reason = SNES_DIVERGED_MAX_IT;
  PetscFunctionReturn(0);
}

/* The SNES of a step (sizes change with the active set): VI Newton, direct LU, then the options under solver_. */
static PetscErrorCode CreateSNES(KergsSolver s, SnesVI *vi)
{
  KSP         ksp;
  PC          pc;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(SNESCreate(s->comm, &vi->snes));
  PetscCall(SNESSetOptionsPrefix(vi->snes, "solver_"));
  PetscCall(SNESSetType(vi->snes, SNESVINEWTONRSLS));
  { /* the l2 line search (secant on |F|^2): with the default backtracking, RSLS stops on failed line searches on most
       frictional steps of confine500; with l2 it solves 8 of 10 of them (docs/solver.md) */
    SNESLineSearch ls;
    PetscCall(SNESGetLineSearch(vi->snes, &ls));
    PetscCall(SNESLineSearchSetType(ls, SNESLINESEARCHL2));
  }
  PetscCall(SNESGetKSP(vi->snes, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, size > 1 ? MATSOLVERMUMPS : MATSOLVERPETSC));
  PetscCall(PCFactorSetShiftType(pc, MAT_SHIFT_NONZERO)); /* J is singular where W is and where r_n = 0 */
  PetscCall(SNESSetMaxLinearSolveFailures(vi->snes, 1000000));
  PetscCall(SNESSetTolerances(vi->snes, 0.0, 0.0, 0.0, s->max_it, -1)); /* ConvergenceTest decides; -1: any number of F */
  PetscCall(SNESSetFromOptions(vi->snes));
  PetscFunctionReturn(0);
}

/* Active set (KergsSolverSetUpSweep), W over the active components (AIJ), the scaling, T's pattern, J = Wa T. */
static PetscErrorCode SolverSetUp_SnesVI(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  SnesVI        *vi = (SnesVI *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nc, rstart, *idx, m = 0, k = 0, zstart;
  PetscReal     *blocks;
  Mat            Wfull, Wsub;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &vi->r, &vi->v, &vi->vd));
  nc = vi->nc = layout.ncomp;
  PetscCall(DestroyStepObjects(vi));
  PetscCall(VecGetOwnershipRange(vi->r, &rstart, NULL));
  PetscCall(PetscMalloc1(n * nc + 1, &idx));
  PetscCall(PetscMalloc2(n + 1, &vi->mu, n + 1, &vi->rho));
  vi->nactive = 0;
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) {
      for (PetscInt j = 0; j < nc; j++) idx[m++] = rstart + a * nc + j;
      vi->mu[vi->nactive++] = nc > 1 ? s->mu[a] : 0.0;
    }
  PetscCall(ISCreateGeneral(s->comm, m, idx, PETSC_OWN_POINTER, &vi->is));
  PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
  PetscCall(MatCreateSubMatrix(Wfull, vi->is, vi->is, MAT_INITIAL_MATRIX, &Wsub));
  PetscCall(MatDestroy(&Wfull));
  PetscCall(MatConvert(Wsub, MATAIJ, MAT_INITIAL_MATRIX, &vi->Wa));
  PetscCall(MatDestroy(&Wsub));
  PetscCall(MatCreateVecs(vi->Wa, &vi->z, &vi->ra));
  PetscCall(VecDuplicate(vi->z, &vi->lb));
  PetscCall(VecDuplicate(vi->z, &vi->zbest));
  PetscCall(VecDuplicate(vi->z, &vi->ub));
  PetscCall(VecDuplicate(vi->z, &vi->ua));
  PetscCall(VecDuplicate(vi->z, &vi->vda));
  PetscCall(VecDuplicate(vi->z, &vi->scale));
  PetscCall(PetscMalloc1(n * nc * nc + 1, &blocks));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, blocks));
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) {
      const PetscReal wnn = blocks[a * nc * nc];
      vi->rho[k++]        = wnn > 0 ? 1.0 / wnn : 1.0;
    }
  PetscCall(PetscFree(blocks));
  vi->iscale = 1.0;
  /* T: one or two nonzeros per row */
  PetscCall(VecGetOwnershipRange(vi->z, &zstart, NULL));
  PetscCall(MatCreateAIJ(s->comm, m, m, PETSC_DETERMINE, PETSC_DETERMINE, nc, NULL, 0, NULL, &vi->T));
  PetscCall(MatSetOption(vi->T, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(FormTransform(vi, vi->z)); /* z = 0 here: the pattern, with explicit zeros */
  PetscCall(MatMatMult(vi->Wa, vi->T, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &vi->J));
  PetscCall(CreateSNES(s, vi));
  PetscCall(SNESSetFunction(vi->snes, vi->ua, FormFunction, vi));
  PetscCall(SNESSetJacobian(vi->snes, vi->J, vi->J, FormJacobian, vi));
  PetscCall(SNESVISetVariableBounds(vi->snes, vi->lb, vi->ub));
  PetscCall(SNESSetConvergenceTest(vi->snes, ConvergenceTest, s, NULL));
  PetscFunctionReturn(0);
}

/* s = the largest |rho v^d_n| (1 if none), z from the warm start r (z_n = r_n / s projected on z_n >= 0; theta =
   r_t / (mu r_n) within [-1, 1], 0 where r_n = 0), the bounds, v^d over the active components and the rows' scaling
   rho / s. */
static PetscErrorCode StartFromImpulses(KergsSolver s, SnesVI *vi)
{
  PetscScalar       *zl, *lo, *hi, *sl;
  const PetscScalar *rl, *vdl;
  PetscReal          impulse_scale = 0.0;
  Vec                sub;

  PetscFunctionBeginUser;
  PetscCall(VecGetSubVector(vi->vd, vi->is, &sub));
  PetscCall(VecCopy(sub, vi->vda));
  PetscCall(VecRestoreSubVector(vi->vd, vi->is, &sub));
  PetscCall(VecGetArrayRead(vi->vda, &vdl));
  for (PetscInt k = 0; k < vi->nactive; k++)
    impulse_scale = PetscMax(impulse_scale, PetscAbsReal(vi->rho[k] * PetscRealPart(vdl[k * vi->nc])));
  PetscCall(VecRestoreArrayRead(vi->vda, &vdl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &impulse_scale, 1, MPIU_REAL, MPIU_MAX, s->comm));
  vi->iscale = impulse_scale > 0 ? impulse_scale : 1.0;
  PetscCall(VecGetSubVector(vi->r, vi->is, &sub));
  PetscCall(VecGetArrayRead(sub, &rl));
  PetscCall(VecGetArray(vi->z, &zl));
  PetscCall(VecGetArray(vi->lb, &lo));
  PetscCall(VecGetArray(vi->ub, &hi));
  PetscCall(VecGetArray(vi->scale, &sl));
  for (PetscInt k = 0; k < vi->nactive; k++) {
    const PetscInt  i  = k * vi->nc;
    const PetscReal rn = PetscMax(PetscRealPart(rl[i]), 0.0);
    zl[i]              = rn / vi->iscale;
    lo[i]              = 0.0;
    hi[i]              = PETSC_INFINITY;
    sl[i]              = vi->rho[k] / vi->iscale;
    if (vi->nc > 1) {
      const PetscReal bound = vi->mu[k] > 0 ? 1.0 : 0.0; /* mu = 0: theta fixed at 0 */
      zl[i + 1]             = vi->mu[k] > 0 && rn > 0 ? PetscClipInterval(PetscRealPart(rl[i + 1]) / (vi->mu[k] * rn), -1.0, 1.0) : 0.0;
      lo[i + 1]             = -bound;
      hi[i + 1]             = bound;
      sl[i + 1]             = vi->rho[k] / vi->iscale;
    }
  }
  PetscCall(VecRestoreArray(vi->scale, &sl));
  PetscCall(VecRestoreArray(vi->ub, &hi));
  PetscCall(VecRestoreArray(vi->lb, &lo));
  PetscCall(VecRestoreArray(vi->z, &zl));
  PetscCall(VecRestoreArrayRead(sub, &rl));
  PetscCall(VecRestoreSubVector(vi->r, vi->is, &sub));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSolve_SnesVI(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                         KergsSolveStats *stats)
{
  SnesVI        *vi = (SnesVI *)s->data;
  PetscInt       nglobal;
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  (void)scene;
  (void)contacts;
  (void)ops;
  PetscCall(PetscTime(&t0));
  PetscCall(VecGetSize(vi->z, &nglobal));
  vi->its = vi->linear_its = vi->function_evals = 0;
  vi->reason                                    = SNES_CONVERGED_ITERATING;
  PetscCall(StartFromImpulses(s, vi));
  PetscCall(NaturalResidual(s, vi, vi->z));
  vi->best = vi->res;
  PetscCall(VecCopy(vi->z, vi->zbest));
  if (nglobal > 0 && vi->res > s->tol) {
    PetscCall(SNESSolve(vi->snes, NULL, vi->z));
    PetscCall(SNESGetIterationNumber(vi->snes, &vi->its));
    PetscCall(SNESGetLinearSolveIterations(vi->snes, &vi->linear_its));
    PetscCall(SNESGetNumberFunctionEvals(vi->snes, &vi->function_evals));
    PetscCall(SNESGetConvergedReason(vi->snes, &vi->reason));
    PetscCall(VecCopy(vi->zbest, vi->z));     /* a failed SNES may leave a trial point */
    PetscCall(NaturalResidual(s, vi, vi->z)); /* leaves r(z) in the operators' r */
    PetscCall(PetscInfo(NULL, "snesvi: %" PetscInt_FMT " iterations, %s, natural residual %g\n", vi->its, SNESConvergedReasons[vi->reason],
                        (double)vi->res));
  } else {
    PetscCall(VecSet(vi->r, 0.0));
    PetscCall(ImpulsesFromUnknowns(vi, vi->z, vi->ra));
    PetscCall(VecISCopy(vi->r, vi->is, SCATTER_FORWARD, vi->ra));
  }
  stats->iterations    = vi->its;
  stats->criterion     = vi->res;
  stats->criterion_met = (PetscBool)(vi->res <= s->tol || nglobal == 0);
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

/* The SNES options are read for -help and the unused-option check; each step's SNES reads them again. */
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
  PetscCall(SNESDestroy(&vi->snes));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_SnesVI(KergsSolver s, PetscViewer viewer)
{
  SnesVI *vi = (SnesVI *)s->data;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, "PETSc SNESVI on the MCP in (r_n, theta), r_t = mu r_n theta, F = (rho u_n, rho u_t / s)\n"));
  if (vi->snes) PetscCall(SNESView(vi->snes, viewer));
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
  vi->shift             = 1e-8;
  s->data               = vi;
  s->max_it             = 1000;
  s->tol                = 1e-10;
  s->criterion          = KERGS_CRITERION_NATURAL;
  s->fixed_criterion    = PETSC_TRUE;
  s->iteration_name     = "SNES iterations";
  s->ops.setfromoptions = SolverSetFromOptions_SnesVI;
  s->ops.setup          = SolverSetUp_SnesVI;
  s->ops.solve          = SolverSolve_SnesVI;
  s->ops.stats          = SolverStats_SnesVI;
  s->ops.view           = SolverView_SnesVI;
  s->ops.destroy        = SolverDestroy_SnesVI;
  PetscFunctionReturn(0);
}
