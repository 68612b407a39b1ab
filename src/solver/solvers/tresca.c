/* kergs solver type "tresca": a fixed point on Tresca problems, each a convex bound-constrained quadratic program
   solved by PETSc's TAO, converging to the original per-step problem (docs/solver.md, "Tresca fixed point").

   Outer iteration k: the friction thresholds s_a = mu_a r_n,a^k come from the last normal impulses. With them fixed,
   the 2D law becomes a Tresca law, and the per-step problem (W symmetric positive semidefinite) is exactly the QP
     min 1/2 r^T W r + r^T v^d   subject to   r_n >= 0,  -s <= r_t <= s
   over the active contacts (KKT: v = W r + v^d, 0 <= v_n _|_ r_n >= 0, v_t of the sign that pushes r_t to its bound,
   0 where r_t lies inside). Inactive contacts keep r = 0 and are left out of the QP. The QP is handed to a Tao
   (prefix solver_tresca_: -solver_tresca_tao_type bqpip|gpcg|tron|blmvm and every other -solver_tresca_tao_* option)
   with the Hessian W over the active contacts, warm-started from r^k, and r^{k+1} is its solution. At a fixed point
   r = r^k the thresholds are mu r_n: r solves the Coulomb problem. W is singular in a confined packing (its kernel:
   self-equilibrated networks), so the QP's minimiser is not unique along the kernel; the optional proximal term
   sigma |r - r^k|^2 / 2 (-solver_tresca_sigma, relative to the mean W_nn) makes it strictly convex and vanishes at the
   fixed point. Convergence is the natural residual of the original problem (KergsSweepNaturalResidual, the same as
   every type's), at most -solver_tol; -solver_max_it caps the outer iterations. */
#include <kergs/private/solverimpl.h>
#include <petsctao.h>

typedef struct {
  Tao            tao; /* this step's QP solver; prefix solver_tresca_ */
  char           taotype[64];
  KergsQuadratic qp;        /* H: W over the active components (+ sigma I), AIJ; c: the linear term */
  IS             is;        /* the active components, global indices of r */
  Vec            x, lb, ub; /* the active components: impulses, bounds */
  PetscReal      wmean;     /* mean W_nn over the active contacts */
  PetscReal      sigma;     /* the proximal coefficient of this step (absolute) */
  PetscInt       nactive;   /* local active contacts */
  /* options */
  PetscReal sigma_factor; /* -solver_tresca_sigma: sigma / mean W_nn, at least */
  PetscReal sigma_alpha;  /* -solver_tresca_sigma_alpha: sigma / mean W_nn = alpha * natural residual, when larger */
  PetscReal inner_rtol;   /* -solver_tresca_inner_rtol: inner tolerance relative to the natural residual */
  /* figures of the last solve */
  PetscInt       outer, tao_its, tao_failed;
  PetscLogDouble tao_seconds;
} Tresca;

static PetscErrorCode DestroyStepObjects(Tresca *tr)
{
  PetscFunctionBeginUser;
  PetscCall(TaoDestroy(&tr->tao));
  PetscCall(MatDestroy(&tr->qp.H));
  PetscCall(ISDestroy(&tr->is));
  PetscCall(VecDestroy(&tr->x));
  PetscCall(VecDestroy(&tr->qp.c));
  PetscCall(VecDestroy(&tr->lb));
  PetscCall(VecDestroy(&tr->ub));
  PetscFunctionReturn(0);
}

/* The Tao of a step (the QP's size changes with the active set): the chosen type, then the options under
   solver_tresca_, so that any -solver_tresca_tao_* option applies. */
static PetscErrorCode CreateTao(KergsSolver s, Tresca *tr)
{
  char prefix[256];

  PetscFunctionBeginUser;
  PetscCall(KergsSolverInnerPrefix(s, "solver_tresca_", prefix, sizeof(prefix)));
  PetscCall(TaoCreate(s->comm, &tr->tao));
  PetscCall(TaoSetOptionsPrefix(tr->tao, prefix));
  PetscCall(TaoSetType(tr->tao, tr->taotype));
  /* the types' own caps (TRON 50, BQPIP 100, GPCG 500) leave a frictionless problem, one QP, unsolved on confine500;
     -solver_tresca_tao_max_it overrides */
  PetscCall(TaoSetMaximumIterations(tr->tao, 1000));
  PetscCall(TaoSetFromOptions(tr->tao));
  PetscFunctionReturn(0);
}

/* Active set (KergsSolverSetUpSweep), then W restricted to the active contacts' components, converted to AIJ (TAO's
   active-set types extract submatrices on arbitrary component subsets), shifted by sigma, and the Tao. */
static PetscErrorCode SolverSetUp_Tresca(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  Tresca        *tr = (Tresca *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nc;
  PetscReal     *blocks, sums[2] = {0.0, 0.0};
  Mat            Wfull;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  nc = layout.ncomp;
  PetscCall(DestroyStepObjects(tr));
  PetscCall(PetscMalloc1(n * nc * nc + 1, &blocks));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, blocks));
  tr->nactive = 0;
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) {
      tr->nactive++;
      sums[0] += blocks[a * nc * nc];
      sums[1] += 1.0;
    }
  PetscCall(PetscFree(blocks));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 2, MPIU_REAL, MPIU_SUM, s->comm));
  tr->wmean = sums[1] > 0 ? sums[0] / sums[1] : 1.0;
  tr->sigma = tr->sigma_factor * tr->wmean;
  PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
  PetscCall(KergsSolverActiveSubmatrix(s, Wfull, n, nc, &tr->is, &tr->qp.H));
  PetscCall(MatDestroy(&Wfull));
  if (tr->sigma > 0) PetscCall(MatShift(tr->qp.H, tr->sigma));
  PetscCall(MatSetOption(tr->qp.H, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatCreateVecs(tr->qp.H, &tr->x, &tr->qp.c));
  PetscCall(VecDuplicate(tr->x, &tr->lb));
  PetscCall(VecDuplicate(tr->x, &tr->ub));
  PetscCall(CreateTao(s, tr));
  PetscCall(KergsQuadraticSetTao(&tr->qp, tr->tao));
  PetscCall(TaoSetVariableBounds(tr->tao, tr->lb, tr->ub));
  PetscFunctionReturn(0);
}

/* The Tresca bounds from the current impulses x (the active components, nc per contact): r_n >= 0, |r_t| <= mu r_n. */
static PetscErrorCode SetBounds(KergsSolver s, Tresca *tr, PetscInt n, PetscInt nc)
{
  const PetscScalar *xl;
  PetscScalar       *lo, *hi;
  PetscInt           k = 0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(tr->x, &xl));
  PetscCall(VecGetArray(tr->lb, &lo));
  PetscCall(VecGetArray(tr->ub, &hi));
  for (PetscInt a = 0; a < n; a++) {
    if (!s->active[a]) continue;
    lo[k * nc] = 0.0;
    hi[k * nc] = PETSC_INFINITY;
    if (nc > 1) {
      const PetscReal thr = s->mu[a] * PetscMax(PetscRealPart(xl[k * nc]), 0.0);
      lo[k * nc + 1]      = -thr;
      hi[k * nc + 1]      = thr;
    }
    k++;
  }
  PetscCall(VecRestoreArray(tr->ub, &hi));
  PetscCall(VecRestoreArray(tr->lb, &lo));
  PetscCall(VecRestoreArrayRead(tr->x, &xl));
  PetscFunctionReturn(0);
}

/* Whether the thresholds do not matter: frictionless (one component, or mu = 0 on every active contact). Then one QP
   is the whole problem. */
static PetscErrorCode IsFrictionless(KergsSolver s, PetscInt n, PetscInt nc, PetscBool *frictionless)
{
  PetscBool f = PETSC_TRUE;

  PetscFunctionBeginUser;
  if (nc > 1)
    for (PetscInt a = 0; a < n; a++)
      if (s->active[a] && s->mu[a] != 0.0) f = PETSC_FALSE;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &f, 1, MPIU_BOOL, MPI_LAND, s->comm));
  *frictionless = f;
  PetscFunctionReturn(0);
}

/* One QP with the thresholds of x (the current impulses), from x: the linear term v^d - sigma x (proximal centre x),
   the gradient tolerance gatol (velocity units), the solve, and its figures. */
static PetscErrorCode SolveQP(KergsSolver s, Tresca *tr, PetscInt n, PetscInt nc, Vec vd, PetscReal sigma, PetscReal gatol,
                              PetscBool *solved)
{
  PetscInt           its;
  TaoConvergedReason reason;
  PetscLogDouble     t0, t1;
  Vec                sub;

  PetscFunctionBeginUser;
  PetscCall(SetBounds(s, tr, n, nc));
  if (sigma != tr->sigma) { /* H = W + sigma I: only its diagonal changes */
    PetscCall(MatShift(tr->qp.H, sigma - tr->sigma));
    tr->sigma = sigma;
  }
  PetscCall(VecGetSubVector(vd, tr->is, &sub));
  PetscCall(VecCopy(sub, tr->qp.c));
  PetscCall(VecRestoreSubVector(vd, tr->is, &sub));
  if (tr->sigma > 0) PetscCall(VecAXPY(tr->qp.c, -tr->sigma, tr->x));
  PetscCall(TaoSetTolerances(tr->tao, gatol, 0.0, 0.0));
  PetscCall(TaoSetSolution(tr->tao, tr->x));
  PetscCall(PetscTime(&t0));
  PetscCall(TaoSolve(tr->tao));
  PetscCall(PetscTime(&t1));
  PetscCall(TaoGetIterationNumber(tr->tao, &its));
  PetscCall(TaoGetConvergedReason(tr->tao, &reason));
  tr->tao_seconds += t1 - t0;
  tr->tao_its += its;
  if (reason < 0) tr->tao_failed++;
  *solved = (PetscBool)(reason > 0);
  PetscCall(PetscInfo(NULL, "tresca: QP %" PetscInt_FMT ": %" PetscInt_FMT " %s iterations, %s (gatol %g)\n", tr->outer + 1, its,
                      tr->taotype, TaoConvergedReasons[reason], (double)gatol));
  PetscFunctionReturn(0);
}

/* Outer iterations until the natural residual of the original problem is at most -solver_tol or -solver_max_it. The
   inner tolerance follows the residual down: |projected gradient| <= inner_rtol * |e| * mean W_nn (the natural map
   divides velocities by W_nn; |e| = res * scale, KergsResiduals), but never tighter than needed for -solver_tol;
   without friction the first QP is the whole problem and is solved to -solver_tol at once. */
static PetscErrorCode SolverSolve_Tresca(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                         KergsSolveStats *stats)
{
  Tresca        *tr = (Tresca *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nc, nglobal;
  KergsResiduals res;
  PetscBool      frictionless = PETSC_FALSE;
  PetscLogDouble t0, t1;
  Vec            r, v, vd, sub;

  PetscFunctionBeginUser;
  (void)scene;
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, &v, &vd));
  PetscCall(VecGetSize(tr->x, &nglobal));
  nc        = layout.ncomp;
  tr->outer = tr->tao_its = tr->tao_failed = 0;
  tr->tao_seconds                          = 0.0;
  PetscCall(IsFrictionless(s, n, nc, &frictionless));
  PetscCall(VecGetSubVector(r, tr->is, &sub));
  PetscCall(VecCopy(sub, tr->x));
  PetscCall(VecRestoreSubVector(r, tr->is, &sub));
  PetscCall(KergsSweepResiduals(s->sweep, r, vd, v, &res));
  while (res.natural > s->tol && nglobal > 0 && tr->outer < s->max_it) {
    const PetscReal before = res.natural;
    PetscReal       gatol;
    PetscBool       solved;
    /* sigma follows the residual down (with -solver_tresca_sigma_alpha), as newton's proximal term does */
    const PetscReal sigma = PetscMax(tr->sigma_factor, tr->sigma_alpha * res.natural) * tr->wmean;
    gatol                 = 0.1 * s->tol * res.scale * tr->wmean;
    if (!frictionless) gatol = PetscMax(gatol, tr->inner_rtol * res.natural * res.scale * tr->wmean);
    PetscCall(SolveQP(s, tr, n, nc, vd, sigma, gatol, &solved));
    tr->outer++;
    PetscCall(VecISCopy(r, tr->is, SCATTER_FORWARD, tr->x)); /* inactive components stay 0 */
    PetscCall(KergsSweepResiduals(s->sweep, r, vd, v, &res));
    /* without friction the QP is the problem, but gatol was scaled by the warm start's max(|r|, |p|), which may be far below the
       solution's (a cold start), and the proximal term biases the QP's answer by sigma (r - r^k): the same thresholds
       (the same Tresca iteration) again, re-centred at the answer and tighter (by at most 100 per round) */
    for (PetscInt k = 0; frictionless && solved && res.natural > s->tol && k < 5; k++) {
      gatol *= PetscMax(0.1 * s->tol / res.natural, 1e-2);
      PetscCall(SolveQP(s, tr, n, nc, vd, sigma, gatol, &solved));
      PetscCall(VecISCopy(r, tr->is, SCATTER_FORWARD, tr->x));
      PetscCall(KergsSweepResiduals(s->sweep, r, vd, v, &res));
    }
    PetscCall(PetscInfo(NULL, "tresca: outer %" PetscInt_FMT ": natural residual %g -> %g, %" PetscInt_FMT " TAO iterations so far\n",
                        tr->outer, (double)before, (double)res.natural, tr->tao_its));
  }
  stats->iterations = tr->outer;
  stats->criterion  = res.natural;
  stats->reason     = nglobal == 0 ? KERGS_SOLVER_CONVERGED_NO_CONTACTS : KERGS_SOLVER_DIVERGED_MAX_IT;
  if (res.natural <= s->tol) PetscCall(KergsSolverCriterionMet(s, stats));
  PetscCall(PetscTime(&t1));
  stats->sweep_seconds = t1 - t0;
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverStats_Tresca(KergsSolver s, KergsSolveStats *st)
{
  Tresca *tr = (Tresca *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsSolveStatsAdd(st, "tao_iterations", (PetscReal)tr->tao_its));
  PetscCall(KergsSolveStatsAdd(st, "tao_failed", (PetscReal)tr->tao_failed));
  PetscCall(KergsSolveStatsAdd(st, "tao_seconds", tr->tao_seconds));
  PetscCall(KergsSolveStatsAddText(st, "tao_type", tr->taotype));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSetFromOptions_Tresca(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  Tresca *tr = (Tresca *)s->data;

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "Tresca fixed point, QPs by TAO (tresca)");
  PetscCall(PetscOptionsReal("-solver_tresca_sigma",
                             "Proximal term sigma |r - r^k|^2 / 2 of each QP, sigma relative to the mean W_nn (0: none; W is singular)", "",
                             tr->sigma_factor, &tr->sigma_factor, NULL));
  PetscCall(
      PetscOptionsReal("-solver_tresca_sigma_alpha",
                       "Proximal sigma / mean W_nn = alpha * natural residual where larger than -solver_tresca_sigma (0: fixed sigma)", "",
                       tr->sigma_alpha, &tr->sigma_alpha, NULL));
  PetscCall(PetscOptionsReal("-solver_tresca_inner_rtol", "QP tolerance relative to the natural residual of the original problem", "",
                             tr->inner_rtol, &tr->inner_rtol, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(tr->sigma_factor >= 0 && !PetscIsInfOrNanReal(tr->sigma_factor), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_tresca_sigma %g must be non-negative", (double)tr->sigma_factor);
  PetscCheck(tr->sigma_alpha >= 0 && !PetscIsInfOrNanReal(tr->sigma_alpha), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_tresca_sigma_alpha %g must be non-negative", (double)tr->sigma_alpha);
  PetscCheck(tr->inner_rtol > 0 && PetscIsNormalReal(tr->inner_rtol), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_tresca_inner_rtol %g must be positive", (double)tr->inner_rtol);
  /* the Tao type (and every -solver_tresca_tao_* option) read once here, for -help and the unused-option check; each
     step's Tao reads them again */
  PetscCall(TaoDestroy(&tr->tao));
  PetscCall(CreateTao(s, tr));
  {
    TaoType type;
    PetscCall(TaoGetType(tr->tao, &type));
    PetscCall(PetscStrncpy(tr->taotype, type, sizeof(tr->taotype)));
  }
  PetscCall(TaoDestroy(&tr->tao));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_Tresca(KergsSolver s, PetscViewer viewer)
{
  Tresca *tr = (Tresca *)s->data;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer,
                                   "Tresca fixed point, QPs by TAO %s, proximal sigma max(%g, %g residual) mean W_nn, inner rtol %g\n",
                                   tr->taotype, (double)tr->sigma_factor, (double)tr->sigma_alpha, (double)tr->inner_rtol));
  if (tr->tao) PetscCall(TaoView(tr->tao, viewer));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverDestroy_Tresca(KergsSolver s)
{
  Tresca *tr = (Tresca *)s->data;

  PetscFunctionBeginUser;
  PetscCall(DestroyStepObjects(tr));
  PetscCall(PetscFree(tr));
  s->data = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_Tresca(KergsSolver s)
{
  Tresca *tr;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&tr));
  s->needs_both_triangles = PETSC_TRUE; /* KergsOperatorsGetFullW */
  PetscCall(PetscStrncpy(tr->taotype, TAOTRON, sizeof(tr->taotype)));
  tr->sigma_factor      = 1e-6;
  tr->inner_rtol        = 0.1;
  s->data               = tr;
  s->max_it             = 1000;
  s->tol                = 1e-10;
  s->criterion          = KERGS_CRITERION_NATURAL;
  s->fixed_criterion    = PETSC_TRUE;
  s->iteration_name     = "Tresca iterations";
  s->ops.setfromoptions = SolverSetFromOptions_Tresca;
  s->ops.setup          = SolverSetUp_Tresca;
  s->ops.solve          = SolverSolve_Tresca;
  s->ops.stats          = SolverStats_Tresca;
  s->ops.view           = SolverView_Tresca;
  s->ops.destroy        = SolverDestroy_Tresca;
  PetscFunctionReturn(0);
}
