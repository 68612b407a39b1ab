/* kergs solver type "nlgsjac": Algorithm 6 (NLGS-Jac). Gauss-Seidel on the sparse W, Jacobi on the dense part
   Z = omega N N^T, which is never stored: its diagonal blocks Z_aa are computed once per step, z~ = Z r~ once,
   and z = Z r^(k-1) once per sweep through the kernel projector. Contact a solves with W~_aa = W_aa + Z_aa and
     v_a = W~_aa r_a + v^d_a + sum_{b != a} W_ab r_b + (z_a - Z_aa r_a^(k-1) - z~_a),
   the last bracket being the extra right-hand side updated before each sweep. */
#include "regularised.h"

static PetscErrorCode SolverSetFromOptions_NLGSJac(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedSetFromOptions(PetscOptionsObject, s, (KergsRegularised *)s->data));
  PetscFunctionReturn(0);
}

/* W~_aa = W_aa + Z_aa for every local contact. */
static PetscErrorCode SolverSetUp_NLGSJac(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  KergsRegularised *reg = (KergsRegularised *)s->data;
  KergsDofLayout    layout;
  const PetscReal  *Zdiag;
  PetscInt          n;

  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedSetUp(s, reg, scene, contacts, ops));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsKernelComputeDiagonalBlocks(reg->kernel));
  PetscCall(KergsKernelGetDiagonalBlocks(reg->kernel, &Zdiag));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, reg->Wdiag));
  for (PetscInt i = 0; i < n * layout.ncomp * layout.ncomp; i++) reg->Wdiag[i] += Zdiag[i];
  PetscFunctionReturn(0);
}

/* extra = Z r^(k-1) - Z_aa r_a^(k-1) - z~, before each sweep. */
static PetscErrorCode SolverPreSweep_NLGSJac(KergsSolver s, KergsOperators ops, PetscReal *extra)
{
  KergsRegularised  *reg = (KergsRegularised *)s->data;
  KergsDofLayout     layout;
  PetscInt           nc, n;
  const PetscScalar *z, *zt, *r;
  const PetscReal   *Zd;
  Mat                Z;
  Vec                rv;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &rv, NULL, NULL));
  PetscCall(KergsKernelGetDiagonalBlocks(reg->kernel, &Zd));
  nc = layout.ncomp;
  PetscCall(KergsKernelGetZ(reg->kernel, &Z));
  PetscCall(MatMult(Z, rv, reg->z));
  PetscCall(VecGetLocalSize(rv, &n));
  PetscCall(VecGetArrayRead(reg->z, &z));
  PetscCall(VecGetArrayRead(reg->ztilde, &zt));
  PetscCall(VecGetArrayRead(rv, &r));
  for (PetscInt k = 0; k < n / nc; k++)
    for (PetscInt i = 0; i < nc; i++) {
      PetscReal zr = 0;
      for (PetscInt j = 0; j < nc; j++) zr += Zd[k * nc * nc + i * nc + j] * r[k * nc + j];
      extra[k * nc + i] = z[k * nc + i] - zr - zt[k * nc + i];
    }
  PetscCall(VecRestoreArrayRead(reg->z, &z));
  PetscCall(VecRestoreArrayRead(reg->ztilde, &zt));
  PetscCall(VecRestoreArrayRead(rv, &r));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSolve_NLGSJac(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                          KergsSolveStats *stats)
{
  KergsRegularised *reg = (KergsRegularised *)s->data;

  PetscFunctionBeginUser;
  (void)scene;
  (void)contacts;
  PetscCall(KergsSolverIterate(s, ops, reg->extra, reg->Wdiag, stats));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverStats_NLGSJac(KergsSolver s, KergsSolveStats *st)
{
  PetscFunctionBeginUser;
  PetscCall(KergsRegularisedStats((KergsRegularised *)s->data, st));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_NLGSJac(KergsSolver s, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "NLGS-Jac (Algorithm 6): Gauss-Seidel on W, Jacobi on omega N N^T applied through the kernel projector\n"));
  PetscCall(KergsRegularisedView((KergsRegularised *)s->data, viewer));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverDestroy_NLGSJac(KergsSolver s)
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
  s->needs_full_W       = PETSC_TRUE; /* W~ = W + omega N N^T over every potential contact (Algorithm 1) */
  s->data               = reg;
  s->ops.setfromoptions = SolverSetFromOptions_NLGSJac;
  s->ops.setup          = SolverSetUp_NLGSJac;
  s->ops.solve          = SolverSolve_NLGSJac;
  s->ops.presweep       = SolverPreSweep_NLGSJac;
  s->ops.stats          = SolverStats_NLGSJac;
  s->ops.view           = SolverView_NLGSJac;
  s->ops.destroy        = SolverDestroy_NLGSJac;
  PetscFunctionReturn(0);
}
