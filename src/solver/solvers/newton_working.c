/* The working set of solver type "newton" (-solver_newton_working_set; docs/solver.md, "Which contacts are active").

   Under the predictive gap rule every contact within the alert distance enters the step's problem, and one that
   stays open (r = 0, u_n >= 0) still brings its couplings into every factorization of J: on the 500-disk pressure
   scene of docs/tradeoff.md, half of newton's solve. On the law's open piece a contact's row of J is the identity
   (A = I, B = 0: F = r; plus the shift -solver_newton_shift, 1e-8, left out with the row), so its Newton direction
   is d = -F whatever the others do, and the other rows need its column only through that d, which is 0 once r = 0
   (the first Newton step makes it so for the residues below). Such a contact can be left out of J, and the Newton
   directions stay exact: F, the merit and the natural residual still run over every contact.

   A contact is left out at the start of a solve when it is open at the start of the step (a predicted gap > 0,
   hence an offset in v^d) and the warm start leaves it unloaded and opening: its impulse at most 1e-12 of the
   largest, and its velocity there, u_n = (W r + v^d)_n, positive. It keeps the exact law, in the smoothing phase
   too (newton.c, EvaluateFunction), so its blocks are exactly I and 0 while it stays on the open piece, and at
   least 1 away from them (A_nn = 0 or B_nn / rho = 1) once it leaves it. Before each Jacobian is assembled, a
   contact left out whose blocks have left the open piece is put back, and J is set up again on its new rows
   (GrowWorkingSet, newton.c). */
#include "newton.h"

/* Off the open piece: A_a - I or B_a / rho_a has an entry above this (any value in (0, 1) tells the two apart). */
#define OFF_OPEN_PIECE 0.5

PetscErrorCode NewtonWorkingSetBegin(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u)
{
  const PetscScalar *rl, *ul;
  PetscInt           deferred = 0;
  PetscReal          rmax, floor;

  PetscFunctionBeginUser;
  PetscCall(VecNorm(r, NORM_INFINITY, &rmax));
  floor = 1e-12 * rmax;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < n; a++) {
    PetscBool unloaded = PETSC_TRUE;
    for (PetscInt c = 0; c < nc; c++)
      if (PetscAbsScalar(rl[a * nc + c]) > floor) unloaded = PETSC_FALSE;
    nt->in_J[a] = (PetscBool) !(s->active[a] && s->gapvel[a] > 0 && unloaded && PetscRealPart(ul[a * nc]) > 0);
    if (!nt->in_J[a]) deferred++;
  }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(&deferred, &nt->left_out, 1, MPIU_INT, MPI_SUM, s->comm));
  nt->rebuilds = 0;
  PetscCall(PetscInfo(NULL, "working set: %" PetscInt_FMT " contacts left out of J\n", nt->left_out));
  PetscFunctionReturn(0);
}

/* Puts back into J the contacts left out whose current blocks (nt->A, nt->B) are off the open piece; *grown on every
   rank when some rank put one back. */
PetscErrorCode NewtonWorkingSetGrow(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscBool *grown)
{
  PetscInt count = 0, total;

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < n; a++) {
    const PetscReal *A = nt->A + a * nc * nc, *B = nt->B + a * nc * nc;
    PetscReal        off = 0.0;
    if (nt->in_J[a]) continue;
    for (PetscInt k = 0; k < nc * nc; k++) {
      const PetscReal identity = k % (nc + 1) == 0 ? 1.0 : 0.0;
      off                      = PetscMax(off, PetscMax(PetscAbsReal(A[k] - identity), PetscAbsReal(B[k]) / nt->rho[a]));
    }
    if (off > OFF_OPEN_PIECE) {
      nt->in_J[a] = PETSC_TRUE;
      count++;
    }
  }
  PetscCall(MPIU_Allreduce(&count, &total, 1, MPIU_INT, MPI_SUM, s->comm));
  *grown = (PetscBool)(total > 0);
  if (*grown) {
    nt->left_out -= total;
    nt->rebuilds++;
    PetscCall(PetscInfo(NULL, "working set: %" PetscInt_FMT " contacts off the open piece put back into J\n", total));
  }
  PetscFunctionReturn(0);
}
