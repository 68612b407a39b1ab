/* kergs solver type "nlgsjac": Algorithm 6 (NLGS-Jac). Gauss-Seidel on the sparse W, Jacobi on the dense part
   Z = omega N N^T, which is never stored: its diagonal blocks Z_aa are computed once per step, z~ = Z r~ once,
   and z = Z r^(k-1) once per sweep through the kernel projector. Contact a solves with W~_aa = W_aa + Z_aa and
     v_a = W~_aa r_a + v^d_a + sum_{b != a} W_ab r_b + (z_a - Z_aa r_a^(k-1) - z~_a),
   the last bracket being the extra right-hand side updated before each sweep. */
#include "regularised.h"

static PetscErrorCode KergsSolverSetFromOptions_NLGSJac(KergsSolver s, PetscOptionItems *unused)
{
  PetscFunctionBeginUser;
  (void)unused;
  PetscCall(KergsRegularisedSetFromOptions(s, (KergsRegularised *)s->data));
  PetscFunctionReturn(0);
}

/* W~_aa = W_aa + Z_aa for every local contact. */
static PetscErrorCode KergsSolverSetUp_NLGSJac(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  KergsRegularised *reg = (KergsRegularised *)s->data;
  PetscInt          nb  = ops->ncomp * ops->ncomp;

  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedSetUp(s, reg, scene, contacts, ops));
  PetscCall(KergsKernelComputeDiagonalBlocks(reg->kernel));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, reg->Wdiag));
  for (PetscInt i = 0; i < contacts->n * nb; i++) reg->Wdiag[i] += reg->kernel->Zdiag[i];
  PetscFunctionReturn(0);
}

/* extra = Z r^(k-1) - Z_aa r_a^(k-1) - z~, before each sweep. */
static PetscErrorCode KergsSolverPreSweep_NLGSJac(KergsSolver s, KergsOperators ops, PetscReal *extra)
{
  KergsRegularised  *reg = (KergsRegularised *)s->data;
  PetscInt           nc = ops->ncomp, n;
  const PetscScalar *z, *zt, *r;
  const PetscReal   *Zd = reg->kernel->Zdiag;
  Mat                Z;

  PetscFunctionBeginUser;
  PetscCall(KergsKernelGetZ(reg->kernel, &Z));
  PetscCall(MatMult(Z, ops->r, reg->z));
  PetscCall(VecGetLocalSize(ops->r, &n));
  PetscCall(VecGetArrayRead(reg->z, &z));
  PetscCall(VecGetArrayRead(reg->ztilde, &zt));
  PetscCall(VecGetArrayRead(ops->r, &r));
  for (PetscInt k = 0; k < n / nc; k++)
    for (PetscInt i = 0; i < nc; i++) {
      PetscReal zr = 0;
      for (PetscInt j = 0; j < nc; j++) zr += Zd[k * nc * nc + i * nc + j] * r[k * nc + j];
      extra[k * nc + i] = z[k * nc + i] - zr - zt[k * nc + i];
    }
  PetscCall(VecRestoreArrayRead(reg->z, &z));
  PetscCall(VecRestoreArrayRead(reg->ztilde, &zt));
  PetscCall(VecRestoreArrayRead(ops->r, &r));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsSolverSolve_NLGSJac(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops, KergsSolveStats *stats)
{
  KergsRegularised *reg = (KergsRegularised *)s->data;

  PetscFunctionBeginUser;
  (void)scene;
  (void)contacts;
  PetscCall(KergsSolverIterate(s, ops, reg->extra, reg->Wdiag, stats));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsSolverRecord_NLGSJac(KergsSolver s, KergsResults res)
{
  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedRecord((KergsRegularised *)s->data, res));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsSolverView_NLGSJac(KergsSolver s, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, "NLGS-Jac (Algorithm 6): Gauss-Seidel on W, Jacobi on omega N N^T applied through the kernel projector\n"));
  PetscCall(KergsRegularisedView((KergsRegularised *)s->data, viewer));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsSolverDestroy_NLGSJac(KergsSolver s)
{
  KergsRegularised *reg = (KergsRegularised *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedDestroy(&reg));
  s->data = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_NLGSJac(KergsSolver s)
{
  KergsRegularised *reg;

  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedCreate(s->comm, &reg));
  s->needs_H            = PETSC_TRUE; /* the kernel projector factors H_f H_f^T */
  s->data               = reg;
  s->ops.setfromoptions = KergsSolverSetFromOptions_NLGSJac;
  s->ops.setup          = KergsSolverSetUp_NLGSJac;
  s->ops.solve          = KergsSolverSolve_NLGSJac;
  s->ops.presweep       = KergsSolverPreSweep_NLGSJac;
  s->ops.record         = KergsSolverRecord_NLGSJac;
  s->ops.view           = KergsSolverView_NLGSJac;
  s->ops.destroy        = KergsSolverDestroy_NLGSJac;
  PetscFunctionReturn(0);
}
