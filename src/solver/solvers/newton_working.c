/* The working set of solver type "newton" (-solver_newton_working_set; docs/solver.md, "Which contacts are active").

   Under the predictive gap rule every contact within the alert distance enters the step's problem, and one that
   stays open (r = 0, u_n >= 0) still brings its couplings into every factorization of J: on the 500-disk pressure
   scene of docs/tradeoff.md, half of newton's solve. Here a contact is deferred when the warm start leaves it
   unloaded and opening: its impulse at most 1e-12 of the largest, and its velocity there, u_n = (W r + v^d)_n with the
   gap rule's offset in v^d, positive. (Newton leaves open contacts at such residues rather than at 0 after a damped
   step; deferring only exact zeros left 0.64 of the solve time instead of 0.57 on that scene, and floors of 1e-9 or
   1e-6 put back more contacts later, for no gain.) A deferred contact is off in s->active while the working set is
   solved (F = r, its row left out of J, newton_linear.c). Its natural map at r = 0 vanishes exactly when u_n >= 0
   (KergsLawNaturalMap), so once the working set is solved, the deferred contacts that the answer closes (u_n < 0)
   are the only violations of the original problem: they are put back, and the solve goes on from that answer until
   none is left. Putting back also the nearly closed ones (u_n below 0.3 of the gap's offset) took 7 % more time. */
#include "newton.h"

/* The normal velocity of local contact a (the first of its components). */
static PetscReal NormalVelocity(const PetscScalar *ul, PetscInt nc, PetscInt a) { return PetscRealPart(ul[a * nc]); }

PetscErrorCode NewtonWorkingSetBegin(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u)
{
  const PetscScalar *rl, *ul;
  PetscInt           deferred = 0;
  PetscReal          rmax, floor;

  PetscFunctionBeginUser;
  PetscCall(PetscArraycpy(nt->active_all, s->active, n));
  PetscCall(VecNorm(r, NORM_INFINITY, &rmax));
  floor = 1e-12 * rmax;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < n; a++) {
    PetscBool unloaded = PETSC_TRUE;
    for (PetscInt c = 0; c < nc; c++)
      if (PetscAbsScalar(rl[a * nc + c]) > floor) unloaded = PETSC_FALSE;
    if (s->active[a] && unloaded && NormalVelocity(ul, nc, a) > 0) {
      s->active[a] = PETSC_FALSE;
      deferred++;
    }
  }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(&deferred, &nt->deferred, 1, MPIU_INT, MPI_SUM, s->comm));
  nt->rounds = 1;
  PetscCall(PetscInfo(NULL, "working set: %" PetscInt_FMT " contacts deferred\n", nt->deferred));
  PetscFunctionReturn(0);
}

/* Puts back the deferred contacts that the current answer closes (u_n < 0); *added counts them over every rank. */
PetscErrorCode NewtonWorkingSetGrow(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec u, PetscInt *added)
{
  const PetscScalar *ul;
  PetscInt           count = 0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < n; a++)
    if (nt->active_all[a] && !s->active[a] && NormalVelocity(ul, nc, a) < 0) {
      s->active[a] = PETSC_TRUE;
      count++;
    }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(MPIU_Allreduce(&count, added, 1, MPIU_INT, MPI_SUM, s->comm));
  if (*added) {
    nt->deferred -= *added;
    nt->rounds++;
    PetscCall(PetscInfo(NULL, "working set: %" PetscInt_FMT " deferred contacts closed by the answer are put back\n", *added));
  }
  PetscFunctionReturn(0);
}

/* The step's activity back: every contact of the original problem. */
PetscErrorCode NewtonWorkingSetEnd(KergsSolver s, Newton *nt, PetscInt n)
{
  PetscFunctionBeginUser;
  PetscCall(PetscArraycpy(s->active, nt->active_all, n));
  PetscFunctionReturn(0);
}
