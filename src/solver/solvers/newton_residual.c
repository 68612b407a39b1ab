/* newton's measure of convergence: the natural residual of the original problem over its contacts, shared by newton.c
   and its two starts (newton_ip.c, newton_desaxce.c). */
#include "newton.h"

/* The natural residual of the original problem (KergsLawNaturalResidualScaled, docs/solver.md) from r and u = W r + v^d. */
PetscErrorCode NewtonNaturalResidual(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, PetscReal *res)
{
  const PetscScalar *rl, *ul;
  PetscReal          sums[3] = {0.0, 0.0, 0.0};

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < n; a++) {
    PetscReal ra[KERGS_MAXCOMP], e[KERGS_MAXCOMP];
    NewtonContactNaturalMap(s, nt, nc, a, rl, ul, ra, e);
    for (PetscInt c = 0; c < nc; c++) {
      sums[0] += e[c] * e[c];
      sums[1] += ra[c] * ra[c];
      sums[2] += PetscSqr(ra[c] - e[c]);
    }
  }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPIU_SUM, s->comm));
  *res      = KergsLawNaturalResidualScaled(sums[0], sums[1], sums[2]);
  nt->enorm = PetscSqrtReal(sums[0]);
  PetscFunctionReturn(0);
}
