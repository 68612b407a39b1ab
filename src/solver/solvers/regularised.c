/* kergs: the part of NLKerGS-P (Algorithm 3) and NLGS-Jac (Algorithm 6) that both share. */
#include "regularised.h"

PetscErrorCode KergsRegularisedCreate(MPI_Comm comm, KergsRegularised **reg)
{
  PetscFunctionBeginUser;
  PetscCall(PetscNew(reg));
  (*reg)->omega_factor = 1.0 / 20.0; /* the paper's finding: omega ~ ||W||_2 / 20 */
  (*reg)->power_its    = 20;
  PetscCall(KergsKernelCreate(comm, &(*reg)->kernel));
  PetscCall(KergsPredictorCreate(comm, &(*reg)->predictor));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsRegularisedSetFromOptions(PetscOptionItems *PetscOptionsObject, KergsSolver s, KergsRegularised *reg)
{
  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "Kernel-regularised solver options (nlkergs, nlgsjac)");
  PetscCall(PetscOptionsReal("-solver_omega", "omega of W + omega N N^T (0: automatic, -solver_omega_factor * ||W||_2)", "",
                             reg->omega_fixed, &reg->omega_fixed, NULL));
  PetscCall(PetscOptionsReal("-solver_omega_factor", "Automatic omega as this fraction of ||W||_2 (the paper: 1/20)", "", reg->omega_factor,
                             &reg->omega_factor, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_omega_power_its", "Power iterations estimating ||W||_2", "", reg->power_its,
                            &reg->power_its, NULL));
  PetscCheck(reg->omega_fixed >= 0 && PetscIsNormalReal(reg->omega_fixed + 1), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_omega %g must be a finite number >= 0", (double)reg->omega_fixed);
  PetscCheck(reg->omega_factor > 0 && PetscIsNormalReal(reg->omega_factor), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_omega_factor %g must be positive", (double)reg->omega_factor);
  PetscCheck(reg->power_its >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_omega_power_its %" PetscInt_FMT " must be at least 1",
             reg->power_its);
  PetscCall(KergsKernelSetOptionsPrefix(reg->kernel, s->prefix));
  PetscCall(KergsPredictorSetOptionsPrefix(reg->predictor, s->prefix));
  PetscCall(KergsKernelSetFromOptions(reg->kernel));
  PetscCall(KergsPredictorSetFromOptions(reg->predictor));
  PetscFunctionReturn(0);
}

/* ||W||_2 by power iteration (W is symmetric positive semi-definite), from a start vector that does not
   depend on the partition, so that 1 and 2 ranks choose the same omega. */
static PetscErrorCode EstimateNormW(Mat W, PetscInt its, PetscReal *norm)
{
  Vec          x, y;
  PetscScalar *xa;
  PetscInt     lo, hi;
  PetscReal    nx = 0;

  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(W, &x, &y));
  PetscCall(VecGetOwnershipRange(x, &lo, &hi));
  PetscCall(VecGetArray(x, &xa));
  for (PetscInt i = lo; i < hi; i++) xa[i - lo] = 1.0 + 0.5 * PetscSinReal((PetscReal)i);
  PetscCall(VecRestoreArray(x, &xa));
  PetscCall(VecNormalize(x, NULL));
  *norm = 0;
  for (PetscInt k = 0; k < its; k++) {
    PetscCall(MatMult(W, x, y));
    PetscCall(VecNorm(y, NORM_2, &nx));
    if (nx == 0) break;
    PetscCall(VecScale(y, 1.0 / nx));
    PetscCall(VecSwap(x, y));
  }
  *norm = nx;
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscFunctionReturn(0);
}

static PetscErrorCode EnsureWork(KergsRegularised *reg, KergsOperators ops, PetscInt nlocal)
{
  KergsDofLayout layout;
  PetscInt       ncomp;
  Vec            r;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, NULL, NULL));
  ncomp = layout.ncomp;
  PetscCall(VecDestroy(&reg->rtilde));
  PetscCall(VecDestroy(&reg->ztilde));
  PetscCall(VecDestroy(&reg->z));
  PetscCall(VecDuplicate(r, &reg->rtilde));
  PetscCall(VecDuplicate(r, &reg->ztilde));
  PetscCall(VecDuplicate(r, &reg->z));
  if (nlocal * ncomp * ncomp > reg->nalloc) {
    PetscCall(PetscFree2(reg->extra, reg->Wdiag));
    reg->nalloc = PetscMax(nlocal * ncomp * ncomp, 2 * reg->nalloc);
    PetscCall(PetscMalloc2(reg->nalloc, &reg->extra, reg->nalloc, &reg->Wdiag));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsRegularisedSetUp(KergsSolver s, KergsRegularised *reg, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  Mat            Z, W;
  PetscLogDouble t0, t1;
  PetscInt       n;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetW(ops, &W, NULL));
  PetscCall(EnsureWork(reg, ops, n));
  PetscCall(EstimateNormW(W, reg->power_its, &reg->normW));
  reg->omega = reg->omega_fixed > 0 ? reg->omega_fixed : reg->omega_factor * reg->normW;
  if (reg->omega <= 0) reg->omega = 1.0;                   /* no contact carries anything: any omega will do */
  PetscCall(KergsKernelSetActive(reg->kernel, s->active)); /* the unknowns: active contacts only */
  PetscCall(KergsKernelSetUp(reg->kernel, scene, contacts, ops));
  PetscCall(KergsKernelSetOmega(reg->kernel, reg->omega));
  PetscCall(PetscTime(&t0));
  PetscCall(KergsPredictorPredict(reg->predictor, scene, contacts, ops, s->active, reg->rtilde));
  PetscCall(PetscTime(&t1));
  reg->predict_seconds = t1 - t0;
  PetscCall(KergsKernelGetZ(reg->kernel, &Z));
  PetscCall(MatMult(Z, reg->rtilde, reg->ztilde));
  PetscCall(PetscInfo(NULL, "omega %g (||W||_2 ~ %g)\n", (double)reg->omega, (double)reg->normW));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsRegularisedStats(KergsRegularised *reg, KergsSolveStats *st)
{
  KergsKernelStats    k;
  KergsPredictorStats p;

  PetscFunctionBeginUser;
  PetscCall(KergsKernelGetStats(reg->kernel, &k));
  PetscCall(KergsPredictorGetStats(reg->predictor, &p));
  PetscCall(KergsSolveStatsAdd(st, "omega", reg->omega));
  PetscCall(KergsSolveStatsAdd(st, "norm_W", reg->normW));
  PetscCall(KergsSolveStatsAddText(st, "predictor_type", p.type));
  PetscCall(KergsSolveStatsAdd(st, "kernel_dimension", (PetscReal)(k.ncols - k.rank)));
  PetscCall(KergsSolveStatsAdd(st, "rank_Hf", (PetscReal)k.rank));
  PetscCall(KergsSolveStatsAdd(st, "floating_grains", (PetscReal)k.floating_grains));
  PetscCall(KergsSolveStatsAdd(st, "peeled_contacts", (PetscReal)k.peeled_contacts));
  PetscCall(KergsSolveStatsAdd(st, "null_pivots", (PetscReal)k.null_pivots));
  PetscCall(KergsSolveStatsAdd(st, "nnz_factor", (PetscReal)k.nnz_factor));
  PetscCall(KergsSolveStatsAdd(st, "factor_seconds", k.factor_seconds));
  PetscCall(KergsSolveStatsAdd(st, "diag_seconds", k.diag_seconds));
  PetscCall(KergsSolveStatsAdd(st, "predict_seconds", reg->predict_seconds));
  PetscCall(KergsSolveStatsAdd(st, "kernel_check_error", k.check_error));
  if (k.check_failed) {
    st->reason = KERGS_SOLVER_DIVERGED_KERNEL;
    PetscCall(PetscInfo(NULL, "the kernel projector (%s) misses ker H_f: |H_f P x| / |H_f x| = %g > -kernel_check_tol %g\n", k.package,
                        (double)k.check_error, (double)k.check_tol));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsRegularisedView(KergsRegularised *reg, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  if (reg->omega_fixed > 0)
    PetscCall(PetscViewerASCIIPrintf(viewer, "omega %g (fixed)\n", (double)reg->omega_fixed));
  else
    PetscCall(PetscViewerASCIIPrintf(viewer, "omega %g * ||W||_2 (estimated by %" PetscInt_FMT " power iterations each step)\n",
                                     (double)reg->omega_factor, reg->power_its));
  PetscCall(KergsPredictorView(reg->predictor, viewer));
  PetscCall(KergsKernelView(reg->kernel, viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsRegularisedDestroy(KergsRegularised **reg)
{
  PetscFunctionBeginUser;
  if (!*reg) PetscFunctionReturn(0);
  PetscCall(KergsKernelDestroy(&(*reg)->kernel));
  PetscCall(KergsPredictorDestroy(&(*reg)->predictor));
  PetscCall(VecDestroy(&(*reg)->rtilde));
  PetscCall(VecDestroy(&(*reg)->ztilde));
  PetscCall(VecDestroy(&(*reg)->z));
  PetscCall(PetscFree2((*reg)->extra, (*reg)->Wdiag));
  PetscCall(PetscFree(*reg));
  PetscFunctionReturn(0);
}
