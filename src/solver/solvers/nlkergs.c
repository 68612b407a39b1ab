/* kergs solver type "nlkergs": Algorithm 3 (NLKerGS-P) on an explicitly stored regularised operator
     (W + omega N N^T) r - v = -v^d + omega N N^T r~,
   with omega N N^T = Z formed column by column from the kernel projector. Z is dense (4.2 million entries for
   500 disks): this is the paper's reference "NLGS (full)", for verification on small problems only
   (-solver_nlkergs_max_size); NLGS-Jac (nlgsjac) is the production path. */
#include "regularised.h"

typedef struct {
  KergsRegularised *reg;
  PetscInt          max_size; /* -solver_nlkergs_max_size: largest number of contact components accepted */
  Mat               Wt;       /* W + Z, stored with a dense pattern */
  KergsSweep        sweep;    /* Gauss-Seidel on Wt */
  PetscInt          nnz_Wt;
} NLKerGS;

static PetscErrorCode SolverSetFromOptions_NLKerGS(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  NLKerGS *nk = (NLKerGS *)s->data;

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "NLKerGS-P on a stored W~ (verification)");
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_nlkergs_max_size",
                            "Largest number of contact components for which W~ is stored densely", "", nk->max_size, &nk->max_size, NULL));
  PetscCall(KergsRegularisedSetFromOptions(PetscOptionsObject, s, nk->reg));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSetUp_NLKerGS(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  NLKerGS           *nk  = (NLKerGS *)s->data;
  KergsRegularised  *reg = nk->reg;
  Mat                Z;
  PetscInt           N, n;
  MatInfo            info;
  const PetscScalar *zt;
  KergsDofLayout     layout;
  Vec                r;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, NULL, NULL));
  PetscCall(VecGetSize(r, &N));
  PetscCheck(N <= nk->max_size, s->comm, PETSC_ERR_SUP,
             "-solver_type nlkergs stores W + omega N N^T densely (%" PetscInt_FMT " x %" PetscInt_FMT
             "): above -solver_nlkergs_max_size %" PetscInt_FMT "; use -solver_type nlgsjac",
             N, N, nk->max_size);
  PetscCall(KergsRegularisedSetUp(s, reg, scene, contacts, ops));
  PetscCall(MatDestroy(&nk->Wt));
  PetscCall(KergsKernelGetZ(reg->kernel, &Z));
  /* explicit Z stored like W, by ncomp x ncomp blocks (Z carries W's block size), so that W~ = Z + W is one
     block row per contact for the sweep */
  PetscCall(MatComputeOperator(Z, layout.ncomp > 1 ? MATBAIJ : MATAIJ, &nk->Wt));
  {
    Mat Wfull; /* W is stored by its upper triangle: Z + W needs both */
    PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
    PetscCall(MatAXPY(nk->Wt, 1.0, Wfull, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatDestroy(&Wfull));
  }
  PetscCall(MatGetInfo(nk->Wt, MAT_GLOBAL_SUM, &info));
  nk->nnz_Wt = (PetscInt)info.nz_used;
  PetscCall(KergsSweepSetUp(nk->sweep, nk->Wt, layout.ncomp, s->mu, s->active));
  /* the regularised right-hand side: v~ = W~ r + v^d - Z r~ */
  PetscCall(VecGetLocalSize(r, &n));
  PetscCall(VecGetArrayRead(reg->ztilde, &zt));
  for (PetscInt i = 0; i < n; i++) reg->extra[i] = -zt[i];
  PetscCall(VecRestoreArrayRead(reg->ztilde, &zt));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSolve_NLKerGS(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                          KergsSolveStats *stats)
{
  NLKerGS *nk = (NLKerGS *)s->data;

  PetscFunctionBeginUser;
  (void)scene;
  (void)contacts;
  s->iterate_sweep = nk->sweep;
  PetscCall(KergsSolverIterate(s, ops, nk->reg->extra, NULL, stats));
  s->iterate_sweep = NULL;
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverStats_NLKerGS(KergsSolver s, KergsSolveStats *st)
{
  NLKerGS *nk = (NLKerGS *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedStats(nk->reg, st));
  PetscCall(KergsSolveStatsAdd(st, "nnz_Wtilde", (PetscReal)nk->nnz_Wt));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_NLKerGS(KergsSolver s, PetscViewer viewer)
{
  NLKerGS *nk = (NLKerGS *)s->data;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "NLKerGS-P (Algorithm 3) on a stored W + omega N N^T (verification; at most %" PetscInt_FMT " components)\n", nk->max_size));
  PetscCall(KergsRegularisedView(nk->reg, viewer));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverDestroy_NLKerGS(KergsSolver s)
{
  NLKerGS *nk = (NLKerGS *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedDestroy(&nk->reg));
  PetscCall(KergsSweepDestroy(&nk->sweep));
  PetscCall(MatDestroy(&nk->Wt));
  PetscCall(PetscFree(nk));
  s->data = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_NLKerGS(KergsSolver s)
{
  NLKerGS *nk;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&nk));
  s->needs_both_triangles = PETSC_TRUE; /* KergsOperatorsGetFullW */
  nk->max_size            = 6000;
  PetscCall(KergsRegularisedCreate(s->comm, &nk->reg));
  PetscCall(KergsSweepCreate(s->comm, &nk->sweep));
  s->needs_H            = PETSC_TRUE; /* the kernel projector factors H_f H_f^T */
  s->needs_full_W       = PETSC_TRUE; /* W~ = W + omega N N^T over every potential contact (Algorithm 1) */
  s->data               = nk;
  s->ops.setfromoptions = SolverSetFromOptions_NLKerGS;
  s->ops.setup          = SolverSetUp_NLKerGS;
  s->ops.solve          = SolverSolve_NLKerGS;
  s->ops.stats          = SolverStats_NLKerGS;
  s->ops.view           = SolverView_NLKerGS;
  s->ops.destroy        = SolverDestroy_NLKerGS;
  PetscFunctionReturn(0);
}
